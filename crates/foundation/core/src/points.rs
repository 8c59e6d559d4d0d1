//! Points in a plane that lie on no known grid (a scan mesh's nodes, an import's positions): each point's nearest
//! neighbour and the median spacing, one definition for the import that fits a lattice to them, the analyses that
//! interpolate them onto one, and the scattered-point datasets.
//!
//! Pairwise: `O(n²)` in the number of points; callers bound it (an import fits a lattice to at most
//! `metaplate_interchange::lattice::MAX_LATTICE_POINTS`).

/// A point's nearest neighbour.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// Distance to it, m: infinite for a lone point, 0 where two points coincide.
    pub distance_m: f64,
    /// Direction to it from the point, radians (`atan2(dy, dx)`); 0 for a lone point.
    pub direction_rad: f64,
}

/// Each point's nearest neighbour among `points_m` (m), in the points' order. Non-finite coordinates give
/// non-finite distances (no point is nearest to one).
pub fn nearest_neighbours(points_m: &[(f64, f64)]) -> Vec<Nearest> {
    points_m
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let mut best = Nearest { distance_m: f64::INFINITY, direction_rad: 0.0 };
            for (j, b) in points_m.iter().enumerate() {
                let d = (b.0 - a.0).hypot(b.1 - a.1);
                if j != i && d < best.distance_m {
                    best = Nearest { distance_m: d, direction_rad: (b.1 - a.1).atan2(b.0 - a.0) };
                }
            }
            best
        })
        .collect()
}

/// The median of the nearest-neighbour distances that are finite and positive, m (of `k` of them, the `k / 2`-th
/// smallest: the upper median of an even count); `None` when there is none (fewer than two distinct points).
pub fn median_distance_m(nearest: &[Nearest]) -> Option<f64> {
    let mut distances: Vec<f64> = nearest.iter().map(|n| n.distance_m).filter(|d| d.is_finite() && *d > 0.0).collect();
    distances.sort_unstable_by(f64::total_cmp);
    distances.get(distances.len() / 2).copied()
}

/// The median distance from each point to its nearest neighbour, m ([`median_distance_m`] of
/// [`nearest_neighbours`]); `None` for fewer than two distinct points.
pub fn median_spacing_m(points_m: &[(f64, f64)]) -> Option<f64> {
    median_distance_m(&nearest_neighbours(points_m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_lattice_has_its_step_and_axis_directions() {
        let points: Vec<(f64, f64)> = (0..12).map(|i| (f64::from(i % 4) * 0.005, f64::from(i / 4) * 0.005)).collect();
        let nearest = nearest_neighbours(&points);
        assert!(nearest.iter().all(|n| (n.distance_m - 0.005).abs() < 1e-15), "{nearest:?}");
        // Every direction is along an axis: a multiple of 90 degrees.
        for n in &nearest {
            let quarter = n.direction_rad / std::f64::consts::FRAC_PI_2;
            assert!((quarter - quarter.round()).abs() < 1e-12, "{n:?}");
        }
        assert_eq!(median_spacing_m(&points), Some(0.005));
    }

    #[test]
    fn the_median_is_the_upper_one_and_skips_coincident_and_lone_points() {
        // Nearest distances 1, 1, 2, 3 (the last two points' nearest is the second at 2 and 3 m).
        let points = [(0.0, 0.0), (1.0, 0.0), (3.0, 0.0), (-3.0, 0.0)];
        let nearest = nearest_neighbours(&points);
        let distances: Vec<f64> = nearest.iter().map(|n| n.distance_m).collect();
        assert_eq!(distances, [1.0, 1.0, 2.0, 3.0]);
        assert_eq!(median_distance_m(&nearest), Some(2.0), "the upper median of an even count");
        assert_eq!(nearest[3].direction_rad, 0.0, "towards +x");
        // Two coincident points: their zero distances are not spacings.
        assert_eq!(median_spacing_m(&[(0.0, 0.0), (0.0, 0.0), (2.0, 0.0)]), Some(2.0));
        // Extremes: none, one, all coincident, a non-finite coordinate.
        assert_eq!(median_spacing_m(&[]), None);
        let lone = nearest_neighbours(&[(1.0, 1.0)]);
        assert_eq!(lone, [Nearest { distance_m: f64::INFINITY, direction_rad: 0.0 }]);
        assert_eq!(median_distance_m(&lone), None);
        assert_eq!(median_spacing_m(&[(0.5, 0.5); 3]), None);
        assert_eq!(median_spacing_m(&[(f64::NAN, 0.0), (0.0, 0.0), (0.0, 1.0)]), Some(1.0));
    }
}

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

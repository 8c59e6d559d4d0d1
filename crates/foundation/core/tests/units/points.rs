use metaplate_core::points::*;

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

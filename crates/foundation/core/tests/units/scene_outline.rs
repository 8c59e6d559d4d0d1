use metaplate_core::scene::*;

// Distances here are sums and hypotenuses of a few decimal lengths: 1e-12 m is ~1000 ulps at 0.1 m, ample for
// rounding and far below any physical length.
const TOL_M: f64 = 1e-12;

#[test]
fn stadium_distances() {
    let s = Outline::Stadium { straight_length_m: 0.10, radius_m: 0.075 };
    assert!((s.distance_inside_m(0.0, 0.0) - 0.075).abs() < TOL_M);
    assert!(s.distance_inside_m(0.125, 0.0).abs() < TOL_M); // tip of the right cap
    assert!(s.distance_inside_m(0.0, 0.075).abs() < TOL_M); // middle of the top edge
    assert!((s.distance_inside_m(0.05, -0.08) + 0.005).abs() < TOL_M);
    // The bounding-box corner is outside by sqrt(2) r - r.
    let corner = 0.075 * (2f64.sqrt() - 1.0);
    assert!((s.distance_inside_m(0.125, 0.075) + corner).abs() < TOL_M);
    assert!(!s.contains(0.125, 0.075) && s.contains(0.125, 0.0));
    assert_eq!(s.bounding_box_m(), (-0.125, 0.125, -0.075, 0.075));
}

#[test]
fn rectangle_distances() {
    let r = Outline::Rectangle { width_m: 0.2, height_m: 0.1 };
    assert!((r.distance_inside_m(0.0, 0.0) - 0.05).abs() < TOL_M);
    assert!((r.distance_inside_m(0.09, 0.0) - 0.01).abs() < TOL_M);
    assert!((r.distance_inside_m(0.13, 0.09) + 0.05).abs() < TOL_M); // 3-4-5 outside the corner
    assert!(r.contains_square(0.0, 0.0, 0.1) && !r.contains_square(0.0, 0.0, 0.1001));
    assert!((r.area_m2() - 0.02).abs() < TOL_M);
}

//! The galvo fit: exact recovery, 4 points, noise, the extremes of scale and offset, and refused sets.

use metaplate_aim::GalvoError;
use metaplate_aim::galvo::{FitModel, GalvoFit, TaughtPoint};
use metaplate_core::rng::SplitMix64;

/// A homography of the size a real rig has: ~50 V per m (20 mm per V), a few degrees of rotation, an offset and
/// a keystone of a few percent over the plate.
const H: [f64; 9] = [48.0, -3.0, 0.2, 2.5, 51.0, -0.15, 0.12, -0.08, 1.0];

fn apply(h: &[f64; 9], (x, y): (f64, f64)) -> (f64, f64) {
    let w = h[6] * x + h[7] * y + h[8];
    ((h[0] * x + h[1] * y + h[2]) / w, (h[3] * x + h[4] * y + h[5]) / w)
}

fn taught(h: &[f64; 9], marks: &[(f64, f64)]) -> Vec<TaughtPoint> {
    marks
        .iter()
        .map(|&(x_m, y_m)| {
            let (x_v, y_v) = apply(h, (x_m, y_m));
            TaughtPoint { x_m, y_m, x_v, y_v }
        })
        .collect()
}

/// An `nx` x `ny` grid of marks over `[-hx, hx] x [-hy, hy]` around `centre`, m.
fn grid(nx: usize, ny: usize, hx: f64, hy: f64, centre: (f64, f64)) -> Vec<(f64, f64)> {
    let at = |i: usize, n: usize, h: f64| if n == 1 { 0.0 } else { -h + 2.0 * h * i as f64 / (n - 1) as f64 };
    (0..ny).flat_map(|j| (0..nx).map(move |i| (centre.0 + at(i, nx, hx), centre.1 + at(j, ny, hy)))).collect()
}

/// The largest difference between the fit's voltages and `truth`'s over a 13 x 9 grid of the region, V.
fn worst_volts_error(fit: &GalvoFit, truth: impl Fn((f64, f64)) -> (f64, f64), region: &[(f64, f64)]) -> f64 {
    region
        .iter()
        .map(|&p| {
            let v = fit.volts_at(p.0, p.1).expect("inside the taught region the map is finite");
            let t = truth(p);
            (v.0 - t.0).abs().max((v.1 - t.1).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn projective_fit_recovers_a_known_homography_from_a_grid_and_from_exactly_four_points() {
    let region = grid(13, 9, 0.12, 0.06, (0.0, 0.0));
    for marks in [grid(3, 3, 0.1, 0.05, (0.0, 0.0)), vec![(-0.1, -0.05), (0.1, -0.05), (0.1, 0.05), (-0.1, 0.05)]] {
        let fit = GalvoFit::fit(FitModel::Projective, &taught(&H, &marks)).expect("a well-spread set fits");
        // Exact data: only rounding is left (volts of O(10) V, SVD in f64: ~1e-14 relative).
        let worst_v = worst_volts_error(&fit, |p| apply(&H, p), &region);
        assert!(worst_v < 1e-9, "{} marks: worst {worst_v:e} V off the true map", marks.len());
        let r = fit.residual();
        assert!(r.max_mm < 1e-9 && r.rms_mm <= r.max_mm, "{r:?}");
    }
}

#[test]
fn the_fit_holds_at_the_extremes_of_offset_spread_and_range() {
    // Marks 2 mm apart, 5 m from the plate's origin: normalisation keeps the DLT well conditioned.
    let far = grid(3, 3, 0.001, 0.001, (5.0, -5.0));
    let h_far = [48.0, -3.0, -230.0, 2.5, 51.0, 240.0, 0.0, 0.0, 1.0];
    let fit = GalvoFit::fit(FitModel::Projective, &taught(&h_far, &far)).expect("fits");
    let worst_v = worst_volts_error(&fit, |p| apply(&h_far, p), &grid(5, 5, 0.001, 0.001, (5.0, -5.0)));
    assert!(worst_v < 1e-9, "far marks: worst {worst_v:e} V");
    // The whole +/- 10 V range of the outputs (marks 0.2 m from the centre).
    let wide = grid(3, 3, 0.2, 0.19, (0.0, 0.0));
    let fit = GalvoFit::fit(FitModel::Projective, &taught(&H, &wide)).expect("fits");
    assert!(taught(&H, &wide).iter().any(|p| p.x_v.abs() > 9.0), "the marks span the outputs' range");
    let worst_v = worst_volts_error(&fit, |p| apply(&H, p), &grid(9, 9, 0.2, 0.19, (0.0, 0.0)));
    assert!(worst_v < 1e-9, "full range: worst {worst_v:e} V");
}

#[test]
fn polynomial_fit_recovers_a_quadratic_map_and_the_projective_fit_reports_what_it_cannot_take() {
    let quad = |(x, y): (f64, f64)| {
        (0.3 + 50.0 * x - 2.0 * y + 40.0 * x * x - 15.0 * x * y, -0.2 + 3.0 * x + 49.0 * y + 30.0 * y * y)
    };
    let marks = grid(3, 3, 0.1, 0.05, (0.0, 0.0));
    let points: Vec<TaughtPoint> = marks
        .iter()
        .map(|&(x_m, y_m)| {
            let (x_v, y_v) = quad((x_m, y_m));
            TaughtPoint { x_m, y_m, x_v, y_v }
        })
        .collect();
    let fit = GalvoFit::fit(FitModel::Polynomial2, &points).expect("fits");
    let worst_v = worst_volts_error(&fit, quad, &grid(13, 9, 0.12, 0.06, (0.0, 0.0)));
    assert!(worst_v < 1e-9, "worst {worst_v:e} V");
    // The same points under a projective model: the quadratic terms (0.4 V, ~8 mm at the edge) stay as residual.
    let projective = GalvoFit::fit(FitModel::Projective, &points).expect("fits");
    assert!(projective.residual().max_mm > 0.5, "{:?}", projective.residual());
}

#[test]
fn noisy_points_give_a_residual_of_the_noise_and_a_map_better_than_it() {
    let sigma_v = 0.5e-3;
    let mut rng = SplitMix64::new(31, 1);
    let marks = grid(5, 5, 0.1, 0.05, (0.0, 0.0));
    let points: Vec<TaughtPoint> = taught(&H, &marks)
        .into_iter()
        .map(|p| TaughtPoint { x_v: p.x_v + sigma_v * rng.normal(), y_v: p.y_v + sigma_v * rng.normal(), ..p })
        .collect();
    let fit = GalvoFit::fit(FitModel::Projective, &points).expect("fits");
    // Noise on the plate: sigma_v over ~50 V/m = ~0.01 mm per axis. The 2-D residual of n = 25 points after 8
    // parameters has rms sigma * sqrt(2 (1 - 8 / 50)) = 1.30 sigma; its estimate from 42 degrees of freedom
    // spreads by ~11 %, so [0.9, 1.7] sigma is over 3 standard deviations either side.
    let sigma_mm = sigma_v / 50.0 * 1e3;
    let r = fit.residual();
    assert!(r.rms_mm > 0.9 * sigma_mm && r.rms_mm < 1.7 * sigma_mm, "rms {} mm vs sigma {sigma_mm} mm", r.rms_mm);
    // The fitted map averages the noise: within the noise of one point everywhere inside the marks.
    let worst_v = worst_volts_error(&fit, |p| apply(&H, p), &grid(9, 9, 0.1, 0.05, (0.0, 0.0)));
    assert!(worst_v < 2.0 * sigma_v, "worst {worst_v:e} V");
}

#[test]
fn degenerate_sets_are_refused_by_name() {
    let four_with_three_on_a_line = [(-0.1, -0.05), (0.0, -0.05), (0.1, -0.05), (0.0, 0.05)];
    let err = GalvoFit::fit(FitModel::Projective, &taught(&H, &four_with_three_on_a_line)).unwrap_err();
    assert!(matches!(&err, GalvoError::Collinear { side: "plate", points } if points == &[0, 1, 2]), "{err}");

    let all_on_a_line: Vec<(f64, f64)> = (0..6).map(|i| (0.02 * i as f64, 0.01 * i as f64)).collect();
    for model in [FitModel::Projective, FitModel::Polynomial2] {
        let err = GalvoFit::fit(model, &taught(&H, &all_on_a_line)).unwrap_err();
        assert!(matches!(err, GalvoError::Collinear { .. }), "{model:?}: {err}");
    }

    let mut duplicated = taught(&H, &grid(3, 3, 0.1, 0.05, (0.0, 0.0)));
    duplicated.push(duplicated[4]);
    let err = GalvoFit::fit(FitModel::Projective, &duplicated).unwrap_err();
    assert!(matches!(err, GalvoError::Duplicate { side: "plate", first: 4, second: 9 }), "{err}");

    // One voltage pair taught for two marks: the beam cannot be in two places.
    let mut same_volts = taught(&H, &grid(3, 3, 0.1, 0.05, (0.0, 0.0)));
    same_volts[8] = TaughtPoint { x_v: same_volts[0].x_v, y_v: same_volts[0].y_v, ..same_volts[8] };
    let err = GalvoFit::fit(FitModel::Projective, &same_volts).unwrap_err();
    assert!(matches!(err, GalvoError::Duplicate { side: "volts", .. }), "{err}");

    // Six marks on one circle (a conic): the quadratic terms are undetermined.
    let circle: Vec<(f64, f64)> =
        (0..6).map(|k| (std::f64::consts::TAU * k as f64 / 6.0).sin_cos()).map(|(s, c)| (0.05 * c, 0.05 * s)).collect();
    let err = GalvoFit::fit(FitModel::Polynomial2, &taught(&H, &circle)).unwrap_err();
    assert!(matches!(err, GalvoError::Degenerate { .. }), "{err}");

    let err = GalvoFit::fit(FitModel::Projective, &taught(&H, &four_with_three_on_a_line[..3])).unwrap_err();
    assert!(matches!(err, GalvoError::TooFewPoints { needed: 4, got: 3, .. }), "{err}");
    let err = GalvoFit::fit(FitModel::Polynomial2, &taught(&H, &grid(5, 1, 0.1, 0.0, (0.0, 0.0))[..5])).unwrap_err();
    assert!(matches!(err, GalvoError::TooFewPoints { needed: 6, got: 5, .. }), "{err}");

    let mut not_finite = taught(&H, &grid(2, 2, 0.1, 0.05, (0.0, 0.0)));
    not_finite[2].y_v = f64::NAN;
    let err = GalvoFit::fit(FitModel::Projective, &not_finite).unwrap_err();
    assert!(matches!(err, GalvoError::InvalidPoint { index: 2, .. }), "{err}");
}

#[test]
fn beyond_the_horizon_the_map_has_no_image_and_newton_inverts_it_inside() {
    let fit = GalvoFit::fit(FitModel::Projective, &taught(&H, &grid(3, 3, 0.1, 0.05, (0.0, 0.0)))).expect("fits");
    // w = 0.12 x - 0.08 y + 1 vanishes at x = -1/0.12 = -8.3 m (y = 0).
    assert_eq!(fit.volts_at(-9.0, 0.0), None);
    assert_eq!(fit.volts_at(f64::NAN, 0.0), None);
    let (x_v, y_v) = apply(&H, (0.07, -0.03));
    let (x, y) = fit.plate_at(x_v, y_v, (0.0, 0.0)).expect("converges");
    assert!((x - 0.07).abs() < 1e-12 && (y + 0.03).abs() < 1e-12, "({x}, {y})");
    assert_eq!(fit.taught_bounds_m(), ((-0.1, -0.05), (0.1, 0.05)));
}

//! Plate-equation (biharmonic Rayleigh quotient) wavelength estimator on synthetic fields on the lab grid (49 x 25 at
//! 5 mm, stadium mask), and at its extremes.
//!
//! Tolerances come from the stencil's dispersion, derived in `metaplate_analysis::wavelength::local`: after the
//! isotropic correction a propagating wave at angle t reads k off by `(kh)^2 (c(t) - 3/4) / 24`,
//! `c = cos^4 t + sin^4 t` in [1/2, 1], so by at most `(kh)^2 / 96` (0.41 % at 5 cm, 0.016 % at 25 cm); the next
//! order adds 4 % of that at 5 cm (measured), so bounds below carry a factor 1.1.
#![allow(clippy::unwrap_used)] // tests may unwrap

use crate::common;

use std::f64::consts::PI;

use common::*;
use metaplate_analysis::AnalysisError;
use metaplate_analysis::wavelength::{
    Exclusion, KSpaceOptions, LocalEstimate, LocalFlags, LocalOptions, StencilCorrection, estimate_local_wavelength,
    estimate_wavelength,
};
use num_complex::Complex64;

const WAVELENGTHS_M: [f64; 4] = [0.05, 0.10, 0.15, 0.25];

fn estimate(field: &[Complex64]) -> Result<LocalEstimate, AnalysisError> {
    estimate_local_wavelength(field, &stadium_mask(), &grid(), &[], &LocalOptions::default())
}

fn error(e: &LocalEstimate, lambda_m: f64) -> f64 {
    e.wavelength_m / lambda_m - 1.0
}

/// `(kh)^2` of a wavelength on the lab grid.
fn kh_sq(lambda_m: f64) -> f64 {
    (2.0 * PI * SPACING_M / lambda_m).powi(2)
}

/// The largest direction-dependent error after the isotropic correction, with the factor 1.1 for the next order.
fn direction_bound(lambda_m: f64) -> f64 {
    1.1 * kh_sq(lambda_m) / 96.0
}

#[test]
fn plane_waves_match_the_predicted_direction_dependence() {
    for lambda_m in WAVELENGTHS_M {
        for angle_deg in [0.0f64, 30.0, 45.0, 90.0, 135.0] {
            let t = angle_deg.to_radians();
            let e = estimate(&plane_wave(lambda_m, t)).unwrap();
            // Leading order: the wavelength reads (kh)^2 (c - 3/4) / 24 long (long on the axes, short on diagonals).
            let c = t.cos().powi(4) + t.sin().powi(4);
            let predicted = kh_sq(lambda_m) * (c - 0.75) / 24.0;
            // Next order, at most 4 % of the bound at 5 cm (measured 0.427 % against 0.411 % on the axis).
            assert!(
                (error(&e, lambda_m) - predicted).abs() < 0.1 * direction_bound(lambda_m),
                "{lambda_m} {angle_deg}: {e:?}"
            );
            assert!(error(&e, lambda_m).abs() < direction_bound(lambda_m));
            // One plane wave is one eigenfunction of the stencil: the residual is rounding, amplified by the
            // stencil's 1 / (kh)^4 (2.5e-4 at 25 cm): 1e-9 bounds it.
            assert!(e.residual < 1e-9, "{e:?}");
            assert_eq!(e.flags, LocalFlags::default());
            assert_eq!(e.points_used, 861);
        }
    }
}

#[test]
fn resolves_where_the_k_space_estimator_cannot() {
    // 25 cm on a 24.5 x 12.5 cm grid: the k-space estimate is flagged under-resolved and biased short; the plate
    // equation needs no aperture: well under 0.1 % (the direction bound is 0.018 %).
    for field in [plane_wave(0.25, 0.3), standing_mixture(0.25, 24, 7), hankel_wave(0.25, 0.16, 0.09)] {
        let k = estimate_wavelength(&field, &stadium_mask(), NX, NY, SPACING_M, &KSpaceOptions::default()).unwrap();
        assert!(k.flags.under_resolved && k.median_m < 0.25, "{k:?}");
        let e = estimate(&field).unwrap();
        assert!(error(&e, 0.25).abs() < 0.001, "{e:?}");
    }
    // 1 m, four times the grid: still measured from the field's curvature (direction bound 0.001 %; the Hankel
    // function's own error of ~1e-11, amplified by 1 / (kh)^4 ~ 1e6, is not in this one).
    let e = estimate(&plane_wave(1.0, 0.5)).unwrap();
    assert!(error(&e, 1.0).abs() < 2e-5, "{e:?}");
}

#[test]
fn standing_mixtures_stay_inside_the_direction_bound() {
    // 24 standing waves of random directions: a mixture of directions reads the energy-weighted mean of their
    // errors (cross terms between directions nearly cancel over many points), inside the single-wave bound.
    for lambda_m in WAVELENGTHS_M {
        for seed in 0..8 {
            let e = estimate(&standing_mixture(lambda_m, 24, seed)).unwrap();
            assert!(error(&e, lambda_m).abs() < direction_bound(lambda_m), "{lambda_m} seed {seed}: {e:?}");
            // Residual: the waves' symbols span (kh)^2 / 12 relative (c from 1/2 to 1), so the misfit of any one
            // k^4 stays below that unless the waves cancel one another over the region (measured: 0.35 to 0.43
            // of the bound).
            assert!(e.residual < kh_sq(lambda_m) / 12.0, "{lambda_m} seed {seed}: {e:?}");
        }
    }
}

#[test]
fn evanescent_waves_obey_the_same_equation() {
    // Alone, evanescent waves read k high by (kh)^2 (c + 3/4) / 24, c in [1/2, 1] (the stencil's error has the
    // opposite sign for them, and the correction assumes propagating waves): within [1.25, 1.75] (kh)^2 / 24 short,
    // with 10 % for the next order.
    for lambda_m in WAVELENGTHS_M {
        let e = estimate(&evanescent_mixture(lambda_m, 4, 99)).unwrap();
        let (lo, hi) = (1.25 * kh_sq(lambda_m) / 24.0, 1.75 * kh_sq(lambda_m) / 24.0);
        assert!(-error(&e, lambda_m) > 0.9 * lo && -error(&e, lambda_m) < 1.1 * hi, "{lambda_m}: {e:?}");
        // Mixed with standing waves (amplitude 30: 0.3 to 0.8 of the energy over the mask from 10 cm up), the
        // estimate is the energy-weighted mean: within the direction bound plus the evanescent share's error.
        let p = standing_mixture(lambda_m, 24, 5);
        let ev = evanescent_mixture(lambda_m, 4, 99);
        let field: Vec<Complex64> = p.iter().zip(&ev).map(|(a, b)| a + b * 30.0).collect();
        let mask = stadium_mask();
        let energy = |f: &dyn Fn(usize) -> f64| (0..NX * NY).filter(|&i| mask[i]).map(f).sum::<f64>();
        let share = energy(&|i| (ev[i] * 30.0).norm_sqr()) / energy(&|i| field[i].norm_sqr());
        let e = estimate(&field).unwrap();
        let bound = direction_bound(lambda_m) + 1.1 * share * hi;
        assert!(error(&e, lambda_m).abs() < bound, "{lambda_m}: share {share}, {e:?}");
    }
}

#[test]
fn cylindrical_wave_from_outside_the_region() {
    // H0(k r) from a source beyond the grid's corner: an exact solution, a fan of directions; the direction bound.
    for lambda_m in WAVELENGTHS_M {
        let e = estimate(&hankel_wave(lambda_m, 0.16, 0.09)).unwrap();
        assert!(error(&e, lambda_m).abs() < direction_bound(lambda_m), "{lambda_m}: {e:?}");
    }
}

#[test]
fn a_source_inside_needs_its_exclusion() {
    // H0 has a logarithmic singularity at its source, inside the grid here: with no exclusion the stencils around
    // it ruin the estimate (-61 % at 25 cm, residual near 1); keeping them 2 cm away restores it to within the
    // direction bound plus 0.05 % (measured: 0.03 % at 5 cm), and the residual tells the two cases apart.
    let (sx, sy) = (0.0325, 0.0125);
    for lambda_m in WAVELENGTHS_M {
        let field = hankel_wave(lambda_m, sx, sy);
        let bad = estimate(&field).unwrap();
        assert!(bad.residual > 0.9, "{lambda_m}: {bad:?}");
        let exclusion = [Exclusion { x_m: sx, y_m: sy, radius_m: 0.02 }];
        let e =
            estimate_local_wavelength(&field, &stadium_mask(), &grid(), &exclusion, &LocalOptions::default()).unwrap();
        assert!(error(&e, lambda_m).abs() < direction_bound(lambda_m) + 5e-4, "{lambda_m}: {e:?}");
        assert!(e.residual < 0.1, "{lambda_m}: {e:?}");
        assert!(e.points_used < bad.points_used);
    }
}

#[test]
fn corrections_do_what_they_say() {
    // Along x at 10 cm: uncorrected reads long by (kh)^2 / 24 (0.41 %), the axis correction is exact, the
    // isotropic one leaves (kh)^2 / 96 (0.10 %). Tolerances: 5 % of each figure for the next order.
    let field = plane_wave(0.10, 0.0);
    let with = |correction| {
        let opts = LocalOptions { correction, ..LocalOptions::default() };
        error(&estimate_local_wavelength(&field, &stadium_mask(), &grid(), &[], &opts).unwrap(), 0.10)
    };
    let x = kh_sq(0.10);
    assert!((with(StencilCorrection::None) - x / 24.0).abs() < 0.05 * x / 24.0);
    assert!(with(StencilCorrection::Axis).abs() < 1e-9);
    assert!((with(StencilCorrection::Isotropic) - x / 96.0).abs() < 0.05 * x / 96.0);
}

#[test]
fn lossy_waves_keep_their_real_wavelength() {
    // A damped plate: k = k0 (1 + i eta)^(-1/4), a wave decaying as it travels. The estimate is 2 pi / Re(k), and
    // the raw quotient's phase is -eta (arg of 1 / (1 + i eta)); eta = 0.03 as the acrylic scene.
    let (lambda0_m, eta) = (0.10, 0.03f64);
    let k = Complex64::new(2.0 * PI / lambda0_m, 0.0) * Complex64::new(1.0, eta).powf(-0.25);
    let field: Vec<Complex64> = (0..NX * NY)
        .map(|i| {
            let (x, _) = xy_m(i);
            (Complex64::i() * k * x).exp()
        })
        .collect();
    let e = estimate(&field).unwrap();
    // Along x: the isotropic correction leaves +(kh)^2 / 96 = 0.10 %; 0.12 % allows for the next order.
    assert!(error(&e, 2.0 * PI / k.re).abs() < 0.0012, "{e:?}");
    assert!((e.k4_raw.arg() + eta.atan()).abs() < 0.002, "{e:?}");
}

#[test]
fn short_wavelengths_are_flagged_then_refused() {
    // 2.5 cm = 5 steps: below 6, flagged, still within the direction bound at that kh (1.6 %, x 1.1).
    let e = estimate(&plane_wave(0.025, 0.4)).unwrap();
    assert!(e.flags.too_short && !e.flags.in_range(), "{e:?}");
    assert!(error(&e, 0.025).abs() < direction_bound(0.025), "{e:?}");
    // A checkerboard, (-1)^(ix + iy): the stencil returns 64 u, beyond any wave the grid can carry (k h <= pi).
    let checkerboard: Vec<Complex64> = (0..NX * NY)
        .map(|i| Complex64::new(if (i % NX + i / NX).is_multiple_of(2) { 1.0 } else { -1.0 }, 0.0))
        .collect();
    assert!(matches!(estimate(&checkerboard), Err(AnalysisError::NotAPlateWave { .. })));
}

#[test]
fn static_fields_are_not_plate_waves() {
    // Rigid-body motion and tilt have a zero bilaplacian: no wavelength (an evanescent-only real exponential would
    // be one, with Re k^4 > 0, so the test is on fields with none).
    let constant = vec![Complex64::new(2.0, -1.0); NX * NY];
    let tilt: Vec<Complex64> = (0..NX * NY).map(|i| Complex64::new(1.0 + 3.0 * xy_m(i).0 - xy_m(i).1, 0.0)).collect();
    let saddle: Vec<Complex64> = (0..NX * NY).map(|i| Complex64::new(xy_m(i).0 * xy_m(i).1, 0.0)).collect();
    for field in [constant, tilt, saddle] {
        assert!(matches!(estimate(&field), Err(AnalysisError::NotAPlateWave { .. })));
    }
}

#[test]
fn refuses_fields_without_energy_or_points() {
    assert!(matches!(estimate(&vec![Complex64::ZERO; NX * NY]), Err(AnalysisError::NoEnergy { .. })));
    // Three rows measured: no point has two measured neighbours on each side in y.
    let mask: Vec<bool> = (0..NX * NY).map(|i| (11..14).contains(&(i / NX))).collect();
    let r = estimate_local_wavelength(&plane_wave(0.05, 0.0), &mask, &grid(), &[], &LocalOptions::default());
    assert!(matches!(r, Err(AnalysisError::TooFewPoints { measured: 0, required: 1 })), "{r:?}");
    // An exclusion covering the grid.
    let all = [Exclusion { x_m: 0.0, y_m: 0.0, radius_m: 1.0 }];
    let r = estimate_local_wavelength(&plane_wave(0.05, 0.0), &stadium_mask(), &grid(), &all, &LocalOptions::default());
    assert!(matches!(r, Err(AnalysisError::TooFewPoints { measured: 0, .. })), "{r:?}");
    // min_points: one point is enough for a plane wave; more than the grid offers is refused.
    let mut one = vec![false; NX * NY];
    for (dx, dy) in
        [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1), (2, 0), (-2, 0), (0, 2), (0, -2)]
    {
        one[((12 + dy) * NX as isize + 24 + dx) as usize] = true;
    }
    let e = estimate_local_wavelength(&plane_wave(0.05, 0.0), &one, &grid(), &[], &LocalOptions::default()).unwrap();
    assert_eq!(e.points_used, 1);
    assert!(error(&e, 0.05).abs() < direction_bound(0.05), "{e:?}");
    let opts = LocalOptions { min_points: 2, ..LocalOptions::default() };
    let r = estimate_local_wavelength(&plane_wave(0.05, 0.0), &one, &grid(), &[], &opts);
    assert!(matches!(r, Err(AnalysisError::TooFewPoints { measured: 1, required: 2 })), "{r:?}");
}

#[test]
fn nan_is_refused_where_measured_and_ignored_where_not() {
    let mask = stadium_mask();
    let mut field = plane_wave(0.05, 0.0);
    assert!(!mask[0]);
    field[0] = Complex64::new(f64::NAN, 0.0);
    assert!(estimate(&field).is_ok());
    let centre = (NY / 2) * NX + NX / 2;
    field[centre] = Complex64::new(0.0, f64::INFINITY);
    assert_eq!(estimate(&field), Err(AnalysisError::NonFinite { input: "field", index: centre }));
}

#[test]
fn result_does_not_depend_on_the_field_scale() {
    let field = standing_mixture(0.10, 24, 3);
    let reference = estimate(&field).unwrap();
    for scale in [1e-300, 1e300] {
        let scaled: Vec<Complex64> = field.iter().map(|v| v * scale).collect();
        let e = estimate(&scaled).unwrap();
        // Normalised to unit peak first; what remains is rounding.
        assert!((e.wavelength_m / reference.wavelength_m - 1.0).abs() < 1e-9, "{scale}: {e:?}");
    }
}

#[test]
fn refuses_bad_shapes_and_parameters() {
    let (field, mask, g) = (plane_wave(0.05, 0.0), stadium_mask(), grid());
    let opts = LocalOptions::default();
    let call = |f: &[Complex64], m: &[bool], g, ex: &[Exclusion], o| estimate_local_wavelength(f, m, g, ex, o);
    assert!(matches!(call(&field[1..], &mask, &g, &[], &opts), Err(AnalysisError::LengthMismatch { .. })));
    assert!(matches!(call(&field, &mask[1..], &g, &[], &opts), Err(AnalysisError::LengthMismatch { .. })));
    let mut bad_grid = g;
    bad_grid.spacing_m = f64::NAN;
    assert!(matches!(call(&field, &mask, &bad_grid, &[], &opts), Err(AnalysisError::InvalidParameter { .. })));
    for ex in [
        Exclusion { x_m: f64::NAN, y_m: 0.0, radius_m: 0.01 },
        Exclusion { x_m: 0.0, y_m: 0.0, radius_m: -0.01 },
        Exclusion { x_m: 0.0, y_m: 0.0, radius_m: f64::INFINITY },
    ] {
        let r = call(&field, &mask, &g, &[ex], &opts);
        assert!(matches!(r, Err(AnalysisError::InvalidParameter { name: "exclusions", .. })), "{r:?}");
    }
    let zero = LocalOptions { min_points: 0, ..opts };
    assert!(matches!(
        call(&field, &mask, &g, &[], &zero),
        Err(AnalysisError::InvalidParameter { name: "min_points", .. })
    ));
}

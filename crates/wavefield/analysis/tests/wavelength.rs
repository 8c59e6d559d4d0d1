//! Wavelength estimator on synthetic fields on the lab grid (49 x 25 at 5 mm, stadium mask), and at its extremes.
//!
//! Tolerances come from the bias table (`examples/wavelength_bias.rs`), whose cause is explained in the module
//! documentation of `metaplate_analysis::wavelength`: for wavelengths up to `L / 2` (L = 24.5 cm) the half-maximum
//! region is narrow next to |k| and the median is within about 3 % of the truth.
#![allow(clippy::unwrap_used)] // tests may unwrap

use crate::common;

use common::*;
use metaplate_analysis::AnalysisError;
use metaplate_analysis::wavelength::{
    AcrossActuators, EstimateFlags, KSpaceOptions, WavelengthEstimate, estimate_wavelength, summarise,
};
use num_complex::Complex64;

fn estimate(field: &[Complex64]) -> Result<WavelengthEstimate, AnalysisError> {
    estimate_wavelength(field, &stadium_mask(), NX, NY, SPACING_M, &KSpaceOptions::default())
}

fn relative_error(estimate_m: f64, truth_m: f64) -> f64 {
    (estimate_m / truth_m - 1.0).abs()
}

#[test]
fn plane_waves_within_resolution() {
    for lambda_m in [0.025, 0.05, 0.10] {
        for angle_deg in [0.0f64, 30.0, 90.0, 135.0] {
            let e = estimate(&plane_wave(lambda_m, angle_deg.to_radians())).unwrap();
            // The half-maximum ellipse around k0 reaches further from the origin across k0 than along it, so the
            // median is off by a few per cent at 10 cm (2.6 % measured at 90 deg); 3 % bounds that.
            assert!(relative_error(e.median_m, lambda_m) < 0.03, "{lambda_m} m at {angle_deg} deg: {e:?}");
            // The sub-bin peak of a lone plane wave is off only through mean removal's notch at k = 0: 1.8 %
            // measured at 10 cm across the 12.5 cm side, none at 5 cm and below.
            let peak_tol = if lambda_m > 0.06 { 0.025 } else { 0.005 };
            assert!(relative_error(e.peak_m, lambda_m) < peak_tol, "{lambda_m} m at {angle_deg} deg: {e:?}");
            assert!(e.iqr_m.0 <= e.median_m && e.median_m <= e.iqr_m.1);
            assert!(e.bins_in_contour > 1);
            assert_eq!(e.flags, EstimateFlags::default(), "{lambda_m} m is inside the valid range");
        }
    }
}

#[test]
fn cylindrical_wave_from_outside_the_aperture() {
    for lambda_m in [0.025, 0.05, 0.10] {
        let e = estimate(&cylindrical_wave(lambda_m, 0.16, 0.09)).unwrap();
        // Curved wavefronts spread the peak over a range of directions, not of |k|: 1 % measured, 3 % as above.
        assert!(relative_error(e.median_m, lambda_m) < 0.03, "{lambda_m} m: {e:?}");
        assert!(e.flags.in_range());
    }
}

#[test]
fn cylindrical_wave_from_inside_the_aperture() {
    for lambda_m in [0.025, 0.05] {
        let e = estimate(&cylindrical_wave(lambda_m, 0.0325, 0.0125)).unwrap();
        // The 1 / sqrt(r) amplitude around a source inside the grid is itself a spatial structure that widens the
        // ring outward (shorter wavelengths): +2.4 % measured at 5 cm; 4 % bounds it. At 10 cm the source's near
        // field dominates the grid and the bias reaches +15 to +19 %, a property of such a field, not tested here.
        assert!(relative_error(e.median_m, lambda_m) < 0.04, "{lambda_m} m: {e:?}");
    }
}

#[test]
fn reverberant_standing_mixture() {
    // Speckle: 24 waves seen through an aperture a few wavelengths wide leave few independent k-samples on the ring,
    // and the peak lands where they happen to add up, so single fields scatter. Over 64 fields (command in
    // `examples/wavelength_bias.rs scatter`) the bias has mean within 0.1 % and standard
    // deviation 0.3 %, 1.0 %, 3.9 % at 2.5, 5, 10 cm. Here 16 other fields: their mean must lie within three standard
    // errors (3 sd / 4) of zero, and each single field within 5 sd (checked where the tail is Gaussian-like; at
    // 10 cm single fields reach 4 sd, so only the mean is checked there).
    for (lambda_m, sd) in [(0.025, 0.003), (0.05, 0.010), (0.10, 0.039)] {
        let seeds = 16u64;
        let mut sum = 0.0;
        for seed in 1000..1000 + seeds {
            let e = estimate(&standing_mixture(lambda_m, 24, seed)).unwrap();
            let bias = e.median_m / lambda_m - 1.0;
            if lambda_m < 0.06 {
                assert!(bias.abs() < 5.0 * sd, "{lambda_m} m, seed {seed}: {e:?}");
            }
            sum += bias;
        }
        let mean = sum / seeds as f64;
        assert!(mean.abs() < 3.0 * sd / (seeds as f64).sqrt(), "{lambda_m} m: mean bias {mean}");
    }
}

#[test]
fn long_wavelengths_are_flagged_and_biased_short() {
    // 25 cm exceeds the grid's longer side (24.5 cm): the aperture cannot resolve it.
    for field in [plane_wave(0.25, 0.0), standing_mixture(0.25, 24, 1), cylindrical_wave(0.25, 0.16, 0.09)] {
        let e = estimate(&field).unwrap();
        assert!(e.flags.under_resolved, "{e:?}");
        assert!(!e.flags.in_range());
        // The documented direction of the bias: short.
        assert!(e.median_m < 0.25, "{e:?}");
    }
}

#[test]
fn wavelength_at_the_spatial_nyquist_limit() {
    // lambda = 2 * spacing: the field alternates sign from point to point, |k| = pi / d on the k-grid's edge.
    let lambda_m = 2.0 * SPACING_M;
    let e = estimate(&plane_wave(lambda_m, 0.0)).unwrap();
    assert!(e.flags.near_nyquist, "{e:?}");
    // The peak bin is exactly at pi / d (no neighbour beyond it to interpolate with): exact to rounding.
    assert!(relative_error(e.peak_m, lambda_m) < 1e-9, "{e:?}");
    // Shorter than 2 d cannot be seen: 9 mm aliases to 1 / (1 / d - 1 / lambda) = 11.25 mm, unflagged, because
    // nothing in the samples tells it from a real 11.25 mm wave. The valid range starts at 2 d.
    let e = estimate(&plane_wave(0.009, 0.0)).unwrap();
    assert!(relative_error(e.peak_m, 0.01125) < 0.005, "{e:?}");
}

#[test]
fn line_scans_measure_the_trace_wavelength() {
    // A row of 49 points along x, and a column of 25 along y.
    let lambda_m = 0.025;
    let row: Vec<Complex64> = (0..NX)
        .map(|ix| Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * ix as f64 * SPACING_M / lambda_m))
        .collect();
    let e = estimate_wavelength(&row, &[true; NX], NX, 1, SPACING_M, &KSpaceOptions::default()).unwrap();
    // 1-D: the half-maximum interval is symmetric around k0, so the median is the peak to 1 % (2.5 cm is 10 %
    // of the 24.5 cm line: well resolved).
    assert!(relative_error(e.median_m, lambda_m) < 0.01, "{e:?}");
    let column: Vec<Complex64> = (0..NY)
        .map(|iy| Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * iy as f64 * SPACING_M / lambda_m))
        .collect();
    let e = estimate_wavelength(&column, &[true; NY], 1, NY, SPACING_M, &KSpaceOptions::default()).unwrap();
    // 12.5 cm line, 5 wavelengths: still resolved, 2 %.
    assert!(relative_error(e.median_m, lambda_m) < 0.02, "{e:?}");
}

#[test]
fn result_does_not_depend_on_the_field_scale() {
    let field = standing_mixture(0.05, 24, 3);
    let reference = estimate(&field).unwrap();
    for scale in [1e-300, 1e300] {
        let scaled: Vec<Complex64> = field.iter().map(|v| v * scale).collect();
        let e = estimate(&scaled).unwrap();
        // The input is normalised to unit peak first; what remains is rounding.
        assert!(relative_error(e.median_m, reference.median_m) < 1e-9, "scale {scale}: {e:?}");
    }
}

#[test]
fn refuses_fields_without_energy() {
    let zero = vec![Complex64::ZERO; NX * NY];
    assert!(matches!(estimate(&zero), Err(AnalysisError::NoEnergy { .. })));
    // A constant (rigid-body) field is all k = 0: nothing left once the mean is removed.
    let constant = vec![Complex64::new(3.0, -1.0); NX * NY];
    assert!(matches!(estimate(&constant), Err(AnalysisError::NoEnergy { .. })));
}

#[test]
fn refuses_a_single_measured_point() {
    let mut mask = vec![false; NX * NY];
    mask[600] = true;
    let r = estimate_wavelength(&plane_wave(0.05, 0.0), &mask, NX, NY, SPACING_M, &KSpaceOptions::default());
    assert!(matches!(r, Err(AnalysisError::TooFewPoints { measured: 1, required: 2 })), "{r:?}");
    let r =
        estimate_wavelength(&plane_wave(0.05, 0.0), &[false; NX * NY], NX, NY, SPACING_M, &KSpaceOptions::default());
    assert!(matches!(r, Err(AnalysisError::TooFewPoints { measured: 0, .. })), "{r:?}");
}

#[test]
fn nan_is_refused_where_measured_and_ignored_where_not() {
    let mask = stadium_mask();
    let mut field = plane_wave(0.05, 0.0);
    let corner = 0; // cut off by the stadium's rounded end
    assert!(!mask[corner]);
    field[corner] = Complex64::new(f64::NAN, 0.0);
    assert!(estimate(&field).is_ok());
    let centre = (NY / 2) * NX + NX / 2;
    field[centre] = Complex64::new(0.0, f64::INFINITY);
    assert_eq!(estimate(&field), Err(AnalysisError::NonFinite { input: "field", index: centre }));
}

#[test]
fn refuses_bad_shapes_and_parameters() {
    let field = plane_wave(0.05, 0.0);
    let mask = stadium_mask();
    let opts = KSpaceOptions::default();
    assert!(matches!(
        estimate_wavelength(&field[1..], &mask, NX, NY, SPACING_M, &opts),
        Err(AnalysisError::LengthMismatch { .. })
    ));
    assert!(matches!(
        estimate_wavelength(&field, &mask[1..], NX, NY, SPACING_M, &opts),
        Err(AnalysisError::LengthMismatch { .. })
    ));
    assert!(matches!(
        estimate_wavelength(&[], &[], 0, NY, SPACING_M, &opts),
        Err(AnalysisError::InvalidParameter { .. })
    ));
    assert!(matches!(
        estimate_wavelength(&field, &mask, usize::MAX, 2, SPACING_M, &opts),
        Err(AnalysisError::TooLarge { .. })
    ));
    for spacing_m in [0.0, -0.005, f64::NAN, f64::INFINITY, 1e-10, 1e7] {
        assert!(matches!(
            estimate_wavelength(&field, &mask, NX, NY, spacing_m, &opts),
            Err(AnalysisError::InvalidParameter { name: "spacing_m", .. })
        ));
    }
    let bad = [
        KSpaceOptions { zero_pad_factor: 0, ..opts },
        KSpaceOptions { zero_pad_factor: 65, ..opts },
        KSpaceOptions { taper_width_m: f64::NAN, ..opts },
        KSpaceOptions { taper_width_m: -0.01, ..opts },
        KSpaceOptions { min_k_rad_m: Some(f64::NAN), ..opts },
        KSpaceOptions { min_k_rad_m: Some(-1.0), ..opts },
    ];
    for o in bad {
        assert!(
            matches!(
                estimate_wavelength(&field, &mask, NX, NY, SPACING_M, &o),
                Err(AnalysisError::InvalidParameter { .. })
            ),
            "{o:?}"
        );
    }
    // Everything below the DC exclusion: no peak candidate at all.
    let o = KSpaceOptions { min_k_rad_m: Some(1e6), ..opts };
    assert!(matches!(estimate_wavelength(&field, &mask, NX, NY, SPACING_M, &o), Err(AnalysisError::NoEnergy { .. })));
}

fn fake(median_m: f64, q25_m: f64, q75_m: f64) -> WavelengthEstimate {
    WavelengthEstimate {
        peak_m: median_m,
        median_m,
        iqr_m: (q25_m, q75_m),
        bins_in_contour: 10,
        flags: EstimateFlags::default(),
    }
}

#[test]
fn summary_across_actuators() {
    let mut estimates = vec![fake(0.10, 0.09, 0.11), fake(0.12, 0.11, 0.14), fake(0.20, 0.18, 0.23)];
    estimates[2].flags.under_resolved = true;
    let mean = summarise(&estimates, AcrossActuators::Mean).unwrap();
    // Exact arithmetic on three numbers; 1e-12 covers rounding.
    assert!((mean.median_m - 0.14).abs() < 1e-12);
    assert!((mean.iqr_m.0 - 0.38 / 3.0).abs() < 1e-12 && (mean.iqr_m.1 - 0.16).abs() < 1e-12);
    assert_eq!((mean.actuators, mean.flagged), (3, 1));
    let median = summarise(&estimates, AcrossActuators::Median).unwrap();
    assert!((median.median_m - 0.12).abs() < 1e-12 && (median.iqr_m.0 - 0.11).abs() < 1e-12);
    assert!(matches!(summarise(&[], AcrossActuators::Mean), Err(AnalysisError::Empty { .. })));
    assert!(matches!(
        summarise(&[fake(f64::NAN, 0.1, 0.2)], AcrossActuators::Median),
        Err(AnalysisError::NonFinite { index: 0, .. })
    ));
}

#[test]
fn summary_of_real_estimates_matches_the_truth() {
    // Eight "actuators" = eight reverberant fields at 5 cm: the mean of their medians lies within three standard
    // errors (3 x 1.0 % / sqrt(8) ~ 1.1 %) of the truth; 1.2 % allows for the mean bias (0.1 %).
    let estimates: Vec<WavelengthEstimate> =
        (0..8).map(|seed| estimate(&standing_mixture(0.05, 24, 100 + seed)).unwrap()).collect();
    let s = summarise(&estimates, AcrossActuators::Mean).unwrap();
    assert!(relative_error(s.median_m, 0.05) < 0.012, "{s:?}");
    assert!(s.iqr_m.0 < s.median_m && s.median_m < s.iqr_m.1);
}

#[test]
fn spacing_extremes_scale_the_result() {
    // The samples of a 5 cm wave on a 5 mm grid are those of a 10-step wave on any grid: the estimate scales with
    // the spacing, to rounding, at both ends of the accepted range.
    use metaplate_analysis::wavelength::{MAX_SPACING_M, MIN_SPACING_M};
    let field = plane_wave(0.05, 0.3);
    let reference = estimate(&field).unwrap();
    for spacing_m in [MIN_SPACING_M, MAX_SPACING_M] {
        let e = estimate_wavelength(&field, &stadium_mask(), NX, NY, spacing_m, &KSpaceOptions::default()).unwrap();
        let expected_m = reference.median_m * spacing_m / SPACING_M;
        assert!(relative_error(e.median_m, expected_m) < 1e-9, "{spacing_m} m: {e:?}");
    }
}

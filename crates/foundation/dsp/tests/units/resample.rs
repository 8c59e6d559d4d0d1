use metaplate_dsp::error::DspError;
use metaplate_dsp::resample::*;
use std::f64::consts::PI;

const FS: f64 = 24_000.0;

/// Worst error of `interp` on a unit sinusoid at `f` cycles per sample, over positions stepping by `step`.
fn worst_error(interp: &Interpolator, f: f64, step: f64) -> f64 {
    let w = 2.0 * PI * f;
    let x: Vec<f64> = (0..1000).map(|i| (w * i as f64 + 0.3).sin()).collect();
    let start = 100.0 + 1.0 / 3.0;
    let y = interp.resample(&x, start, step, 300).unwrap();
    y.iter().enumerate().map(|(j, v)| (v - (w * (start + j as f64 * step) + 0.3).sin()).abs()).fold(0.0, f64::max)
}

#[test]
fn interpolators_meet_their_documented_accuracy() {
    // The bounds stated on `Interpolator`; a step just off 1 walks through all fractional positions.
    let step = 1.0 + 1.0 / 997.0;
    for (hw, f, bound) in [(4, 0.01, 2e-4), (4, 0.1, 2e-4), (8, 0.3, 3e-4), (16, 0.4, 4e-4)] {
        let err = worst_error(&Interpolator::new(hw).unwrap(), f, step);
        assert!(err < bound, "half-width {hw} at {f} fs: {err:e}");
    }
    // The step's extremes, on content that survives the halved rate (0.05 fs < 0.25 fs).
    for step in [0.5, 2.0] {
        let err = worst_error(&Interpolator::new(8).unwrap(), 0.05, step);
        assert!(err < 3e-4, "step {step}: {err:e}");
    }
    assert_eq!(Interpolator::for_band(675.0, FS).half_width(), 4);
    assert_eq!(Interpolator::for_band(5000.0, FS).half_width(), 8);
    assert_eq!(Interpolator::for_band(12_000.0, FS).half_width(), 16);
}

#[test]
fn integer_positions_copy_and_outside_is_zero() {
    let x: Vec<f64> = (0..50).map(|i| (i as f64 * 0.37).cos()).collect();
    let y = Interpolator::new(8).unwrap().resample(&x, -10.0, 1.0, 70).unwrap();
    // The kernel at an integer position is one tap of 1 and zeros of sinc(k) = sin(pi k) / (pi k), 1e-17.
    for (j, v) in y.iter().enumerate() {
        let expected = if (10..60).contains(&j) { x[j - 10] } else { 0.0 };
        assert!((v - expected).abs() < 1e-12, "{j}: {v} vs {expected}");
    }
}

#[test]
fn resample_into_matches_resample_and_reads_only_what_the_kernel_reaches() {
    let x: Vec<f64> = (0..200).map(|i| (i as f64 * 0.21).sin()).collect();
    for hw in [4, 5, 8] {
        let i = Interpolator::new(hw).unwrap();
        let expected = i.resample(&x, 20.3, 1.0002, 150).unwrap();
        let mut out = vec![f64::NAN; 150];
        i.resample_into(&x, 20.3, 1.0002, &mut out).unwrap();
        assert_eq!(out, expected, "half-width {hw}");
    }
    // Positions 50.25 ..= 59.25, half-width 4: the kernel reads samples 47..=63, checked with a margin of 2 for
    // the rounding of positions to the table (44..=65). A NaN further out does not touch the output and is not
    // an error; one inside is, named at its index in x.
    let i = Interpolator::new(4).unwrap();
    let mut out = vec![0.0; 10];
    for far in [0, 40, 68, 199] {
        let mut y = x.clone();
        y[far] = f64::NAN;
        i.resample_into(&y, 50.25, 1.0, &mut out).unwrap();
    }
    for near in [47, 55, 63] {
        let mut y = x.clone();
        y[near] = f64::INFINITY;
        let err = i.resample_into(&y, 50.25, 1.0, &mut out).unwrap_err();
        assert!(matches!(err, DspError::NonFinite { index, .. } if index == near), "{near}: {err}");
    }
    // Nothing to write: nothing read, nothing refused.
    i.resample_into(&[f64::NAN], 0.0, 1.0, &mut []).unwrap();
    // Positions beyond either end of x read nothing of it: zeros.
    i.resample_into(&x, -100.0, 1.0, &mut out).unwrap();
    assert!(out.iter().all(|v| *v == 0.0));
    i.resample_into(&x, 1000.0, 2.0, &mut out).unwrap();
    assert!(out.iter().all(|v| *v == 0.0));
}

#[test]
fn resample_refuses_bad_parameters() {
    let i = Interpolator::new(4).unwrap();
    assert!(matches!(i.resample(&[1.0, f64::NAN], 0.0, 1.0, 2), Err(DspError::NonFinite { .. })));
    assert!(matches!(i.resample(&[1.0], f64::NAN, 1.0, 2), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(i.resample(&[1.0], 1e12, 1.0, 2), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(i.resample(&[1.0], 0.0, 0.49, 2), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(i.resample(&[1.0], 0.0, 2.01, 2), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(i.resample(&[1.0], 0.0, 1.0, MAX_RESAMPLE_LEN + 1), Err(DspError::TooLong { .. })));
    assert!(i.resample(&[], 0.0, 1.0, 3).unwrap().iter().all(|v| *v == 0.0));
    assert!(Interpolator::new(0).is_err());
    assert!(Interpolator::new(Interpolator::MAX_HALF_WIDTH + 1).is_err());
    // Odd half-widths take the generic path and agree with the specialised ones in accuracy.
    assert!(worst_error(&Interpolator::new(5).unwrap(), 0.05, 1.001) < 2e-4);
}

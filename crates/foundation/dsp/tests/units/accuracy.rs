use metaplate_dsp::accuracy::*;
use metaplate_dsp::error::DspError;
use num_complex::Complex64;

#[test]
fn relative_error_in_db() {
    let r = [1.0, -2.0, 3.0, 0.5];
    let m: Vec<f64> = r.iter().map(|v| v * 1.1).collect();
    assert!((relative_error_db(&m, &r).unwrap() + 20.0).abs() < 1e-9);
    assert!(relative_error_db(&[0.0; 4], &r).unwrap().abs() < 1e-12);
    assert_eq!(relative_error_db(&r, &r).unwrap(), IDENTICAL_DB);
    assert!(relative_error_db(&r, &[0.0; 4]).is_err());
    assert!(relative_error_db(&r[..3], &r).is_err());
    assert!(relative_error_db(&[], &[]).is_err());
    assert!(relative_error_db(&[f64::NAN; 4], &r).is_err());
    assert!(relative_error_db(&[1e300; 4], &r).is_err(), "an overflowing error is refused, not infinite");
}

#[test]
fn band_energy_is_parseval_within_the_band() {
    let fs = 1000.0;
    let n = 1000;
    // A 100 Hz sine of amplitude 2 (energy n * 2^2 / 2 = 2000) and a 300 Hz one of amplitude 1 (500).
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            2.0 * (std::f64::consts::TAU * 100.0 * t).sin() + (std::f64::consts::TAU * 300.0 * t).cos()
        })
        .collect();
    assert!((band_energy(&x, (0.0, 500.0), fs).unwrap() - 2500.0).abs() < 1e-9);
    assert!((band_energy(&x, (80.0, 120.0), fs).unwrap() - 2000.0).abs() < 1e-9);
    assert!(band_energy(&x, (350.0, 500.0), fs).unwrap() < 1e-18);
}

#[test]
fn the_estimate_is_noise_over_what_is_left_and_capped() {
    let fs = 24000.0;
    // An in-band sine whose band energy E is known: the estimate is noise / (E - noise).
    let ir: Vec<f64> = (0..2400).map(|i| (std::f64::consts::TAU * 200.0 * i as f64 / fs).sin()).collect();
    let e = band_energy(&ir, ERROR_BAND_HZ, fs).unwrap();
    assert!((e - 1200.0).abs() < 1e-6, "{e}");
    let db = estimated_error_db(&ir, e / 101.0, fs).unwrap();
    assert!((db + 20.0).abs() < 1e-9, "{db}");
    // Extremes: no noise; noise at or above half the energy; a response with nothing in the band.
    assert_eq!(estimated_error_db(&ir, 0.0, fs).unwrap(), IDENTICAL_DB);
    assert_eq!(estimated_error_db(&ir, e / 2.0, fs).unwrap(), 0.0);
    assert_eq!(estimated_error_db(&ir, 1e300, fs).unwrap(), 0.0);
    assert!(estimated_error_db(&ir, 1e-300, fs).unwrap() >= IDENTICAL_DB);
    let dc = vec![1.0; 2400];
    assert!(estimated_error_db(&dc, 1.0, fs).is_err(), "no energy in the band");
    assert!(estimated_error_db(&ir, f64::NAN, fs).is_err());
    assert!(estimated_error_db(&ir, -1.0, fs).is_err());
    assert!(estimated_error_db(&ir, 1.0, 0.0).is_err());
    assert!(estimated_error_db(&[], 1.0, fs).is_err());
}

#[test]
fn spectral_error_matches_the_real_one() {
    let r = [1.0, -2.0, 3.0, 0.5];
    let m = [1.1, -1.9, 2.5, 0.0];
    let c = |x: &[f64]| x.iter().map(|&v| Complex64::new(v, 0.0)).collect::<Vec<_>>();
    assert_eq!(spectral_error_db(&c(&m), &c(&r)).unwrap(), relative_error_db(&m, &r).unwrap());
    let mut bad = c(&m);
    bad[2].im = f64::INFINITY;
    assert!(matches!(spectral_error_db(&bad, &c(&r)), Err(DspError::NonFinite { index: 2, .. })));
    assert!(spectral_error_db(&c(&r), &[Complex64::new(0.0, 0.0); 4]).is_err());
}

use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::*;
use metaplate_dsp::error::DspError;
use metaplate_dsp::fft;
use num_complex::Complex64;

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

#[test]
fn division_without_regularisation_is_exact() {
    let d = [c(2.0, 0.0), c(0.0, 1.0), c(-1.0, 1.0)];
    let h = [c(0.5, 0.0), c(1.0, -2.0), c(3.0, 0.25)];
    let n: Vec<Complex64> = d.iter().zip(&h).map(|(a, b)| a * b).collect();
    let got = divide_spectra(&n, &d, None, 0.0).unwrap();
    for (g, want) in got.iter().zip(&h) {
        // Products and quotients of small exact numbers: a few ulps.
        assert!((g - want).norm() < 1e-15, "{g} vs {want}");
    }
}

#[test]
fn epsilon_is_relative_to_the_in_band_peak() {
    // Bin 0 is out of band (gain 0) and much stronger: it must not set eps.
    let d = [c(100.0, 0.0), c(1.0, 0.0), c(2.0, 0.0)];
    let n = d;
    let gains = [0.0, 1.0, 0.5];
    let reg = 0.25;
    let got = divide_spectra(&n, &d, Some(&gains), reg).unwrap();
    let eps = reg * 4.0; // max in-band |D|^2 is 4, at bin 2
    assert_eq!(got[0], c(0.0, 0.0));
    // H = |D|^2 / (|D|^2 + eps) * gain, in exact binary fractions here.
    assert!((got[1].re - 1.0 / (1.0 + eps)).abs() < 1e-15);
    assert!((got[2].re - 0.5 * 4.0 / (4.0 + eps)).abs() < 1e-15);
    assert_eq!(got[1].im, 0.0);
}

#[test]
fn zero_gain_bins_are_never_divided() {
    // An exact spectral zero out of band is harmless even without regularisation.
    let d = [c(0.0, 0.0), c(1.0, 0.0)];
    let got = divide_spectra(&[c(1.0, 0.0), c(1.0, 0.0)], &d, Some(&[0.0, 1.0]), 0.0).unwrap();
    assert_eq!(got, vec![c(0.0, 0.0), c(1.0, 0.0)]);
}

#[test]
fn spectral_zero_in_band_without_regularisation_is_a_non_finite_result() {
    let d = [c(0.0, 0.0), c(1.0, 0.0)];
    let n = [c(1.0, 0.0), c(1.0, 0.0)];
    assert!(matches!(divide_spectra(&n, &d, None, 0.0), Err(DspError::NonFiniteResult { .. })));
    // Any positive regularisation makes the same division finite: the zero bin gives 0.
    let got = divide_spectra(&n, &d, None, 1e-12).unwrap();
    assert_eq!(got[0], c(0.0, 0.0));
}

#[test]
fn refuses_bad_spectra_and_parameters() {
    let one = [c(1.0, 0.0), c(1.0, 0.0)];
    assert!(matches!(divide_spectra(&[], &[], None, 0.0), Err(DspError::Empty { .. })));
    assert!(matches!(divide_spectra(&one, &one[..1], None, 0.0), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(
        divide_spectra(&[c(f64::NAN, 0.0), c(1.0, 0.0)], &one, None, 0.0),
        Err(DspError::NonFinite { index: 0, .. })
    ));
    assert!(matches!(
        divide_spectra(&one, &[c(1.0, 0.0), c(0.0, f64::INFINITY)], None, 0.0),
        Err(DspError::NonFinite { index: 1, .. })
    ));
    for reg in [-1e-9, f64::NAN, f64::INFINITY] {
        assert!(matches!(divide_spectra(&one, &one, None, reg), Err(DspError::InvalidParameter { .. })));
    }
    for gains in [[0.0, 0.0], [1.0, -0.5], [f64::NAN, 1.0]] {
        assert!(matches!(divide_spectra(&one, &one, Some(&gains), 0.0), Err(DspError::InvalidParameter { .. })));
    }
    assert!(matches!(divide_spectra(&one, &one, Some(&[1.0]), 0.0), Err(DspError::LengthMismatch { .. })));
}

#[test]
fn denominator_without_energy_in_band_is_refused() {
    let n = [c(1.0, 0.0), c(1.0, 0.0), c(1.0, 0.0)];
    let zero = [c(0.0, 0.0); 3];
    assert!(matches!(divide_spectra(&n, &zero, None, 1e-3), Err(DspError::InvalidParameter { .. })));
    // Energy only out of band; in band below rounding (1e-14 of the peak) counts as none.
    let out_of_band = [c(1.0, 0.0), c(1e-14, 0.0), c(0.0, 0.0)];
    let gains = [0.0, 1.0, 1.0];
    assert!(matches!(divide_spectra(&n, &out_of_band, Some(&gains), 1e-3), Err(DspError::InvalidParameter { .. })));
    // Just above the threshold it divides.
    let weak = [c(1.0, 0.0), c(1e-12, 0.0), c(0.0, 0.0)];
    assert!(divide_spectra(&n, &weak, Some(&gains), 1e-3).is_ok());
}

#[test]
fn paper_config_is_valid_and_as_documented() {
    let cfg = DeconvConfig::paper();
    cfg.validate().unwrap();
    assert_eq!(cfg.sample_rate_hz, 24_000.0);
    assert_eq!(cfg.ir_len, 12_000);
    assert_eq!(cfg.pre_samples, 0);
    let band = cfg.band.unwrap();
    assert_eq!((band.lo_hz, band.hi_hz), (62.0, 625.0));
    assert!(band.lo_transition_hz > 0.0 && band.hi_hz + band.hi_transition_hz < 781.0);
}

#[test]
fn calibration_config_is_valid_and_as_documented() {
    let cfg = DeconvConfig::calibration();
    cfg.validate().unwrap();
    assert_eq!((cfg.sample_rate_hz, cfg.ir_len, cfg.pre_samples), (24_000.0, 8192, 2048));
    let band = cfg.band.unwrap();
    // Covers the Kirkeby calibration band, 50..625 Hz, so the band limit is never inverted as a roll-off.
    assert_eq!((band.lo_hz, band.hi_hz), (50.0, 625.0));
    assert_eq!(cfg.regularisation, 1e-4);
}

#[test]
fn validate_refuses_each_bad_field() {
    let base = DeconvConfig::paper();
    let band = base.band.unwrap();
    for bad in [
        DeconvConfig { sample_rate_hz: 0.0, ..base },
        DeconvConfig { sample_rate_hz: f64::NAN, ..base },
        DeconvConfig { ir_len: 0, ..base },
        DeconvConfig { regularisation: -1.0, ..base },
        DeconvConfig { regularisation: f64::INFINITY, ..base },
        DeconvConfig { band: Some(BandLimit { hi_hz: 12_001.0, ..band }), ..base },
        DeconvConfig { band: Some(BandLimit { lo_hz: 700.0, ..band }), ..base },
        DeconvConfig { pre_samples: base.ir_len, ..base },
        DeconvConfig { pre_samples: usize::MAX, ..base },
    ] {
        assert!(matches!(bad.validate(), Err(DspError::InvalidParameter { .. })), "{bad:?}");
    }
    let too_long = DeconvConfig { ir_len: fft::MAX_FFT_LEN + 1, ..base };
    assert!(matches!(too_long.validate(), Err(DspError::TooLong { .. })));
    // Band edges at 0 Hz and exactly at Nyquist are valid.
    let full = BandLimit { lo_hz: 0.0, hi_hz: 12_000.0, lo_transition_hz: 0.0, hi_transition_hz: 0.0 };
    DeconvConfig { band: Some(full), ..base }.validate().unwrap();
    // The largest pre_samples keeps time 0 as the last sample returned.
    DeconvConfig { pre_samples: base.ir_len - 1, ..base }.validate().unwrap();
}

#[test]
fn constant_check_accepts_an_impulse_and_refuses_levels() {
    assert!(check_not_constant("x", &[3.0]).is_ok());
    assert!(check_not_constant("x", &[0.0, 0.0]).is_err());
    assert!(check_not_constant("x", &[0.7; 5]).is_err());
    assert!(check_not_constant("x", &[0.7, 0.7 + 1e-12]).is_ok());
}

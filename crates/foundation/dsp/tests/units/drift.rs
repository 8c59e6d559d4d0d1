use metaplate_core::rng::SplitMix64;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::error::DspError;
use metaplate_dsp::fft;
use metaplate_dsp::resample::Interpolator;
use num_complex::Complex64;
use std::f64::consts::PI;

use metaplate_dsp::drift::*;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};

const FS: f64 = 24_000.0;

/// A 0.2 s linear sweep 200 Hz..3 kHz with 5 ms fades: 4800 samples.
fn sweep() -> Vec<f64> {
    let spec =
        SweepSpec { kind: SweepKind::Linear, f1_hz: 200.0, f2_hz: 3000.0, duration_s: 0.2, ..SweepSpec::default() };
    spec.generate().unwrap()
}

fn band() -> BandLimit {
    BandLimit::new(300.0, 2500.0, 50.0, 200.0).unwrap()
}

#[test]
fn circular_delay_is_exact_on_periodic_band_limited_signals() {
    // Three sinusoids on FFT bins of a 64-sample period: periodic and band-limited, so a circular delay is an
    // exact time shift; f64 FFT rounding stays below 1e-12.
    let n = 64;
    let bins = [(3.0, 1.0, 0.2), (10.0, 0.5, 1.0), (25.0, 0.25, -0.7)];
    let signal = |t: f64| -> f64 { bins.iter().map(|&(k, a, p)| a * (2.0 * PI * k * t / n as f64 + p).sin()).sum() };
    let x: Vec<f64> = (0..n).map(|i| signal(i as f64)).collect();
    for delay in [0.0, 2.3, -7.75, 64.0, 1e9 + 0.5] {
        let y = delay_circular(&x, delay).unwrap();
        for (i, v) in y.iter().enumerate() {
            let expected = signal(i as f64 - delay.rem_euclid(n as f64));
            assert!((v - expected).abs() < 1e-9, "delay {delay} at {i}: {v} vs {expected}");
        }
    }
    assert!(matches!(delay_circular(&[], 1.0), Err(DspError::Empty { .. })));
    assert!(matches!(delay_circular(&[1.0], f64::INFINITY), Err(DspError::InvalidParameter { .. })));
    // Length one: a constant, unchanged by any delay.
    assert_eq!(delay_circular(&[2.0], 0.3).unwrap(), vec![2.0]);
}

#[test]
fn delay_from_spectra_reads_circular_delays_up_to_half_a_period() {
    let e = sweep();
    let n = e.len();
    let template = fft::forward(&e, n).unwrap();
    let gains = band().bin_gains(n, FS);
    // A circularly delayed copy has exactly the template's spectrum times a phase ramp: the estimate is exact to
    // rounding (1e-9 sample), the coherence 1, for delays right up to half the period.
    for delay in [0.0, 0.25, -3.7, 1234.56, -(n as f64) / 2.0 + 0.5, n as f64 / 2.0 - 0.5] {
        let copy = fft::forward(&delay_circular(&e, delay).unwrap(), n).unwrap();
        let est = delay_from_spectra(&copy, &template, n, Some(&gains)).unwrap();
        assert!((est.delay_samples - delay).abs() < 1e-6, "{delay}: {}", est.delay_samples);
        assert!(est.coherence > 0.999_999, "{delay}: coherence {}", est.coherence);
    }
    // Noise has no coherence with the sweep: 1 / sqrt(in-band bins), about 0.05 here; 0.2 is a wide margin.
    let mut rng = SplitMix64::new(1, 0);
    let noise: Vec<f64> = (0..n).map(|_| rng.uniform() * 2.0 - 1.0).collect();
    let est = delay_from_spectra(&fft::forward(&noise, n).unwrap(), &template, n, Some(&gains)).unwrap();
    assert!(est.coherence < 0.2, "noise coherence {}", est.coherence);
    let zero = vec![Complex64::new(0.0, 0.0); template.len()];
    assert!(matches!(delay_from_spectra(&zero, &template, n, None), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(delay_from_spectra(&template[1..], &template, n, None), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(delay_from_spectra(&template, &template, 1, None), Err(DspError::InvalidParameter { .. })));
}

/// `repetitions` copies of `e` played back to back, recorded from `latency` with `drift_ppm`, then a tail.
fn recording(e: &[f64], repetitions: usize, latency: f64, drift_ppm: f64, tail: usize) -> Vec<f64> {
    let played: Vec<f64> = e.iter().copied().cycle().take(e.len() * repetitions).collect();
    let ratio = 1.0 + drift_ppm * 1e-6;
    let len = (latency + played.len() as f64 * ratio).ceil() as usize + tail;
    // Recorder sample m holds player position (m - latency) / ratio: a start of -latency / ratio, a step of
    // 1 / ratio (the library's interpolator here; the round-trip tests use an independent one).
    Interpolator::new(16).unwrap().resample(&played, -latency / ratio, 1.0 / ratio, len).unwrap()
}

#[test]
fn locate_and_fit_recover_latency_and_drift_across_the_valid_range() {
    let e = sweep();
    let n = e.len();
    let b = band();
    // Latency from the recording's first sample to 3 periods in; drift across the accepted range. Clean
    // copies: positions to ~1e-4 sample, so over 3 periods of 4800 samples the drift to ~0.01 ppm; 0.1 ppm and
    // 0.01 sample are margins.
    for latency in [0.0, 0.4, 14_400.3] {
        for drift_ppm in [-MAX_DRIFT_PPM, -37.0, 0.0, 250.0, MAX_DRIFT_PPM] {
            let rec = recording(&e, 4, latency, drift_ppm, 500);
            let positions = locate_repetitions(&rec, &e, 4, Some(&b), FS).unwrap();
            let fit = fit_clock(&positions, n).unwrap();
            let case = format!("latency {latency}, drift {drift_ppm}");
            assert!((fit.drift_ppm - drift_ppm).abs() < 0.1, "{case}: drift {}", fit.drift_ppm);
            assert!((fit.latency_samples - latency).abs() < 0.01, "{case}: latency {}", fit.latency_samples);
            assert!(fit.residual_rms_samples < 0.01, "{case}: residual {}", fit.residual_rms_samples);
            assert!((fit.recorder_position(n as f64) - positions[1]).abs() < 0.01, "{case}");
        }
    }
}

#[test]
fn a_prepared_template_locates_and_measures_as_the_free_functions() {
    let e = sweep();
    let n = e.len();
    let b = band();
    let template = ExcitationTemplate::new(&e, Some(&b), FS).unwrap();
    assert_eq!(template.period_samples(), n);
    assert_eq!(template.spectrum(), fft::forward(&e, n).unwrap().as_slice());
    assert_eq!(template.bin_gains(), Some(b.bin_gains(n, FS).as_slice()));
    // One template for several recordings (different latencies and drifts): the same positions, bit for bit.
    for (latency, drift_ppm) in [(0.0, 0.0), (321.7, -250.0), (14_400.3, MAX_DRIFT_PPM)] {
        let rec = recording(&e, 3, latency, drift_ppm, 500);
        assert_eq!(template.locate(&rec, 3).unwrap(), locate_repetitions(&rec, &e, 3, Some(&b), FS).unwrap());
    }
    // Its delay over the band is `delay_from_spectra`'s, also without a band (all bins).
    let copy = fft::forward(&delay_circular(&e, 37.25).unwrap(), n).unwrap();
    let expected = delay_from_spectra(&copy, template.spectrum(), n, template.bin_gains()).unwrap();
    assert_eq!(template.delay_of(&copy).unwrap(), expected);
    let full = ExcitationTemplate::new(&e, None, FS).unwrap();
    assert_eq!(full.delay_of(&copy).unwrap(), delay_from_spectra(&copy, full.spectrum(), n, None).unwrap());
    assert!(matches!(template.delay_of(&copy[1..]), Err(DspError::LengthMismatch { .. })));
    let mut bad = copy.clone();
    bad[100].re = f64::NAN; // in the band (100 bins of 5 Hz: 500 Hz)
    assert!(matches!(template.delay_of(&bad), Err(DspError::NonFinite { .. })));
    // The valid range of the excitation, band and sample rate.
    assert!(matches!(ExcitationTemplate::new(&[], None, FS), Err(DspError::Empty { .. })));
    assert!(matches!(ExcitationTemplate::new(&[1.0], None, FS), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(ExcitationTemplate::new(&[1.0, f64::NAN], None, FS), Err(DspError::NonFinite { .. })));
    assert!(ExcitationTemplate::new(&[1.0, -1.0], None, FS).is_ok());
    assert!(ExcitationTemplate::new(&e, None, 0.0).is_err());
    let inverted = BandLimit { lo_hz: 2500.0, hi_hz: 300.0, ..b };
    assert!(ExcitationTemplate::new(&e, Some(&inverted), FS).is_err());
}

#[test]
fn locate_refuses_what_holds_no_excitation() {
    let e = sweep();
    assert!(matches!(
        locate_repetitions(&vec![0.0; 20_000], &e, 2, None, FS),
        Err(DspError::InvalidParameter { name: "recording", .. })
    ));
    let mut rng = SplitMix64::new(2, 0);
    let noise: Vec<f64> = (0..20_000).map(|_| rng.uniform() * 2.0 - 1.0).collect();
    assert!(matches!(
        locate_repetitions(&noise, &e, 2, Some(&band()), FS),
        Err(DspError::InvalidParameter { name: "recording", .. })
    ));
    let rec = recording(&e, 2, 100.0, 0.0, 100);
    assert!(matches!(locate_repetitions(&rec, &e, 0, None, FS), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(locate_repetitions(&rec, &[], 1, None, FS), Err(DspError::Empty { .. })));
    assert!(matches!(locate_repetitions(&rec, &e, 1, None, f64::NAN), Err(DspError::InvalidParameter { .. })));
    // Asked for more copies than were played: the last ones are not where the line says.
    assert!(locate_repetitions(&rec, &e, 4, None, FS).is_err());
}

#[test]
fn fit_clock_checks_its_line() {
    let n = 1000;
    let exact: Vec<f64> = (0..5).map(|r| 12.5 + r as f64 * n as f64 * (1.0 + 20e-6)).collect();
    let fit = fit_clock(&exact, n).unwrap();
    assert!((fit.drift_ppm - 20.0).abs() < 1e-6 && (fit.latency_samples - 12.5).abs() < 1e-9);
    assert!((fit.ratio() - 1.000_02).abs() < 1e-12);
    assert!(matches!(fit_clock(&exact[..1], n), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(fit_clock(&exact, 0), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(fit_clock(&[0.0, f64::NAN], n), Err(DspError::NonFinite { .. })));
    // 1500 ppm: beyond the limit and its slack.
    assert!(fit_clock(&[0.0, 1001.5], n).is_err());
    // The limit itself, and just within the slack.
    assert!(fit_clock(&[0.0, 1001.0], n).is_ok() && fit_clock(&[0.0, 999.0005], n).is_ok());
    // One copy 3 samples off the line of the others (a dropout): refused.
    let mut glitch = exact.clone();
    glitch[2] += 3.0;
    assert!(matches!(fit_clock(&glitch, n), Err(DspError::InvalidParameter { .. })));
}

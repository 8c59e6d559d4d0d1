//! Kirkeby inverse filters on a voice-coil-like actuator response.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use std::f64::consts::PI;

use metaplate_dsp::DspError;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::{KirkebyConfig, KirkebyFilter, TargetPhase, design, design_spectrum};
use num_complex::Complex64;

const FS_HZ: f64 = 24_000.0;

/// One biquad section, direct form I, from the RBJ audio-EQ cookbook (bilinear transform prewarped at `f0_hz`).
struct Biquad {
    b: [f64; 3],
    a: [f64; 3],
}

impl Biquad {
    fn new(f0_hz: f64, q: f64, high_pass: bool) -> Self {
        let w0 = 2.0 * PI * f0_hz / FS_HZ;
        let (cos, alpha) = (w0.cos(), w0.sin() / (2.0 * q));
        let b = if high_pass {
            [(1.0 + cos) / 2.0, -(1.0 + cos), (1.0 + cos) / 2.0]
        } else {
            [(1.0 - cos) / 2.0, 1.0 - cos, (1.0 - cos) / 2.0]
        };
        Self { b, a: [1.0 + alpha, -2.0 * cos, 1.0 - alpha] }
    }

    fn filter(&self, x: &[f64]) -> Vec<f64> {
        let (b, a) = (self.b, self.a);
        let mut y = vec![0.0; x.len()];
        for n in 0..x.len() {
            let xm = |k: usize| if n >= k { x[n - k] } else { 0.0 };
            let ym = |y: &[f64], k: usize| if n >= k { y[n - k] } else { 0.0 };
            y[n] = (b[0] * xm(0) + b[1] * xm(1) + b[2] * xm(2) - a[1] * ym(&y, 1) - a[2] * ym(&y, 2)) / a[0];
        }
        y
    }
}

/// Impulse response of the model actuator, `len` samples: a 70 Hz suspension resonance (2nd-order high-pass,
/// Q 2) and a roll-off (two 2nd-order low-pass sections at 350 Hz, Butterworth Q 0.541 and 1.307), as causal IIR
/// filters (bilinear transform), behind `latency` samples of pure delay.
fn actuator_ir(len: usize, latency: usize) -> Vec<f64> {
    let mut x = vec![0.0; len];
    x[latency] = 1.0;
    let sections = [Biquad::new(70.0, 2.0, true), Biquad::new(350.0, 0.541, false), Biquad::new(350.0, 1.307, false)];
    sections.iter().fold(x, |acc, s| s.filter(&acc))
}

/// Magnitude in dB of `x` on the bins of a length-`n` DFT, with the bins' frequencies.
fn magnitude_db(x: &[f64], n: usize) -> Vec<(f64, f64)> {
    fft::forward(x, n)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, c)| (fft::bin_freq_hz(k, n, FS_HZ), 20.0 * c.norm().log10()))
        .collect()
}

/// The model actuator used throughout: 4096 samples (170 ms; the resonance's envelope has decayed by 160 dB), with
/// a 1 ms (24-sample) latency so the response is not minimum phase and the modelling delay has work to do.
fn model_actuator() -> Vec<f64> {
    actuator_ir(4096, 24)
}

/// Extremes of `|c * h|` in dB over `lo_hz..=hi_hz`, on a DFT four times longer than `c * h` (bins 4 times finer
/// than the signal's own resolution, so no dip between bins goes unseen).
fn band_extremes_db(y: &[f64], lo_hz: f64, hi_hz: f64) -> (f64, f64) {
    let n = fft::fast_len(4 * y.len()).unwrap();
    magnitude_db(y, n)
        .iter()
        .filter(|(f, _)| (lo_hz..=hi_hz).contains(f))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, m)| (lo.min(m), hi.max(m)))
}

/// Largest `|H(f)| / (1 / (2 sqrt(beta_abs B(f))))` over the design bins, for the design spectrum and for the
/// spectrum of the final taps.
fn bound_ratios(c: &[f64], cfg: &KirkebyConfig, filter: &KirkebyFilter) -> (f64, f64) {
    let s = design_spectrum(c, cfg).unwrap();
    let taps = fft::forward(&filter.taps, s.fft_len).unwrap();
    let ratio = |h: &Complex64, r: f64| h.norm() * 2.0 * r.sqrt();
    let design = s.inverse.iter().zip(&s.regularisation).map(|(h, r)| ratio(h, *r)).fold(0.0, f64::max);
    let truncated = taps.iter().zip(&s.regularisation).map(|(h, r)| ratio(h, *r)).fold(0.0, f64::max);
    (design, truncated)
}

/// Energy of `y[..end]` over the energy of `y`, dB.
fn energy_before_db(y: &[f64], end: usize) -> f64 {
    let total: f64 = y.iter().map(|v| v * v).sum();
    let early: f64 = y[..end].iter().map(|v| v * v).sum();
    10.0 * (early / total).log10()
}

/// 5 ms at 24 kHz.
const FIVE_MS: usize = 120;

#[test]
fn model_actuator_spans_40_db_over_20_to_1000_hz() {
    // The brief asks for a response with 40 dB of dynamic range over 20..1000 Hz; this checks the model has it
    // (measured 42.9 dB: +6.3 dB at the resonance, -36.6 dB at 1 kHz).
    let mag = magnitude_db(&model_actuator(), 1 << 16);
    let (lo, hi) = mag
        .iter()
        .filter(|(f, _)| (20.0..=1000.0).contains(f))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, m)| (lo.min(m), hi.max(m)));
    assert!(hi - lo >= 40.0, "dynamic range {} dB", hi - lo);
}

#[test]
fn default_design_flattens_the_band_within_half_a_db() {
    let c = model_actuator();
    let cfg = KirkebyConfig::calibration_default();
    let filter = design(&c, &cfg).unwrap();
    assert_eq!(filter.taps.len(), cfg.fir_len);
    let y = filter.apply(&c).unwrap();
    assert_eq!(y.len(), c.len() + cfg.fir_len - 1);
    // +/-0.5 dB is the requirement; measured -0.05..+0.03 dB (regularisation costs 0.02 dB at 625 Hz, where the
    // response is 26 dB below its peak; truncation to 8192 taps the rest).
    let (lo, hi) = band_extremes_db(&y, 50.0, 625.0);
    assert!(lo > -0.5 && hi < 0.5, "in-band {lo} .. {hi} dB");
    // The filter's boost covers the response's in-band dynamic range (26.4 dB from the resonance peak down to
    // 625 Hz); anything far above would mean it also boosts outside the band. 1 dB covers truncation ripple.
    assert!(filter.max_boost_db > 25.0 && filter.max_boost_db < 27.5, "boost {} dB", filter.max_boost_db);
}

#[test]
fn gain_is_bounded_by_the_regularisation() {
    let c = model_actuator();
    let cfg = KirkebyConfig::calibration_default();
    let filter = design(&c, &cfg).unwrap();
    let (design_ratio, taps_ratio) = bound_ratios(&c, &cfg, &filter);
    // Design spectrum: the bound is exact algebra (|C| / (|C|^2 + r) <= 1 / (2 sqrt r)); 1e-12 is rounding.
    assert!(design_ratio <= 1.0 + 1e-12, "design spectrum exceeds the bound by {design_ratio}");
    // Final taps: truncation to fir_len and the fades ripple |H| by about as much as the in-band flatness error
    // (0.05 dB = 0.6 %); 2 % (0.17 dB) gives three times that. Measured: 0.99999.
    assert!(taps_ratio <= 1.02, "taps exceed the bound by {taps_ratio}");
}

#[test]
fn no_energy_more_than_5_ms_before_the_modelling_delay() {
    let c = model_actuator();
    let cfg = KirkebyConfig::calibration_default();
    let y = design(&c, &cfg).unwrap().apply(&c).unwrap();
    // Requirement -60 dB; measured -79 dB (the minimum-phase target leaves only truncation and cepstral residue).
    let pre_db = energy_before_db(&y, cfg.modelling_delay_samples - FIVE_MS);
    assert!(pre_db < -60.0, "energy before the delay: {pre_db} dB");
}

#[test]
fn linear_target_is_zero_phase_and_so_rings_before_the_delay() {
    // Textbook Kirkeby (pure-delay target) with room on both sides: c * h is the zero-phase R(f) delayed, i.e.
    // symmetric about the delay, and its 50 Hz band edge rings for tens of milliseconds before it. This is why the
    // default target is minimum phase.
    let c = model_actuator();
    let cfg = KirkebyConfig {
        target: TargetPhase::Linear,
        fir_len: 16_384,
        modelling_delay_samples: 8192,
        ..KirkebyConfig::calibration_default()
    };
    let y = design(&c, &cfg).unwrap().apply(&c).unwrap();
    let d = cfg.modelling_delay_samples;
    let peak = y.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    // Symmetric to truncation error: the filter's tails are cut 340 ms from the delay, where the ringing has
    // decayed (measured asymmetry 5e-6 of the peak; 1e-4 leaves a factor 20).
    let asym = (1..d).map(|m| (y[d + m] - y[d - m]).abs()).fold(0.0, f64::max) / peak;
    assert!(asym < 1e-4, "asymmetry {asym} of the peak");
    // Measured -18.5 dB; anything above -30 dB shows the ringing the minimum-phase target removes.
    let pre_db = energy_before_db(&y, d - FIVE_MS);
    assert!(pre_db > -30.0, "pre-ringing energy {pre_db} dB: expected the band edge's ringing to show");
    let (lo, hi) = band_extremes_db(&y, 50.0, 625.0);
    assert!(lo > -0.5 && hi < 0.5, "in-band {lo} .. {hi} dB");
}

#[test]
fn tiny_beta_approaches_the_exact_inverse_in_band() {
    let c = model_actuator();
    for target in [TargetPhase::Linear, TargetPhase::Minimum] {
        let cfg = KirkebyConfig { beta: 1e-12, target, ..KirkebyConfig::calibration_default() };
        let s = design_spectrum(&c, &cfg).unwrap();
        let fs = cfg.sample_rate_hz;
        let d = cfg.modelling_delay_samples as f64;
        for (k, (cv, h)) in s.response.iter().zip(&s.inverse).enumerate() {
            let f = fft::bin_freq_hz(k, s.fft_len, fs);
            if (50.0..=625.0).contains(&f) {
                // In band beta_abs B / |C|^2 <= 1e-12 / 2.3e-3 (the response's weakest in-band power relative to its
                // peak): C H differs from the target by less than 1e-9; 1e-6 leaves room for rounding.
                let achieved = cv * h;
                let err = match target {
                    TargetPhase::Linear => (achieved * Complex64::from_polar(1.0, 2.0 * PI * f * d / fs) - 1.0).norm(),
                    TargetPhase::Minimum => (achieved.norm() - 1.0).abs(),
                };
                assert!(err < 1e-6, "{target:?} at {f} Hz: error {err}");
            }
        }
        let filter = design(&c, &cfg).unwrap();
        assert!(filter.taps.iter().all(|t| t.is_finite()));
        // Out of band the filter may now boost up to 1 / (2 sqrt(1e-12 * 1e5)) = 1581 times (64 dB) the gain that
        // flattens the peak; 1 dB over that covers truncation.
        assert!(filter.max_boost_db.is_finite() && filter.max_boost_db < 65.0, "boost {}", filter.max_boost_db);
    }
}

#[test]
fn huge_beta_tends_to_the_scaled_matched_filter() {
    let c = model_actuator();
    let cfg = KirkebyConfig { beta: 1e6, target: TargetPhase::Linear, ..KirkebyConfig::calibration_default() };
    let s = design_spectrum(&c, &cfg).unwrap();
    let fs = cfg.sample_rate_hz;
    let d = cfg.modelling_delay_samples as f64;
    for (k, ((cv, h), r)) in s.response.iter().zip(&s.inverse).zip(&s.regularisation).enumerate() {
        if cv.norm() == 0.0 {
            continue;
        }
        // H r / C* = D r / (|C|^2 + r): off from the delay D by |C|^2 / r <= 1 / (1e6 B) <= 1e-6.
        let f = fft::bin_freq_hz(k, s.fft_len, fs);
        let delay = Complex64::from_polar(1.0, -2.0 * PI * f * d / fs);
        let err = (h * r / cv.conj() - delay).norm();
        assert!(err <= 1.0001e-6, "at {f} Hz: {err}");
    }
    // Default (minimum-phase) target: finite and tiny. In this limit |H| ~ |C| / (beta_abs B) <= 1e-6 / max|C|
    // (B >= in_band = 1), a boost of at most -120 dB (measured -120.003 dB); 0.5 dB covers truncation ripple.
    let filter = design(&c, &KirkebyConfig { beta: 1e6, ..KirkebyConfig::calibration_default() }).unwrap();
    assert!(filter.taps.iter().all(|t| t.is_finite()));
    assert!(filter.max_boost_db < -119.5, "boost {}", filter.max_boost_db);
}

#[test]
fn zero_beta_inverts_a_minimum_phase_response_exactly() {
    // 1 + 0.5 z^-1 has no spectral zero; its exact inverse is the causal sum of (-0.5)^n. Both targets agree
    // (R = 1 is its own minimum-phase version). The tail fade covers the last 8 of 32 taps; the first 24 must
    // match to FFT rounding (1e-12), as the inverse's wrap-around at 1024 bins is 0.5^1024.
    for target in [TargetPhase::Linear, TargetPhase::Minimum] {
        let cfg = KirkebyConfig {
            fir_len: 32,
            modelling_delay_samples: 0,
            beta: 0.0,
            target,
            fft_len: Some(1024),
            ..KirkebyConfig::calibration_default()
        };
        let filter = design(&[1.0, 0.5], &cfg).unwrap();
        for (n, t) in filter.taps.iter().take(24).enumerate() {
            assert!((t - (-0.5f64).powi(n as i32)).abs() < 1e-12, "{target:?} tap {n}: {t}");
        }
    }
    // With an exact spectral zero (1 + z^-1 at Nyquist) and no regularisation the inverse is 0 / 0: refused.
    let cfg = KirkebyConfig {
        fir_len: 32,
        modelling_delay_samples: 0,
        beta: 0.0,
        fft_len: Some(1024),
        ..KirkebyConfig::calibration_default()
    };
    assert!(matches!(design(&[1.0, 1.0], &cfg), Err(DspError::NonFiniteResult { .. })));
}

#[test]
fn band_edges_at_zero_hz_and_at_nyquist() {
    let c = model_actuator();
    let bands = [
        BandLimit::new(0.0, 12_000.0, 0.0, 0.0).unwrap(),
        BandLimit::new(0.0, 625.0, 0.0, 200.0).unwrap(),
        BandLimit::new(50.0, 12_000.0, 25.0, 0.0).unwrap(),
    ];
    for band in bands {
        let mut cfg = KirkebyConfig::calibration_default();
        cfg.profile.band = band;
        let filter = design(&c, &cfg).unwrap();
        assert!(filter.taps.iter().all(|t| t.is_finite()) && filter.max_boost_db.is_finite());
        let (design_ratio, _) = bound_ratios(&c, &cfg, &filter);
        assert!(design_ratio <= 1.0 + 1e-12, "{band:?}: {design_ratio}");
        // The calibration band lies inside each of these bands, so it is still flattened (same budget as the
        // default design; measured within -0.14..+0.07 dB, the widest when the regularisation stays low near DC).
        let (lo, hi) = band_extremes_db(&filter.apply(&c).unwrap(), 50.0, 625.0);
        assert!(lo > -0.5 && hi < 0.5, "{band:?}: in-band {lo} .. {hi} dB");
    }
}

#[test]
fn fir_len_extremes() {
    let c = model_actuator();
    // One tap (the delay must then be 0): the first sample of the untruncated design, no fade applied.
    let cfg = KirkebyConfig { fir_len: 1, modelling_delay_samples: 0, ..KirkebyConfig::calibration_default() };
    let filter = design(&c, &cfg).unwrap();
    let s = design_spectrum(&c, &cfg).unwrap();
    let full = fft::inverse(&s.inverse, s.fft_len).unwrap();
    assert_eq!(filter.taps, vec![full[0]]);
    assert!(filter.max_boost_db.is_finite());
    // Longer than the design FFT: refused, not silently truncated.
    let cfg = KirkebyConfig { fft_len: Some(4096), ..KirkebyConfig::calibration_default() };
    assert!(matches!(design(&c, &cfg), Err(DspError::InvalidParameter { name: "fft_len", .. })));
    // A design FFT shorter than the response would truncate the response: refused too.
    let cfg = KirkebyConfig { fir_len: 1024, fft_len: Some(2048), ..KirkebyConfig::calibration_default() };
    assert!(matches!(design(&c, &cfg), Err(DspError::InvalidParameter { name: "fft_len", .. })));
    // The default design FFT is 4 times the taps, 7-smooth.
    let s = design_spectrum(&c, &KirkebyConfig::calibration_default()).unwrap();
    assert_eq!(s.fft_len, 32_768);
}

#[test]
fn response_delay_is_removed_before_the_design() {
    let c = model_actuator();
    let cfg = KirkebyConfig::calibration_default();
    let causal = design(&c, &cfg).unwrap();
    let peak = causal.taps.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    // The same response behind 1000 zeros, declared as its time 0: the same design FFT (32768 points), whose
    // circular rotation puts the zeros at negative time, so the same filter to rounding (1e-12 of the peak tap).
    for delay in [1000, 4095] {
        let mut delayed = vec![0.0; delay];
        delayed.extend_from_slice(&c[..c.len().min(8192 - delay)]);
        let filter = design(&delayed, &KirkebyConfig { response_delay_samples: delay, ..cfg }).unwrap();
        let err = filter.taps.iter().zip(&causal.taps).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-12 * peak, "delay {delay}: taps differ by {err:e} of {peak:e}");
    }
    // The delay must lie inside the response (its last sample is the largest valid one).
    assert!(design(&c, &KirkebyConfig { response_delay_samples: c.len() - 1, ..cfg }).is_ok());
    let bad = KirkebyConfig { response_delay_samples: c.len(), ..cfg };
    assert!(matches!(design(&c, &bad), Err(DspError::InvalidParameter { name: "response_delay_samples", .. })));
}

#[test]
fn calibration_recipe_takes_the_measurement_s_rate_and_pre_samples() {
    let deconv = DeconvConfig { sample_rate_hz: 48_000.0, ..DeconvConfig::calibration() };
    let cfg = KirkebyConfig::calibration(&deconv);
    assert_eq!((cfg.sample_rate_hz, cfg.response_delay_samples), (48_000.0, 2048));
    // Everything else is the calibration default, modelling delay included (the pre-samples are not added to it).
    let default = KirkebyConfig::calibration_default();
    assert_eq!(KirkebyConfig { sample_rate_hz: default.sample_rate_hz, response_delay_samples: 0, ..cfg }, default);
}

/// `c` through a zero-phase band limit (on a long grid, so nothing wraps), as a deconvolution returns it: `len`
/// samples from time `-pre` (the pre-ringing before time 0 first).
fn band_limited_window(c: &[f64], band: BandLimit, pre: usize, len: usize) -> Vec<f64> {
    let n = 1 << 17;
    let spectrum: Vec<Complex64> =
        fft::forward(c, n).unwrap().iter().zip(band.bin_gains(n, FS_HZ)).map(|(v, g)| v * g).collect();
    let mut y = fft::inverse(&spectrum, n).unwrap();
    y.rotate_right(pre);
    y.truncate(len);
    y
}

#[test]
fn a_two_sided_band_limited_response_is_flattened() {
    // The calibration measurement's band (DeconvConfig::calibration): the band limit rings before time 0.
    let band = BandLimit::new(50.0, 625.0, 20.0, 100.0).unwrap();
    let c = model_actuator();
    let pre = 2048;
    let measured = band_limited_window(&c, band, pre, 8192);
    let cfg = KirkebyConfig { response_delay_samples: pre, ..KirkebyConfig::calibration_default() };
    let y = design(&measured, &cfg).unwrap().apply(&c).unwrap();
    // The physical response through the filter, over the scan's band: the default design's budget (measured
    // -0.05 .. +0.04 dB).
    let (lo, hi) = band_extremes_db(&y, 62.0, 625.0);
    assert!(lo > -0.5 && hi < 0.5, "two-sided: in-band {lo} .. {hi} dB");
    // The causal cut of the same response loses the pre-ringing, which the design then inverts too: measured
    // -0.06 .. +0.75 dB, outside the budget (this actuator's onset is smoother than a voice coil's, whose causal
    // cut costs more, see tests/calibration.rs).
    let causal = band_limited_window(&c, band, 0, 8192);
    let y = design(&causal, &KirkebyConfig::calibration_default()).unwrap().apply(&c).unwrap();
    let (lo, hi) = band_extremes_db(&y, 62.0, 625.0);
    assert!(lo < -0.5 || hi > 0.5, "causal cut: in-band {lo} .. {hi} dB, within the budget after all");
}

#[test]
fn beta_is_relative_so_the_design_is_scale_free() {
    let c = model_actuator();
    let cfg = KirkebyConfig::calibration_default();
    let a = design(&c, &cfg).unwrap();
    let scaled: Vec<f64> = c.iter().map(|v| 1000.0 * v).collect();
    let b = design(&scaled, &cfg).unwrap();
    let peak = a.taps.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    // Every step is scale-covariant; only rounding (1e-12 of the peak tap) may differ.
    for (x, y) in a.taps.iter().zip(&b.taps) {
        assert!((x - 1000.0 * y).abs() < 1e-12 * peak);
    }
    assert!((a.max_boost_db - b.max_boost_db).abs() < 1e-9);
}

#[test]
fn refuses_bad_responses() {
    let cfg = KirkebyConfig::calibration_default();
    assert!(matches!(design(&[], &cfg), Err(DspError::Empty { .. })));
    assert!(matches!(design(&[0.0; 100], &cfg), Err(DspError::InvalidParameter { name: "response_ir", .. })));
    let mut c = model_actuator();
    c[10] = f64::NAN;
    assert!(matches!(design(&c, &cfg), Err(DspError::NonFinite { index: 10, .. })));
    c[10] = f64::INFINITY;
    assert!(matches!(design(&c, &cfg), Err(DspError::NonFinite { index: 10, .. })));
}

#[test]
fn refuses_bad_configurations() {
    let c = model_actuator();
    let base = KirkebyConfig::calibration_default();
    let mut bad: Vec<(KirkebyConfig, &str)> = vec![
        (KirkebyConfig { modelling_delay_samples: base.fir_len, ..base }, "modelling_delay_samples"),
        (KirkebyConfig { modelling_delay_samples: base.fir_len + 7, ..base }, "modelling_delay_samples"),
        (KirkebyConfig { fir_len: 0, modelling_delay_samples: 0, ..base }, "fir_len"),
        (KirkebyConfig { beta: -1e-6, ..base }, "beta"),
        (KirkebyConfig { beta: f64::NAN, ..base }, "beta"),
        (KirkebyConfig { beta: f64::INFINITY, ..base }, "beta"),
        (KirkebyConfig { sample_rate_hz: 0.0, ..base }, "sample_rate_hz"),
    ];
    bad.push((KirkebyConfig { response_delay_samples: c.len(), ..base }, "response_delay_samples"));
    let mut cfg = base;
    cfg.profile.in_band = -1.0;
    bad.push((cfg, "profile.in_band"));
    let mut cfg = base;
    cfg.profile.out_of_band = f64::NAN;
    bad.push((cfg, "profile.out_of_band"));
    let mut cfg = base;
    cfg.profile.band = BandLimit { lo_hz: 12_000.0, hi_hz: 13_000.0, lo_transition_hz: 0.0, hi_transition_hz: 0.0 };
    bad.push((cfg, "profile.band.lo_hz"));
    for (cfg, field) in bad {
        match design(&c, &cfg) {
            Err(DspError::InvalidParameter { name, .. }) => assert_eq!(name, field),
            other => panic!("{field}: expected InvalidParameter, got {other:?}"),
        }
    }
}

#[test]
fn apply_refuses_bad_signals() {
    let filter = design(&model_actuator(), &KirkebyConfig::calibration_default()).unwrap();
    assert!(matches!(filter.apply(&[]), Err(DspError::Empty { .. })));
    assert!(matches!(filter.apply(&[0.0, f64::NAN]), Err(DspError::NonFinite { .. })));
}

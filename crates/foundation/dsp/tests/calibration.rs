//! End-to-end actuator calibration: measure a voice-coil-like actuator with the calibration sweep, deconvolve, design
//! the Kirkeby inverse, and verify the compensated response with a second measurement through the filter.
//!
//! The verification is the full-length spectral ratio `FFT(y) / FFT(sweep)` of the actuator's output `y` for the
//! compensated sweep: no window, no truncation, so it is exactly `C(f) H(f)` for the linear part and judges the
//! filter alone, not a second deconvolution.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use std::f64::consts::PI;

use metaplate_dsp::deconv::{DeconvConfig, deconvolve};
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::{KirkebyConfig, KirkebyFilter, design};
use metaplate_dsp::sweep::SweepSpec;
use num_complex::Complex64;

const FS_HZ: f64 = 24_000.0;

/// The scan's band, where the compensated response must be flat, Hz.
const SCAN_BAND_HZ: (f64, f64) = (62.0, 625.0);

/// The requirement: compensated response within +/-1 dB of its median over the scan's band.
const REQUIRED_DB: f64 = 1.0;

/// A voice coil (the Hammerstein model of the mock hardware, rebuilt here since dsp cannot depend on it): a static
/// cubic `u + cubic u^3`, then a 2nd-order high-pass at the 70 Hz suspension resonance (Q 2) and a 1st-order
/// low-pass at 400 Hz, both bilinear transforms prewarped at their corners. Unit gain in the pass band.
struct VoiceCoil {
    /// High-pass biquad `[b0, b1, b2, a1, a2]` (a0 normalised to 1).
    high_pass: [f64; 5],
    /// Low-pass first-order section `[b0, b1, a1]`.
    low_pass: [f64; 3],
    cubic: f64,
}

impl VoiceCoil {
    fn new(cubic: f64) -> Self {
        let w0 = 2.0 * PI * 70.0 / FS_HZ;
        let (c, alpha) = (w0.cos(), w0.sin() / (2.0 * 2.0));
        let a0 = 1.0 + alpha;
        let high_pass =
            [(1.0 + c) / 2.0 / a0, -(1.0 + c) / a0, (1.0 + c) / 2.0 / a0, -2.0 * c / a0, (1.0 - alpha) / a0];
        let t = (PI * 400.0 / FS_HZ).tan();
        Self { high_pass, low_pass: [t / (1.0 + t), t / (1.0 + t), (t - 1.0) / (1.0 + t)], cubic }
    }

    /// Output for the drive `u`, sample by sample from rest.
    fn drive(&self, u: &[f64]) -> Vec<f64> {
        let [b0, b1, b2, a1, a2] = self.high_pass;
        let [c0, c1, d1] = self.low_pass;
        let (mut x1, mut x2, mut y1, mut y2, mut h1, mut l1) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        u.iter()
            .map(|&u| {
                let x = u + self.cubic * u * u * u;
                let y = b0 * x + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
                (x2, x1, y2, y1) = (x1, x, y1, y);
                let l = c0 * y + c1 * h1 - d1 * l1;
                (h1, l1) = (y, l);
                l
            })
            .collect()
    }

    /// Exact frequency response of the linear part at `f_hz`.
    fn response(&self, f_hz: f64) -> Complex64 {
        let z1 = Complex64::from_polar(1.0, -2.0 * PI * f_hz / FS_HZ);
        let [b0, b1, b2, a1, a2] = self.high_pass;
        let [c0, c1, d1] = self.low_pass;
        (b0 + b1 * z1 + b2 * z1 * z1) / (1.0 + a1 * z1 + a2 * z1 * z1) * (c0 + c1 * z1) / (1.0 + d1 * z1)
    }
}

/// The calibration sweep: 3 s linear, 50..625 Hz at 24 kHz, amplitude 0.5, default (5 ms) fades.
fn calibration_sweep() -> Vec<f64> {
    SweepSpec { f1_hz: 50.0, amplitude: 0.5, ..SweepSpec::default() }.generate().unwrap()
}

/// `x` followed by `tail` zeros, so the actuator's response rings out inside the recording.
fn with_tail(x: &[f64], tail: usize) -> Vec<f64> {
    let mut padded = x.to_vec();
    padded.resize(x.len() + tail, 0.0);
    padded
}

/// The measured impulse response: the sweep and `ir_len` samples of tail through the coil, deconvolved.
fn measure(coil: &VoiceCoil, sweep: &[f64], deconv: &DeconvConfig) -> Vec<f64> {
    deconvolve(&coil.drive(&with_tail(sweep, deconv.ir_len)), sweep, deconv).unwrap()
}

/// The compensated response `FFT(y) / FFT(sweep)` in dB relative to its median, at every bin of the scan's band,
/// with the bins' frequencies. `y` is the coil's output for the filtered sweep plus 0.5 s of silence (the
/// suspension's 9 ms time constant has decayed by e^-55 by then), and the FFT holds all of it.
fn compensated_levels_db(coil: &VoiceCoil, sweep: &[f64], filter: &KirkebyFilter) -> Vec<(f64, f64)> {
    let y = coil.drive(&with_tail(&filter.apply(sweep).unwrap(), FS_HZ as usize / 2));
    let n = fft::fast_len(y.len()).unwrap();
    let (ys, xs) = (fft::forward(&y, n).unwrap(), fft::forward(sweep, n).unwrap());
    let levels: Vec<(f64, f64)> = (0..ys.len())
        .map(|k| (fft::bin_freq_hz(k, n, FS_HZ), 20.0 * (ys[k] / xs[k]).norm().log10()))
        .filter(|(f, _)| (SCAN_BAND_HZ.0..=SCAN_BAND_HZ.1).contains(f))
        .collect();
    let mut sorted: Vec<f64> = levels.iter().map(|&(_, l)| l).collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    levels.into_iter().map(|(f, l)| (f, l - median)).collect()
}

/// Lowest and highest of the levels, dB.
fn extremes_db(levels: &[(f64, f64)]) -> (f64, f64) {
    levels.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, l)| (lo.min(l), hi.max(l)))
}

/// The whole calibration with `deconv` and the matching Kirkeby recipe; returns the compensated levels.
fn calibrate(coil: &VoiceCoil, deconv: &DeconvConfig, kirkeby: &KirkebyConfig) -> Vec<(f64, f64)> {
    let sweep = calibration_sweep();
    let filter = design(&measure(coil, &sweep, deconv), kirkeby).unwrap();
    compensated_levels_db(coil, &sweep, &filter)
}

/// The recipe's configurations, or the same with the causal cut (`pre_samples` 0) the fix replaces.
fn recipe(pre_samples: usize) -> (DeconvConfig, KirkebyConfig) {
    let deconv = DeconvConfig { pre_samples, ..DeconvConfig::calibration() };
    (deconv, KirkebyConfig::calibration(&deconv))
}

/// Worst deviation, dB, of the measured response's magnitude (about its time 0, on a 2^16-point grid) from the
/// coil's exact linear response over the scan's band.
fn measurement_error_db(coil: &VoiceCoil, deconv: &DeconvConfig) -> f64 {
    let ir = measure(coil, &calibration_sweep(), deconv);
    let n = 1 << 16;
    let mut centred = with_tail(&ir, n - ir.len());
    centred.rotate_left(deconv.pre_samples);
    let spectrum = fft::forward(&centred, n).unwrap();
    spectrum
        .iter()
        .enumerate()
        .map(|(k, c)| (fft::bin_freq_hz(k, n, FS_HZ), c))
        .filter(|(f, _)| (SCAN_BAND_HZ.0..=SCAN_BAND_HZ.1).contains(f))
        .map(|(f, c)| (20.0 * (c.norm() / coil.response(f).norm()).log10()).abs())
        .fold(0.0, f64::max)
}

/// The cubic of the mock hardware's coils, 0.01: at the sweep's amplitude 0.5 it raises the gain by
/// `3/4 * 0.01 * 0.5^2` = 0.19 % (0.016 dB) and makes a third harmonic 70 dB down.
const CUBIC: f64 = 0.01;

#[test]
fn two_sided_measurement_matches_the_coil_and_a_causal_cut_does_not() {
    let coil = VoiceCoil::new(CUBIC);
    // Two-sided (the recipe): measured 0.019 dB, the cubic's 0.016 dB gain change plus 0.005 dB left by the
    // regularisation bias (< 0.005 dB) and the band limit's ringing beyond the 2048 pre-samples. 0.1 dB is 5 times
    // that and still 10 times below the causal cut's error.
    let two_sided = measurement_error_db(&coil, &recipe(DeconvConfig::calibration().pre_samples).0);
    assert!(two_sided < 0.1, "two-sided measurement off the coil by {two_sided} dB");
    // Causal cut: the band-limited onset's negative-time part is lost, a broad in-band error (measured 1.39 dB,
    // the worst at the band edges). Above 1 dB shows the mechanism behind the failed calibration below.
    let causal = measurement_error_db(&coil, &recipe(0).0);
    assert!(causal > 1.0, "causal cut off the coil by only {causal} dB: the two-sided fix would be moot");
}

#[test]
fn calibration_recipe_flattens_the_scan_band() {
    let coil = VoiceCoil::new(CUBIC);
    let (deconv, kirkeby) = recipe(DeconvConfig::calibration().pre_samples);
    let (lo, hi) = extremes_db(&calibrate(&coil, &deconv, &kirkeby));
    // The requirement.
    assert!(lo > -REQUIRED_DB && hi < REQUIRED_DB, "compensated response {lo:+.3} .. {hi:+.3} dB");
    // Measured -0.042 .. +0.030 dB (-0.019 .. +0.038 without the cubic). Budget: the measurement's 0.02 dB (test
    // above); the cubic on the compensated drive, whose amplitude 0.5 / |C| runs from 0.25 at the resonance to
    // 0.93 at 625 Hz, so its gain change varies by 3/4 * 0.01 * (0.93^2 - 0.25^2) = 0.6 % (0.05 dB); the Kirkeby
    // design's truncation to 8192 taps and its regularisation, 0.05 dB (see tests/kirkeby.rs): 0.12 dB in all.
    // +/-0.2 dB keeps a regression well inside the requirement visible.
    assert!(lo > -0.2 && hi < 0.2, "compensated response {lo:+.3} .. {hi:+.3} dB, beyond the 0.2 dB budget");
}

#[test]
fn calibration_from_a_causal_cut_fails_the_requirement() {
    // The same measurement and design with pre_samples 0 (the behaviour before the fix): the compensated response
    // tilts by the measurement's error, measured -1.38 .. +0.14 dB (-1.35 .. +0.15 without the cubic; other causal
    // set-ups, ir_len 4096 or 16384, with or without a band limit, gave -1.35 to -1.59 dB at worst). Below -1 dB is
    // the requirement failed.
    let coil = VoiceCoil::new(CUBIC);
    let (deconv, kirkeby) = recipe(0);
    let (lo, hi) = extremes_db(&calibrate(&coil, &deconv, &kirkeby));
    assert!(lo < -REQUIRED_DB || hi > REQUIRED_DB, "causal cut passes: {lo:+.3} .. {hi:+.3} dB");
}

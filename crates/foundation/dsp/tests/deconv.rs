//! Deconvolution: round trips with noise against an error predicted from the noise level, reference and periodic
//! modes, harmonic separation, and every parameter at its extremes.
#![allow(clippy::unwrap_used)] // tests may unwrap: a failure is the test failing

use metaplate_core::rng::SplitMix64;
use metaplate_dsp::DspError;
use metaplate_dsp::band::BandLimit;
use metaplate_dsp::conv::convolve;
use metaplate_dsp::deconv::{
    DeconvConfig, deconvolve, deconvolve_periodic, deconvolve_with_reference, separate_harmonics,
};
use metaplate_dsp::fft;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use num_complex::Complex64;
use proptest::prelude::*;

const FS: f64 = 24_000.0;
const TAU: f64 = std::f64::consts::TAU;

fn gaussian(len: usize, sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed, 0);
    (0..len).map(|_| sigma * rng.normal()).collect()
}

/// White Gaussian samples under an exponential envelope `exp(-t / tau_s)`.
fn random_decaying_ir(len: usize, tau_s: f64, seed: u64) -> Vec<f64> {
    gaussian(len, 1.0, seed).iter().enumerate().map(|(i, z)| z * (-(i as f64) / FS / tau_s).exp()).collect()
}

/// Two damped modes, 180 Hz (tau 40 ms) and 430 Hz (tau 25 ms): decayed by e^-12 within 0.5 s.
fn two_mode_resonator(len: usize) -> Vec<f64> {
    (0..len)
        .map(|i| {
            let t = i as f64 / FS;
            (-t / 0.04).exp() * (TAU * 180.0 * t).sin() + 0.6 * (-t / 0.025).exp() * (TAU * 430.0 * t).sin()
        })
        .collect()
}

fn paper_sweep(kind: SweepKind) -> SweepSpec {
    SweepSpec { kind, ..SweepSpec::default() }
}

/// The truth as a perfect deconvolution would return it: `h` through the band's gains, `ir_len` samples from time
/// `-pre_samples` (the band limit's ringing before time 0 wraps to the end of the grid, from where it is taken).
/// Computed on a grid 8 times longer than the estimator's, so that the two share no sampling artefacts.
fn band_limited(h: &[f64], cfg: &DeconvConfig) -> Vec<f64> {
    let n = fft::fast_len(8 * h.len().max(cfg.ir_len)).unwrap();
    let mut spectrum = fft::forward(h, n).unwrap();
    if let Some(band) = cfg.band {
        for (c, g) in spectrum.iter_mut().zip(band.bin_gains(n, cfg.sample_rate_hz)) {
            *c *= g;
        }
    }
    let mut y = fft::inverse(&spectrum, n).unwrap();
    y.rotate_right(cfg.pre_samples);
    y.truncate(cfg.ir_len);
    y
}

fn diff(a: &[f64], b: &[f64]) -> Vec<f64> {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn energy(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

fn db(ratio: f64) -> f64 {
    10.0 * ratio.log10()
}

/// Energy of `x` between `lo_hz` and `hi_hz` (Parseval over the positive bins of its own-length FFT, doubled).
fn in_band_energy(x: &[f64], lo_hz: f64, hi_hz: f64) -> f64 {
    let m = x.len();
    let spectrum = fft::forward(x, m).unwrap();
    let sum: f64 = spectrum
        .iter()
        .enumerate()
        .filter(|(k, _)| (lo_hz..=hi_hz).contains(&fft::bin_freq_hz(*k, m, FS)))
        .map(|(_, c)| c.norm_sqr())
        .sum();
    2.0 * sum / m as f64
}

/// In-band error energy of `estimate` against `truth`, relative to the truth's in-band energy, dB.
fn in_band_error_db(estimate: &[f64], truth: &[f64], lo_hz: f64, hi_hz: f64) -> f64 {
    db(in_band_energy(&diff(estimate, truth), lo_hz, hi_hz) / in_band_energy(truth, lo_hz, hi_hz))
}

/// What the theory predicts for deconvolving by `x` with `cfg` over `[lo_hz, hi_hz]`:
/// - the expected in-band error energy of the first `ir_len` samples for white noise of standard deviation `sigma`
///   in the recording. The deconvolved noise is `n` filtered by `G = conj(X) / (|X|^2 + eps)`, stationary over the
///   returned samples (the recording's noise covers the whole support of the inverse filter), so an `M`-point FFT
///   of it has `E|E(f)|^2 = M sigma^2 |G(f)|^2`, and the in-band energy `2/M sum |E|^2` is `2 sigma^2 sum |G(f_k)|^2`
///   over the in-band bins of the `M` grid, a Riemann sum evaluated here on a finer grid, scaled by `M / N`;
/// - the worst relative bias `eps / (|X|^2 + eps)` over the band (the regularisation's only in-band effect).
fn predicted_noise_energy_and_bias(x: &[f64], sigma: f64, cfg: &DeconvConfig, lo_hz: f64, hi_hz: f64) -> (f64, f64) {
    let n = fft::fast_len(x.len() + cfg.ir_len).unwrap();
    let spectrum = fft::forward(x, n).unwrap();
    let power: Vec<f64> = spectrum.iter().map(Complex64::norm_sqr).collect();
    let gains = cfg.band.map_or(vec![1.0; power.len()], |b| b.bin_gains(n, cfg.sample_rate_hz));
    let peak = power.iter().zip(&gains).filter(|(_, g)| **g > 0.0).map(|(p, _)| *p).fold(0.0, f64::max);
    let eps = cfg.regularisation * peak;
    let (mut sum_g2, mut bias) = (0.0, 0.0f64);
    for (k, p) in power.iter().enumerate() {
        if (lo_hz..=hi_hz).contains(&fft::bin_freq_hz(k, n, FS)) {
            sum_g2 += p / (p + eps).powi(2);
            bias = bias.max(eps / (p + eps));
        }
    }
    (2.0 * sigma * sigma * sum_g2 * cfg.ir_len as f64 / n as f64, bias)
}

/// Convolves `h` with the sweep, adds white noise at `snr_db` (the clean recording's mean power over the noise
/// power), deconvolves with `cfg`, and checks the in-band error against the prediction.
fn check_noisy_round_trip(h: &[f64], sweep: &SweepSpec, cfg: &DeconvConfig, snr_db: f64, seed: u64) {
    let x = sweep.generate().unwrap();
    let clean = convolve(&x, h).unwrap();
    let sigma = (energy(&clean) / clean.len() as f64 / 10f64.powf(snr_db / 10.0)).sqrt();
    let noise = gaussian(clean.len(), sigma, seed);
    let recording: Vec<f64> = clean.iter().zip(&noise).map(|(s, n)| s + n).collect();
    let estimate = deconvolve(&recording, &x, cfg).unwrap();
    let truth = band_limited(h, cfg);
    let band = cfg.band.unwrap();
    let (lo, hi) = (band.lo_hz, band.hi_hz);
    let err_db = in_band_error_db(&estimate, &truth, lo, hi);
    let (noise_energy, bias) = predicted_noise_energy_and_bias(&x, sigma, cfg, lo, hi);
    let truth_energy = in_band_energy(&truth, lo, hi);
    // The error energy sums about 2 * 563 Hz * 0.5 s = 563 independent Gaussian terms, so it scatters around its
    // expectation by sqrt(2 / 563) = 6 % (0.26 dB): +-1 dB is 4 standard deviations. The bias is deterministic and
    // adds at most bias^2 of the truth's energy (upper bound only).
    let lower_db = db(noise_energy / truth_energy) - 1.0;
    let upper_db = db((noise_energy + bias * bias * truth_energy) / truth_energy) + 1.0;
    assert!(
        (lower_db..=upper_db).contains(&err_db),
        "{:?} sweep: in-band error {err_db:.2} dB outside [{lower_db:.2}, {upper_db:.2}] dB",
        sweep.kind
    );
}

/// The exponential sweep's power falls by 10 dB across the band, so it needs a lower regularisation than the
/// paper's linear sweep (see `DeconvConfig::paper`); 1e-5 keeps its worst in-band bias near -65 dB.
fn exponential_cfg() -> DeconvConfig {
    DeconvConfig { regularisation: 1e-5, ..DeconvConfig::paper() }
}

#[test]
fn random_ir_through_the_paper_linear_sweep_with_noise() {
    let h = random_decaying_ir(12_000, 0.05, 1);
    check_noisy_round_trip(&h, &paper_sweep(SweepKind::Linear), &DeconvConfig::paper(), 20.0, 11);
}

#[test]
fn resonator_through_the_paper_linear_sweep_with_noise() {
    let h = two_mode_resonator(12_000);
    check_noisy_round_trip(&h, &paper_sweep(SweepKind::Linear), &DeconvConfig::paper(), 20.0, 12);
}

#[test]
fn random_ir_through_an_exponential_sweep_with_noise() {
    let h = random_decaying_ir(12_000, 0.05, 2);
    check_noisy_round_trip(&h, &paper_sweep(SweepKind::Exponential), &exponential_cfg(), 20.0, 13);
}

#[test]
fn resonator_through_an_exponential_sweep_with_noise() {
    let h = two_mode_resonator(12_000);
    check_noisy_round_trip(&h, &paper_sweep(SweepKind::Exponential), &exponential_cfg(), 30.0, 14);
}

/// Delays `x`, zero-padded to `len`, by `delay_samples` (fractional) with a circular FFT phase ramp.
fn delayed(x: &[f64], len: usize, delay_samples: f64) -> Vec<f64> {
    let spectrum: Vec<Complex64> = fft::forward(x, len)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, c)| c * Complex64::from_polar(1.0, -TAU * delay_samples * k as f64 / len as f64))
        .collect();
    fft::inverse(&spectrum, len).unwrap()
}

#[test]
fn reference_mode_cancels_a_fractional_latency() {
    let h = random_decaying_ir(12_000, 0.05, 3);
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let clean = convolve(&x, &h).unwrap();
    // One DAQ acquisition: both channels see the same 37.3-sample latency; 100 samples of margin keep the delayed
    // signals from wrapping around the window.
    let window = clean.len() + 100;
    let latency = 37.3;
    let response = delayed(&clean, window, latency);
    let reference = delayed(&x, window, latency);
    let cfg = DeconvConfig { regularisation: 1e-7, ..DeconvConfig::paper() };
    let truth = band_limited(&h, &cfg);
    let (lo, hi) = (62.0, 625.0);
    let estimate = deconvolve_with_reference(&response, &reference, &cfg).unwrap();
    let err_db = in_band_error_db(&estimate, &truth, lo, hi);
    // Noise-free, and the phase ramp delays both exactly alike, so what remains is the regularisation bias
    // (at most `bias` per bin, here about -124 dB).
    let (_, bias) = predicted_noise_energy_and_bias(&x, 0.0, &cfg, lo, hi);
    assert!(err_db <= 20.0 * bias.log10(), "error {err_db:.1} dB, bias bound {:.1} dB", 20.0 * bias.log10());
    // Without the reference the latency stays in: 37.3 samples is a full radian at 625 Hz.
    let plain_db = in_band_error_db(&deconvolve(&response, &x, &cfg).unwrap(), &truth, lo, hi);
    assert!(plain_db > -10.0, "plain deconvolution error {plain_db:.1} dB");
}

#[test]
fn periodic_mode_on_a_steady_state_period_equals_the_linear_result() {
    let h = random_decaying_ir(6_000, 0.02, 4);
    let sweep = SweepSpec { duration_s: 1.0, ..SweepSpec::default() };
    let period = sweep.generate().unwrap();
    let p = period.len();
    let repeated: Vec<f64> = period.iter().chain(&period).chain(&period).copied().collect();
    let response = convolve(&repeated, &h).unwrap();
    let cfg = DeconvConfig { ir_len: 6_000, ..DeconvConfig::paper() };
    // The second period is in steady state: h (0.25 s) is shorter than a period (1 s).
    let periodic = deconvolve_periodic(&response[p..2 * p], &period, &cfg).unwrap();
    let linear = deconvolve(&convolve(&period, &h).unwrap(), &period, &cfg).unwrap();
    // Both sample the same regularised, band-limited spectrum, on grids of 1 s and about 1.7 s, and differ only by
    // what wraps around the 1 s period: the band limit's ringing (brick-wall 1 / (pi B t) times the raised cosine's
    // 1 / (4 (W t)^2) for W = 20 Hz: about 1e-6 of the peak after 0.75 s, -120 dB) and the regularisation bias,
    // at most -44 dB (bound below) but spread over about a period, because |X|^2 ripples on a 1 / T scale; only
    // a little of it wraps differently (measured -103 dB). -90 dB keeps 13 dB of that margin and still catches a
    // misaligned period or a wrong FFT length, which cost tens of dB.
    let rel_db = db(energy(&diff(&periodic, &linear)) / energy(&linear));
    assert!(rel_db < -90.0, "periodic and linear differ by {rel_db:.1} dB");
    // And the pair is right, not merely alike: both within the paper regularisation's bias bound of the truth.
    let (_, bias) = predicted_noise_energy_and_bias(&period, 0.0, &cfg, 62.0, 625.0);
    let err_db = in_band_error_db(&periodic, &band_limited(&h, &cfg), 62.0, 625.0);
    assert!(err_db <= 20.0 * bias.log10(), "periodic error {err_db:.1} dB");
}

#[test]
fn pre_samples_return_the_band_limited_response_before_time_0() {
    // White noise under a decaying envelope starts abruptly: the band limit smears its onset into negative time.
    let h = random_decaying_ir(12_000, 0.05, 15);
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let recording = convolve(&x, &h).unwrap();
    // 100 ms before time 0: two periods of the 20 Hz skirt.
    let pre = 2_400;
    let cfg = DeconvConfig { regularisation: 1e-6, pre_samples: pre, ..DeconvConfig::paper() };
    let estimate = deconvolve(&recording, &x, &cfg).unwrap();
    assert_eq!(estimate.len(), cfg.ir_len);
    let truth = band_limited(&h, &cfg);
    // What is returned before time 0 is real content, not padding: measured -17.8 dB of the truth's energy.
    let negative_db = db(energy(&truth[..pre]) / energy(&truth));
    assert!(negative_db > -30.0, "negative-time energy {negative_db:.1} dB");
    // Noise-free: only the regularisation bias remains, as for the causal window (see the tests below).
    let (_, bias) = predicted_noise_energy_and_bias(&x, 0.0, &cfg, 62.0, 625.0);
    let err_db = in_band_error_db(&estimate, &truth, 62.0, 625.0);
    assert!(err_db <= 20.0 * bias.log10(), "error {err_db:.1} dB, bias bound {:.1} dB", 20.0 * bias.log10());
    // From time 0 on, the samples are the causal result's (FFT lengths differ by the pre-samples, so what wraps
    // around differs: the skirt's ringing after more than 3 s, about -130 dB, see exponential_cfg; measured -151 dB).
    let causal = deconvolve(&recording, &x, &DeconvConfig { pre_samples: 0, ..cfg }).unwrap();
    let rel_db = db(energy(&diff(&estimate[pre..], &causal[..cfg.ir_len - pre])) / energy(&causal));
    assert!(rel_db < -110.0, "causal part differs by {rel_db:.1} dB");
}

#[test]
fn pre_samples_at_their_extremes() {
    let x = gaussian(2_000, 1.0, 16);
    let h = [0.75, -0.5, 0.25];
    let recording = convolve(&x, &h).unwrap();
    // The largest valid pre_samples, ir_len - 1: time 0 is the last sample, all before it (exactly zero for an
    // exact deconvolution) is rounding.
    let cfg = DeconvConfig { sample_rate_hz: FS, ir_len: 4, band: None, regularisation: 0.0, pre_samples: 3 };
    let got = deconvolve(&recording, &x, &cfg).unwrap();
    let n = fft::fast_len(x.len() + 4 + 3).unwrap();
    let tol = ROUNDING_PER_CONDITION * condition_number(&x, n);
    assert!(got[..3].iter().all(|v| v.abs() < tol), "{got:?} (tolerance {tol:e})");
    assert!((got[3] - 0.75).abs() < tol, "{got:?} (tolerance {tol:e})");
    // pre_samples = ir_len would leave time 0 out: refused, in every mode.
    let bad = DeconvConfig { pre_samples: 4, ..cfg };
    let refused =
        |r: Result<Vec<f64>, DspError>| matches!(r, Err(DspError::InvalidParameter { name: "pre_samples", .. }));
    assert!(refused(deconvolve(&recording, &x, &bad)));
    assert!(refused(deconvolve_with_reference(&x, &x, &bad)));
    assert!(refused(deconvolve_periodic(&x, &x, &bad)));
}

#[test]
fn periodic_pre_samples_are_the_end_of_the_period() {
    let h = random_decaying_ir(6_000, 0.02, 17);
    let period = SweepSpec { duration_s: 1.0, ..SweepSpec::default() }.generate().unwrap();
    let p = period.len();
    let repeated: Vec<f64> = period.iter().chain(&period).copied().collect();
    let response = convolve(&repeated, &h).unwrap();
    let steady = &response[p..2 * p];
    // The whole circular result, then a window of it starting 1200 samples before time 0: the same FFT, so the
    // same samples exactly, rotated.
    let whole = deconvolve_periodic(steady, &period, &DeconvConfig { ir_len: p, ..DeconvConfig::paper() }).unwrap();
    for pre in [1_200, 5_999] {
        let cfg = DeconvConfig { ir_len: 6_000, pre_samples: pre, ..DeconvConfig::paper() };
        let got = deconvolve_periodic(steady, &period, &cfg).unwrap();
        assert_eq!(&got[..pre], &whole[p - pre..]);
        assert_eq!(&got[pre..], &whole[..6_000 - pre]);
    }
}

/// A memoryless polynomial `y = x + a2 x^2 + a3 x^3` followed by `filter`, driven by `sweep`.
fn hammerstein_recording(sweep: &SweepSpec, a2: f64, a3: f64, filter: &[f64]) -> Vec<f64> {
    let y: Vec<f64> = sweep.generate().unwrap().iter().map(|x| x + a2 * x * x + a3 * x * x * x).collect();
    convolve(&y, filter).unwrap()
}

#[test]
fn harmonics_of_a_polynomial_nonlinearity_come_back_at_the_predicted_levels() {
    let amplitude = 0.8;
    let (a2, a3) = (0.2, 0.1);
    let sweep = SweepSpec { amplitude, ..paper_sweep(SweepKind::Exponential) };
    let cfg = exponential_cfg();
    // For x = A sin: x^2 = A^2/2 (1 - cos 2phi) and x^3 = A^3/4 (3 sin phi - sin 3phi), so the fundamental at the
    // nonlinearity's output is A (1 + 3 a3 A^2 / 4), the 2nd harmonic a2 A^2 / 2, the 3rd a3 A^3 / 4.
    let c1 = 1.0 + 0.75 * a3 * amplitude * amplitude;
    let level2_db = 20.0 * (a2 * amplitude / 2.0 / c1).log10();
    let level3_db = 20.0 * (a3 * amplitude * amplitude / 4.0 / c1).log10();
    let total_db = db(10f64.powf(level2_db / 10.0) + 10f64.powf(level3_db / 10.0));
    for filter in [random_decaying_ir(12_000, 0.03, 5), two_mode_resonator(12_000)] {
        let recording = hammerstein_recording(&sweep, a2, a3, &filter);
        let r = separate_harmonics(&recording, &sweep, 3, &cfg).unwrap();
        assert_eq!(r.harmonics.len(), 2);
        assert!(r.harmonics.iter().all(|h| h.len() == cfg.ir_len));
        // Exact for this (Hammerstein) system but at the ends of each harmonic's range, which the measure skips by
        // two Fresnel widths; what ripple is left there was measured at 0.3 dB. 1 dB is three times that.
        let (m2, m3) = (r.harmonic_level_db[0], r.harmonic_level_db[1]);
        assert!((m2 - level2_db).abs() < 1.0, "2nd harmonic {m2:.2} dB, predicted {level2_db:.2} dB");
        assert!((m3 - level3_db).abs() < 1.0, "3rd harmonic {m3:.2} dB, predicted {level3_db:.2} dB");
        assert!((r.distortion_db - total_db).abs() < 1.0, "total {:.2} dB vs {total_db:.2} dB", r.distortion_db);
        // The linear response is c1 times the filter, but where the 5 ms fades make x^3's fundamental (env^3)
        // differ from c1 x (env): (3 a3 A^2 / 4 / c1)^2 = 2e-3 of the energy over 2 x 5 ms / 3 s of the sweep, times
        // about 0.3 for the fade shape: about -57 dB. -50 dB allows for the x^2 offset's edges besides.
        let truth: Vec<f64> = band_limited(&filter, &cfg).iter().map(|v| c1 * v).collect();
        let err_db = in_band_error_db(&r.linear, &truth, 62.0, 625.0);
        assert!(err_db < -50.0, "linear response error {err_db:.1} dB");
    }
}

#[test]
fn a_linear_system_shows_no_distortion() {
    let sweep = paper_sweep(SweepKind::Exponential);
    let cfg = exponential_cfg();
    let recording = hammerstein_recording(&sweep, 0.0, 0.0, &two_mode_resonator(12_000));
    let r = separate_harmonics(&recording, &sweep, 3, &cfg).unwrap();
    // Only the band limit's pre-ringing of the linear response reaches back into harmonic 2's window, which ends
    // 0.4 s before time 0: brick-wall ringing 1 / (pi B t) = 1.3e-3 times the raised cosine's 1 / (4 (W t)^2) = 4e-3
    // for W = 20 Hz, about 5e-6 of the peak (-105 dB); -80 dB allows for that estimate's constant and still fails
    // at once if a window is misplaced onto the linear response (0 dB).
    assert!(r.distortion_db < -80.0, "distortion {:.1} dB", r.distortion_db);
    assert!(r.harmonic_level_db.iter().all(|l| l.is_finite() && *l < -80.0), "{:?}", r.harmonic_level_db);
    // The linear part is what plain deconvolution gives; the two use different FFT lengths, so they differ by the
    // ringing wrapped around each, bounded as above.
    let plain = deconvolve(&recording, &sweep.generate().unwrap(), &cfg).unwrap();
    let rel_db = db(energy(&diff(&r.linear, &plain)) / energy(&plain));
    assert!(rel_db < -80.0, "linear response differs from deconvolve by {rel_db:.1} dB");
}

#[test]
fn harmonic_windows_start_pre_samples_before_each_arrival() {
    let sweep = SweepSpec { amplitude: 0.8, ..paper_sweep(SweepKind::Exponential) };
    let recording = hammerstein_recording(&sweep, 0.2, 0.1, &random_decaying_ir(12_000, 0.03, 18));
    let cfg = exponential_cfg();
    let pre = 1_200;
    let r0 = separate_harmonics(&recording, &sweep, 3, &cfg).unwrap();
    let r = separate_harmonics(&recording, &sweep, 3, &DeconvConfig { pre_samples: pre, ..cfg }).unwrap();
    // Every window is shifted alike: from its arrival on, the samples are those without pre-samples. The FFT
    // lengths differ by the pre-samples, so the ringing wrapped around each differs (-80 dB bound of
    // a_linear_system_shows_no_distortion; measured -134, -110 and -95 dB).
    let tail = cfg.ir_len - pre;
    for (got, want) in std::iter::once((&r.linear, &r0.linear)).chain(r.harmonics.iter().zip(&r0.harmonics)) {
        assert_eq!(got.len(), cfg.ir_len);
        let rel_db = db(energy(&diff(&got[pre..], &want[..tail])) / energy(want));
        assert!(rel_db < -80.0, "window differs by {rel_db:.1} dB");
    }
    // The levels move only by what the shifted windows gain and lose at their ends: each now holds its response's
    // band-limit pre-ringing (for such an abrupt response 1.7 % of its energy, see the test above), in the
    // harmonic's and the linear response's alike, and loses a decayed end (e^-13 at 0.4 s). Measured 0.067 dB
    // (k = 2) and 0.012 dB (k = 3); 0.2 dB is three times that, and a misplaced window moves a level by tens of dB.
    for (a, b) in r.harmonic_level_db.iter().zip(&r0.harmonic_level_db) {
        assert!((a - b).abs() < 0.2, "level {a:.3} dB vs {b:.3} dB");
    }
}

#[test]
fn harmonic_separation_refuses_what_it_cannot_do() {
    let sweep = paper_sweep(SweepKind::Exponential);
    let recording = hammerstein_recording(&sweep, 0.1, 0.0, &two_mode_resonator(2_000));
    let cfg = exponential_cfg();
    let invalid = |r: Result<_, DspError>| matches!(r, Err(DspError::InvalidParameter { .. }));
    // A linear sweep does not separate harmonics.
    assert!(invalid(separate_harmonics(&recording, &paper_sweep(SweepKind::Linear), 2, &cfg)));
    // Orders: at least 2; 11 x 62 Hz lies beyond 625 Hz.
    assert!(invalid(separate_harmonics(&recording, &sweep, 1, &cfg)));
    assert!(invalid(separate_harmonics(&recording, &sweep, 11, &cfg)));
    // Windows: L ln(4/3) = 0.37 s between harmonics 3 and 4 cannot hold 0.5 s; 0.3 s fits.
    assert!(invalid(separate_harmonics(&recording, &sweep, 4, &cfg)));
    assert!(separate_harmonics(&recording, &sweep, 4, &DeconvConfig { ir_len: 7_200, ..cfg }).is_ok());
    // Mismatched sample rates, a recording shorter than the sweep, and a silent recording (levels undefined).
    assert!(invalid(separate_harmonics(&recording, &sweep, 2, &DeconvConfig { sample_rate_hz: 48_000.0, ..cfg })));
    assert!(invalid(separate_harmonics(&recording[..1_000], &sweep, 2, &cfg)));
    assert!(invalid(separate_harmonics(&vec![0.0; recording.len()], &sweep, 2, &cfg)));
    let mut bad = recording.clone();
    bad[5] = f64::NAN;
    assert!(matches!(separate_harmonics(&bad, &sweep, 2, &cfg), Err(DspError::NonFinite { index: 5, .. })));
}

/// Rounding in an FFT deconvolution: about f64::EPSILON * log2(n), amplified by the condition number
/// max|X| / min|X| over the divided bins; 1e-13 covers 2^25-point FFTs with a factor 10 to spare.
const ROUNDING_PER_CONDITION: f64 = 1e-13;

fn condition_number(x: &[f64], n: usize) -> f64 {
    let mags: Vec<f64> = fft::forward(x, n).unwrap().iter().map(|c| c.norm()).collect();
    mags.iter().copied().fold(0.0, f64::max) / mags.iter().copied().fold(f64::INFINITY, f64::min)
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().map(|v| v.abs()).fold(0.0, f64::max)
}

#[test]
fn regularisation_zero_is_exact_in_band() {
    let h = random_decaying_ir(12_000, 0.05, 6);
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let cfg = DeconvConfig { regularisation: 0.0, ..DeconvConfig::paper() };
    let estimate = deconvolve(&convolve(&x, &h).unwrap(), &x, &cfg).unwrap();
    let err_db = in_band_error_db(&estimate, &band_limited(&h, &cfg), 62.0, 625.0);
    // No bias and no noise: rounding is far below; what remains is the 20 Hz skirt's ringing wrapped around the
    // estimator's 3.5 s grid, down to about (pi * 20 Hz * 3 s)^-3 = 2e-7 of its peak (-130 dB); -110 dB leaves 20 dB
    // for that estimate's constant.
    assert!(err_db < -110.0, "error {err_db:.1} dB");
}

#[test]
fn regularisation_zero_with_an_exact_spectral_zero_is_a_non_finite_result() {
    // [1, 0, -1, 0] has exact zeros at DC and Nyquist; without a band limit both are divided.
    let reference = [1.0, 0.0, -1.0, 0.0];
    let response = [1.0, 2.0, 3.0, 4.0];
    let cfg = DeconvConfig { sample_rate_hz: 4.0, ir_len: 4, band: None, regularisation: 0.0, pre_samples: 0 };
    assert!(matches!(deconvolve_periodic(&response, &reference, &cfg), Err(DspError::NonFiniteResult { .. })));
    // A regularisation of any size makes it finite.
    let h = deconvolve_periodic(&response, &reference, &DeconvConfig { regularisation: 1e-12, ..cfg }).unwrap();
    assert!(h.iter().all(|v| v.is_finite()));
}

#[test]
fn huge_regularisation_gives_a_finite_result_tending_to_zero() {
    let h = random_decaying_ir(12_000, 0.05, 7);
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let cfg = DeconvConfig { regularisation: 1e12, ..DeconvConfig::paper() };
    let estimate = deconvolve(&convolve(&x, &h).unwrap(), &x, &cfg).unwrap();
    assert!(estimate.iter().all(|v| v.is_finite()));
    // Every bin is scaled by |X|^2 / (|X|^2 + eps) <= 1 / (1 + 1e12) < 1e-12 of the band-limited truth, so its norm
    // is too; 10 % for the truth's energy outside the first ir_len samples (its band-limit pre-ringing).
    let ratio = (energy(&estimate) / energy(&band_limited(&h, &cfg))).sqrt();
    assert!(ratio < 1.1e-12, "norm ratio {ratio:e}");
    assert!(ratio > 0.0);
}

#[test]
fn band_edges_at_zero_hz_and_at_nyquist() {
    // White excitation: energy at every bin from 0 Hz to Nyquist.
    let x = gaussian(4_800, 1.0, 8);
    let h = random_decaying_ir(2_400, 0.01, 9);
    let recording = convolve(&x, &h).unwrap();
    let base = DeconvConfig { sample_rate_hz: FS, ir_len: 2_400, band: None, regularisation: 0.0, pre_samples: 0 };
    let n = fft::fast_len(x.len() + base.ir_len).unwrap();
    let tol = ROUNDING_PER_CONDITION * condition_number(&x, n) * max_abs(&h);
    // The full band, edge to edge without skirts, is no band limit at all.
    let full = BandLimit::new(0.0, FS / 2.0, 0.0, 0.0).unwrap();
    let with_full = deconvolve(&recording, &x, &DeconvConfig { band: Some(full), ..base }).unwrap();
    assert_eq!(with_full, deconvolve(&recording, &x, &base).unwrap());
    let err = max_abs(&diff(&with_full, &h));
    assert!(err < tol, "full band: error {err:e}, tolerance {tol:e}");
    // A band starting at 0 Hz and one ending at Nyquist, each with a 3 kHz skirt on its inner side only. Their
    // ringing, wrapped around 0.3 s grids, is down to (pi * 3 kHz * 0.1 s)^-3 = 1e-9 of the peak: that, not
    // rounding, sets the tolerance.
    for band in
        [BandLimit::new(0.0, 6_000.0, 0.0, 3_000.0).unwrap(), BandLimit::new(6_000.0, FS / 2.0, 3_000.0, 0.0).unwrap()]
    {
        let cfg = DeconvConfig { band: Some(band), ..base };
        let estimate = deconvolve(&recording, &x, &cfg).unwrap();
        let truth = band_limited(&h, &cfg);
        let err = max_abs(&diff(&estimate, &truth));
        assert!(err < tol + 1e-9 * max_abs(&truth), "{band:?}: error {err:e}");
    }
}

#[test]
fn a_sweep_shorter_than_the_impulse_response_is_exact_with_the_whole_tail_recorded() {
    // 0.1 s sweep, 0.5 s response (tau 50 ms: down by e^-10 at its end, so ir_len holds it all).
    let sweep = SweepSpec { duration_s: 0.1, ..SweepSpec::default() };
    let x = sweep.generate().unwrap();
    let h = random_decaying_ir(12_000, 0.05, 10);
    let cfg = DeconvConfig { regularisation: 1e-6, ..DeconvConfig::paper() };
    let truth = band_limited(&h, &cfg);
    let recording = convolve(&x, &h).unwrap();
    let (_, bias) = predicted_noise_energy_and_bias(&x, 0.0, &cfg, 62.0, 625.0);
    let bias_db = 20.0 * bias.log10();
    // Noise-free: only the regularisation bias remains; make sure that bound means something.
    assert!(bias_db < -90.0, "bias bound {bias_db:.1} dB");
    let err_db = in_band_error_db(&deconvolve(&recording, &x, &cfg).unwrap(), &truth, 62.0, 625.0);
    assert!(err_db <= bias_db, "error {err_db:.1} dB, bias bound {bias_db:.1} dB");
    // Recording only the first tenth of the tail is not enough: the test above could fail.
    let cut = &recording[..x.len() + 1_200];
    let cut_db = in_band_error_db(&deconvolve(cut, &x, &cfg).unwrap(), &truth, 62.0, 625.0);
    assert!(cut_db > -30.0, "cut recording error {cut_db:.1} dB");
}

#[test]
fn all_zero_and_constant_excitations_are_refused() {
    let recording = gaussian(1_000, 1.0, 11);
    let cfg = DeconvConfig { sample_rate_hz: FS, ir_len: 100, band: None, regularisation: 1e-3, pre_samples: 0 };
    let invalid = |r: Result<Vec<f64>, DspError>| matches!(r, Err(DspError::InvalidParameter { .. }));
    for excitation in [vec![0.0; 500], vec![0.25; 500], vec![0.0]] {
        assert!(invalid(deconvolve(&recording, &excitation, &cfg)), "{:?}", &excitation[..1]);
        assert!(invalid(deconvolve(&recording, &excitation, &DeconvConfig::paper())));
    }
    assert!(invalid(deconvolve_with_reference(&recording, &vec![-3.0; 1_000], &cfg)));
    assert!(invalid(deconvolve_periodic(&recording, &vec![0.0; 1_000], &cfg)));
    // A periodic constant is pure DC; with a band away from 0 Hz it has no energy in the band either.
    let banded = DeconvConfig { sample_rate_hz: FS, ..DeconvConfig::paper() };
    assert!(invalid(deconvolve_periodic(
        &recording[..1_000],
        &vec![1.0; 1_000],
        &DeconvConfig { ir_len: 500, ..banded }
    )));
    // A tone at fs / 4, far above the band and exact in f64, has no energy in it (only FFT rounding).
    let out_of_band: Vec<f64> = (0..24_000).map(|i| [0.0, 1.0, 0.0, -1.0][i % 4]).collect();
    let periodic = DeconvConfig { ir_len: 1_000, ..DeconvConfig::paper() };
    assert!(invalid(deconvolve_periodic(&out_of_band, &out_of_band, &periodic)));
    // A single sample is an impulse: a valid excitation, returning the recording itself.
    let h = deconvolve(&recording, &[1.0], &DeconvConfig { regularisation: 0.0, ..cfg }).unwrap();
    assert!(max_abs(&diff(&h, &recording[..100])) < 1e-12);
}

#[test]
fn all_zero_and_constant_recordings() {
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let cfg = DeconvConfig::paper();
    // Silence is a valid measurement (a nodal point): exactly zero, not an error.
    let zero = deconvolve(&vec![0.0; x.len() + 12_000], &x, &cfg).unwrap();
    assert!(zero.iter().all(|v| *v == 0.0));
    // A DC offset on the recording is out of band: finite, and small next to a unit response's. Its rectangle's
    // spectrum is at most 0.5 fs / (pi f) = 62 at 62 Hz, against the sweep's in-band |X| = sqrt(A^2 T fs^2 / (4 B))
    // = 876, so at most 0.07 of a unit response per bin at the lower band edge, falling as 1 / f above it: < 0.1.
    let offset = deconvolve(&vec![0.5; x.len() + 12_000], &x, &cfg).unwrap();
    assert!(offset.iter().all(|v| v.is_finite()));
    let unit = deconvolve(&convolve(&x, &[1.0]).unwrap(), &x, &cfg).unwrap();
    assert!(max_abs(&offset) < 0.1 * max_abs(&unit), "{} vs {}", max_abs(&offset), max_abs(&unit));
}

#[test]
fn nan_and_infinity_in_a_recording_are_refused() {
    let x = paper_sweep(SweepKind::Linear).generate().unwrap();
    let cfg = DeconvConfig::paper();
    for bad_value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut recording = vec![0.0; x.len() + 100];
        recording[42] = bad_value;
        let non_finite = |r: Result<Vec<f64>, DspError>| matches!(r, Err(DspError::NonFinite { index: 42, .. }));
        assert!(non_finite(deconvolve(&recording, &x, &cfg)));
        assert!(non_finite(deconvolve(&x, &recording[..x.len()], &cfg)));
        let reference = &recording[..x.len()];
        assert!(non_finite(deconvolve_with_reference(&x, reference, &cfg)));
        assert!(non_finite(deconvolve_with_reference(reference, &x, &cfg)));
        assert!(non_finite(deconvolve_periodic(reference, &x, &cfg)));
    }
    assert!(matches!(deconvolve(&[], &x, &cfg), Err(DspError::Empty { .. })));
    assert!(matches!(deconvolve(&x, &[], &cfg), Err(DspError::Empty { .. })));
}

#[test]
fn ir_len_one_returns_the_first_sample() {
    let x = gaussian(2_000, 1.0, 12);
    let h = [0.75, -0.5, 0.25];
    let cfg = DeconvConfig { sample_rate_hz: FS, ir_len: 1, band: None, regularisation: 0.0, pre_samples: 0 };
    let got = deconvolve(&convolve(&x, &h).unwrap(), &x, &cfg).unwrap();
    assert_eq!(got.len(), 1);
    let n = fft::fast_len(x.len() + 1).unwrap();
    let tol = ROUNDING_PER_CONDITION * condition_number(&x, n);
    assert!((got[0] - 0.75).abs() < tol, "{} (tolerance {tol:e})", got[0]);
    // Periodic mode at ir_len 1 too, where the period may be as short as one sample.
    let p = deconvolve_periodic(&[1.5], &[0.5], &cfg).unwrap();
    assert!((p[0] - 3.0).abs() < 1e-15);
}

#[test]
fn ir_len_zero_or_beyond_the_period_is_refused() {
    let x = gaussian(100, 1.0, 13);
    let cfg = DeconvConfig { sample_rate_hz: FS, ir_len: 0, band: None, regularisation: 0.0, pre_samples: 0 };
    assert!(matches!(deconvolve(&x, &x, &cfg), Err(DspError::InvalidParameter { name: "ir_len", .. })));
    let long = DeconvConfig { ir_len: 101, ..cfg };
    assert!(matches!(deconvolve_periodic(&x, &x, &long), Err(DspError::InvalidParameter { name: "ir_len", .. })));
    assert!(deconvolve_periodic(&x, &x, &DeconvConfig { ir_len: 100, ..cfg }).is_ok());
    let huge = DeconvConfig { ir_len: fft::MAX_FFT_LEN + 1, ..cfg };
    assert!(matches!(deconvolve(&x, &x, &huge), Err(DspError::TooLong { .. })));
    // Mismatched lengths where one acquisition must give equal ones.
    assert!(matches!(deconvolve_with_reference(&x, &x[..99], &long), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(deconvolve_periodic(&x, &x[..99], &long), Err(DspError::LengthMismatch { .. })));
    // A recording shorter than its excitation missed the end of the sweep.
    assert!(matches!(deconvolve(&x[..50], &x, &long), Err(DspError::InvalidParameter { name: "recording", .. })));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// Any short response through any short excitation comes back exactly (no band limit, no regularisation).
    #[test]
    fn round_trip_of_short_signals(
        h in prop::collection::vec(-1.0f64..1.0, 1..40),
        tail in prop::collection::vec(-1.0f64..1.0, 0..40),
        sample_rate_hz in 1.0f64..1e5,
    ) {
        // A leading sample larger than the sum of the others' magnitudes keeps |X| >= x0 - sum > 0 at every
        // frequency, so the condition number is at most (x0 + S) / (x0 - S) = (3S + 1) / (S + 1) < 3.
        let s: f64 = tail.iter().map(|v| v.abs()).sum();
        let x: Vec<f64> = std::iter::once(2.0 * s + 1.0).chain(tail.iter().copied()).collect();
        let cfg = DeconvConfig { sample_rate_hz, ir_len: h.len(), band: None, regularisation: 0.0, pre_samples: 0 };
        let got = deconvolve(&convolve(&x, &h).unwrap(), &x, &cfg).unwrap();
        prop_assert_eq!(got.len(), h.len());
        let tol = ROUNDING_PER_CONDITION * 3.0 * (1.0 + max_abs(&h));
        prop_assert!(max_abs(&diff(&got, &h)) < tol);
    }
}

//! Fractional-octave smoothing of a response's power spectrum, and the minimum-phase response with that smoothed
//! magnitude.
//!
//! Why: an actuator measured on its own magnet also shows the plate's driving-point modes, peaks and notches of
//! +/-25 dB a few hertz wide. They belong to the plate at that one point, not to the actuator: an inverse filter
//! that inverted them would boost narrow notches by tens of dB, spend the amplifier's headroom there and lower the
//! signal-to-noise ratio of every other frequency at every other point. So the calibration flattens the actuator's
//! broadband response, the power averaged over a fraction of an octave, as loudspeakers are equalised, and states
//! its flatness on the same smoothing.

use num_complex::Complex64;

use crate::error::{DspError, check_result, check_signal};
use crate::{fft, impulse};

/// Power spectrum `power` (bins `0..=n/2` of an `n`-point DFT at `sample_rate_hz`) averaged over `1/fraction` of
/// an octave around each bin: bin `k` at `f` averages the bins within `f * 2^(+-1/(2 fraction))`; bin 0 is kept.
///
/// Valid range: `power.len() == n / 2 + 1`, finite non-negative powers, `fraction` finite and >= 1 (1 is a whole
/// octave; 3 the usual third-octave), finite positive sample rate. Linear time (prefix sums).
///
/// # Errors
/// [`DspError::LengthMismatch`], [`DspError::NonFinite`], [`DspError::InvalidParameter`] naming the bad argument.
pub fn fractional_octave_power(
    power: &[f64],
    n: usize,
    sample_rate_hz: f64,
    fraction: f64,
) -> Result<Vec<f64>, DspError> {
    if power.len() != fft::bin_count(n) {
        return Err(DspError::LengthMismatch {
            what: "power bins against n / 2 + 1",
            a: power.len(),
            b: fft::bin_count(n),
        });
    }
    check_signal("power", power)?;
    if power.iter().any(|p| *p < 0.0) {
        return Err(DspError::InvalidParameter { name: "power", reason: "must be >= 0 at every bin".into() });
    }
    if !(fraction.is_finite() && fraction >= 1.0) {
        return Err(DspError::InvalidParameter { name: "fraction", reason: format!("must be >= 1, got {fraction}") });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(DspError::InvalidParameter {
            name: "sample_rate_hz",
            reason: format!("must be finite and positive, got {sample_rate_hz}"),
        });
    }
    let mut prefix = Vec::with_capacity(power.len() + 1);
    prefix.push(0.0);
    for p in power {
        prefix.push(prefix[prefix.len() - 1] + p);
    }
    let half_width = 2f64.powf(0.5 / fraction);
    let last = power.len() - 1;
    let smoothed: Vec<f64> = (0..power.len())
        .map(|k| {
            if k == 0 {
                return power[0];
            }
            // Bin numbers scale with frequency, so the band's edges in bins are k / w and k w.
            let lo = ((k as f64 / half_width).ceil() as usize).clamp(1, k);
            let hi = ((k as f64 * half_width).floor() as usize).clamp(k, last);
            (prefix[hi + 1] - prefix[lo]) / (hi + 1 - lo) as f64
        })
        .collect();
    check_result("smoothed power", &smoothed)?;
    Ok(smoothed)
}

/// The minimum-phase response whose magnitude is `ir`'s, smoothed over `1/fraction` of an octave: `ir.len()`
/// samples, with time 0 at sample `pre_samples` as in `ir` (the samples before it are zero: a minimum-phase
/// response starts at once).
///
/// Valid range: `ir` finite, not all zero, `pre_samples < ir.len()`; `fraction` and `sample_rate_hz` as
/// [`fractional_octave_power`]. The cepstrum is taken at twice the length, so the smoothed response (shorter than
/// the raw one: smoothing removes the long ring of narrow modes) is not time-aliased.
///
/// # Errors
/// As [`fractional_octave_power`] and [`impulse::minimum_phase_spectrum`]; [`DspError::InvalidParameter`] for
/// `pre_samples`.
pub fn smoothed_minimum_phase(
    ir: &[f64],
    pre_samples: usize,
    sample_rate_hz: f64,
    fraction: f64,
) -> Result<Vec<f64>, DspError> {
    check_signal("response", ir)?;
    if pre_samples >= ir.len() {
        return Err(DspError::InvalidParameter {
            name: "pre_samples",
            reason: format!("must be below the response's length ({}), got {pre_samples}", ir.len()),
        });
    }
    let n = fft::fast_len(2 * ir.len())?;
    let power: Vec<f64> = fft::forward(ir, n)?.iter().map(Complex64::norm_sqr).collect();
    let smoothed = fractional_octave_power(&power, n, sample_rate_hz, fraction)?;
    let magnitude: Vec<f64> = smoothed.iter().map(|p| p.sqrt()).collect();
    let spectrum = impulse::minimum_phase_spectrum(&magnitude, n)?;
    let min_phase = fft::inverse(&spectrum, n)?;
    let mut out = vec![0.0; pre_samples];
    out.extend_from_slice(&min_phase[..ir.len() - pre_samples]);
    check_result("smoothed minimum-phase response", &out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn smoothing_keeps_a_flat_spectrum_and_averages_a_notch_away() {
        let n = 4096;
        let bins = fft::bin_count(n);
        let flat = vec![2.0; bins];
        for fraction in [1.0, 3.0, 24.0] {
            let s = fractional_octave_power(&flat, n, 24_000.0, fraction).unwrap();
            assert!(s.iter().all(|v| (v - 2.0).abs() < 1e-12), "a flat spectrum stays flat");
        }
        // A one-bin notch at bin 1000: a third octave there spans about 231 bins, so the notch costs 1/231 of the
        // power (-0.02 dB); unsmoothed it is -inf dB.
        let mut notched = vec![1.0; bins];
        notched[1000] = 0.0;
        let s = fractional_octave_power(&notched, n, 24_000.0, 3.0).unwrap();
        let width = (1000.0 * 2f64.powf(1.0 / 6.0)).floor() - (1000.0 / 2f64.powf(1.0 / 6.0)).ceil() + 1.0;
        assert!((s[1000] - (1.0 - 1.0 / width)).abs() < 1e-12, "{}", s[1000]);
        // The extremes: bin 0 is kept; the top bin averages only what lies below it.
        assert_eq!(s[0], 1.0);
        assert!((s[bins - 1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn smoothing_refuses_bad_arguments() {
        let p = vec![1.0; 5];
        assert!(matches!(fractional_octave_power(&p, 16, 1.0, 3.0), Err(DspError::LengthMismatch { .. })));
        assert!(matches!(fractional_octave_power(&p, 8, 1.0, 0.5), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(fractional_octave_power(&p, 8, 0.0, 3.0), Err(DspError::InvalidParameter { .. })));
        let neg = [1.0, -1.0, 1.0, 1.0, 1.0];
        assert!(matches!(fractional_octave_power(&neg, 8, 1.0, 3.0), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(smoothed_minimum_phase(&[1.0, 0.0], 2, 1.0, 3.0), Err(DspError::InvalidParameter { .. })));
        assert!(smoothed_minimum_phase(&[0.0; 8], 0, 1.0, 3.0).is_err(), "all zero: no magnitude to give a phase");
    }

    #[test]
    fn a_smooth_minimum_phase_response_comes_back_unchanged() {
        // A one-pole low-pass (minimum phase, smooth magnitude) with 16 pre-samples: smoothing over a 24th of an
        // octave barely changes its magnitude, and its minimum phase is its own phase.
        let pre = 16;
        let mut ir = vec![0.0; 2048];
        for (i, v) in ir[pre..].iter_mut().enumerate() {
            *v = 0.1 * 0.9f64.powi(i as i32);
        }
        let out = smoothed_minimum_phase(&ir, pre, 24_000.0, 24.0).unwrap();
        assert!(out[..pre].iter().all(|v| *v == 0.0));
        let error: f64 = out.iter().zip(&ir).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        let energy: f64 = ir.iter().map(|v| v * v).sum();
        // Smoothing a 1/(1 - 0.9 z^-1) magnitude over 1/24 octave changes it by under 0.1 % where it matters.
        assert!(error / energy < 1e-4, "relative error energy {}", error / energy);
    }
}

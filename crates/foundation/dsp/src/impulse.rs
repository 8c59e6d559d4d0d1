//! Band-limited impulses and minimum-phase conversion.
//!
//! A band-limited impulse is the target signal of wave focusing (the paper renders "band-limited impulses" at a
//! pixel) and a clean test signal; the minimum-phase version of an impulse response keeps its magnitude but moves its
//! energy as early as possible, which is what a causal filter with no pre-ringing needs.

use std::f64::consts::PI;

use num_complex::Complex64;

use crate::band::BandLimit;
use crate::error::{DspError, check_result, check_sample_rate, check_signal};
use crate::fft;

/// Zero-phase band-limited impulse of `len` samples centred at `delay_samples` (fractional delays allowed).
///
/// Built in the frequency domain on a length-`len` DFT: bin `k` (frequency `f_k = k fs / len`) is set to
/// `band.gain(f_k) * exp(-i 2 pi f_k delay / fs)`, then transformed back. Normalisation: the unnormalised DFT of the
/// result (`sum_n x[n] e^{-i 2 pi k n / len}`, as [`fft::forward`]) is exactly 1 in magnitude at every bin inside the
/// band and follows the band's raised-cosine skirts outside it; the peak value is therefore about
/// `(2 (hi - lo) + lo_transition + hi_transition) / fs` (the area under the two-sided gain), about 0.05 for a
/// 50..625 Hz band at 24 kHz. At the Nyquist bin of an even `len` a real signal can only carry
/// `gain * cos(pi delay)`, so the magnitude there is exact only for integer delays.
///
/// The result is one period of a periodic signal: the impulse's tails wrap around the ends. Raised-cosine skirts of
/// width `W` Hz make the tails decay like `1 / (4 pi W^2 t^3)`, so when at least `3 / W` seconds (with `W` the
/// narrower skirt) separate `delay_samples` from both ends of the buffer, the wrapped part stays below about
/// -50 dB of the peak. Brick-wall edges (zero transition) decay only like `1 / t` and always wrap audibly; taper
/// the result (see [`crate::window`]) or give the band skirts.
///
/// Valid range: `1 <= len <= fft::MAX_FFT_LEN`, `0 <= delay_samples < len` (finite), a valid `band` with
/// `lo_hz < fs / 2`, and at least one bin of non-zero gain (`len` long enough to resolve the band).
///
/// # Errors
/// [`DspError::InvalidParameter`] for a parameter outside that range, [`DspError::TooLong`] for `len`.
pub fn band_limited_impulse(
    len: usize,
    delay_samples: f64,
    band: &BandLimit,
    sample_rate_hz: f64,
) -> Result<Vec<f64>, DspError> {
    check_sample_rate(sample_rate_hz)?;
    band.validate()?;
    if len == 0 {
        return Err(DspError::InvalidParameter { name: "len", reason: "must be at least 1".into() });
    }
    if !(delay_samples.is_finite() && delay_samples >= 0.0 && delay_samples < len as f64) {
        return Err(DspError::InvalidParameter {
            name: "delay_samples",
            reason: format!("must lie in [0, {len}), got {delay_samples}"),
        });
    }
    let nyquist_hz = sample_rate_hz / 2.0;
    if band.lo_hz >= nyquist_hz {
        return Err(DspError::InvalidParameter {
            name: "band.lo_hz",
            reason: format!("{} Hz is not below Nyquist ({nyquist_hz} Hz)", band.lo_hz),
        });
    }
    let gains = band.bin_gains(len, sample_rate_hz);
    if gains.iter().all(|&g| g == 0.0) {
        return Err(DspError::InvalidParameter {
            name: "len",
            reason: format!("{len} samples are too few to put a DFT bin inside the band"),
        });
    }
    let spectrum: Vec<Complex64> = gains
        .iter()
        .enumerate()
        .map(|(k, &g)| Complex64::from_polar(g, -2.0 * PI * k as f64 * delay_samples / len as f64))
        .collect();
    let x = fft::inverse(&spectrum, len)?;
    check_result("band-limited impulse", &x)?;
    Ok(x)
}

/// Magnitude floor of [`minimum_phase`], dB relative to the peak magnitude: bins weaker than this are raised to it
/// before the logarithm. -100 dB lies below anything a 16-bit measurement resolves, yet keeps `ln |H|` within
/// about 23 nepers of its peak so the cepstrum stays well conditioned.
pub const MIN_PHASE_FLOOR_DB: f64 = -100.0;

/// Initial zero-padding factor of [`minimum_phase`]: the cepstrum is first computed on this many times the input
/// length. Cepstral time aliasing (the homomorphic method's error) shrinks as the padding grows.
pub const MIN_PHASE_PAD_FACTOR: usize = 16;

/// Accuracy [`minimum_phase`] guarantees, dB relative to the peak magnitude: at every bin of its DFT, the result's
/// magnitude differs from the input's by at most this much of the peak. The error is additive (cepstral aliasing and
/// truncation), so it is 0.1 dB where the response lies 40 dB below its peak and about 1 dB at 60 dB below.
pub const MIN_PHASE_ERROR_DB: f64 = -80.0;

/// Largest FFT [`minimum_phase`] grows to while refining (2^22, 64 MiB per complex buffer), unless the initial
/// padding already needs more.
pub const MIN_PHASE_MAX_FFT_LEN: usize = 1 << 22;

/// Minimum-phase version of `ir`: the same magnitude response, with the energy as early as possible, `ir.len()`
/// samples long.
///
/// Homomorphic (real-cepstrum) method: `|H|` on a DFT of `n = fft::fast_len(MIN_PHASE_PAD_FACTOR * len)` bins,
/// floored at [`MIN_PHASE_FLOOR_DB`] below its peak; the real cepstrum of `ln |H|` is folded onto positive
/// quefrencies, exponentiated back and truncated to `len` samples (a length-`len` FIR has a minimum-phase
/// counterpart of the same length: its zeros reflected inside the unit circle). The result's magnitude is then
/// checked on the same `n` bins; while it misses [`MIN_PHASE_ERROR_DB`] anywhere, `n` is quadrupled, up to
/// [`MIN_PHASE_MAX_FFT_LEN`]. Zeros close to the unit circle (long, noisy responses) need the most padding: a
/// 4096-sample decaying noise burst needs 2^22 bins.
///
/// Valid range: finite, non-empty `ir` with a non-zero sample, whose minimum-phase version the method resolves to
/// the stated accuracy within the FFT cap.
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`] for `ir`; [`DspError::InvalidParameter`] for an all-zero `ir` or
/// one whose accuracy is not reached within the cap; [`DspError::TooLong`] when the initial padding exceeds
/// [`fft::MAX_FFT_LEN`]; [`DspError::NonFiniteResult`] should the computation overflow.
pub fn minimum_phase(ir: &[f64]) -> Result<Vec<f64>, DspError> {
    check_signal("impulse response", ir)?;
    if ir.iter().all(|&v| v == 0.0) {
        return Err(DspError::InvalidParameter {
            name: "ir",
            reason: "all samples are zero: there is no magnitude response to keep".into(),
        });
    }
    let first_n = fft::fast_len(ir.len().saturating_mul(MIN_PHASE_PAD_FACTOR))?;
    let max_n = first_n.max(MIN_PHASE_MAX_FFT_LEN);
    let mut n = first_n;
    loop {
        let (out, error_db) = minimum_phase_at(ir, n)?;
        if error_db <= MIN_PHASE_ERROR_DB {
            return Ok(out);
        }
        let next = fft::fast_len(n.saturating_mul(4))?;
        if next > max_n {
            return Err(DspError::InvalidParameter {
                name: "ir",
                reason: format!(
                    "its minimum-phase magnitude is still off by {error_db:.1} dB of the peak at an FFT of {n} \
                     (zeros too close to the unit circle)"
                ),
            });
        }
        n = next;
    }
}

/// One pass of [`minimum_phase`] at DFT length `n`: the truncated result and its worst magnitude error over the
/// bins, in dB relative to the peak magnitude.
fn minimum_phase_at(ir: &[f64], n: usize) -> Result<(Vec<f64>, f64), DspError> {
    let magnitude: Vec<f64> = fft::forward(ir, n)?.iter().map(|c| c.norm()).collect();
    let spectrum = minimum_phase_spectrum(&magnitude, n)?;
    let mut out = fft::inverse(&spectrum, n)?;
    out.truncate(ir.len());
    check_result("minimum-phase conversion", &out)?;
    let peak = magnitude.iter().fold(0.0, |m: f64, v| m.max(*v));
    let achieved = fft::forward(&out, n)?;
    let worst = magnitude.iter().zip(&achieved).map(|(m, a)| (a.norm() - m).abs()).fold(0.0, f64::max);
    Ok((out, 20.0 * (worst / peak).log10()))
}

/// Minimum-phase spectrum with a given magnitude on the `n / 2 + 1` bins of a length-`n` real DFT.
///
/// `magnitude` is floored at [`MIN_PHASE_FLOOR_DB`] below its peak, so the result's magnitude is
/// `max(magnitude, floor)` exactly (to rounding) and its phase is the minimum phase of that magnitude, computed by
/// the real cepstrum at length `n` (no padding: pad the magnitude's underlying signal first if its cepstrum is long;
/// see [`minimum_phase`]).
///
/// Valid range: `1 <= n <= fft::MAX_FFT_LEN`, `magnitude.len() == n / 2 + 1`, finite non-negative magnitudes with a
/// positive peak.
///
/// # Errors
/// [`DspError::LengthMismatch`], [`DspError::NonFinite`], [`DspError::InvalidParameter`] (named `magnitude`) for a
/// negative or all-zero magnitude, [`DspError::NonFiniteResult`] should the exponentiation overflow.
pub fn minimum_phase_spectrum(magnitude: &[f64], n: usize) -> Result<Vec<Complex64>, DspError> {
    if magnitude.len() != fft::bin_count(n) {
        return Err(DspError::LengthMismatch {
            what: "magnitude bins against n / 2 + 1",
            a: magnitude.len(),
            b: fft::bin_count(n),
        });
    }
    check_signal("magnitude", magnitude)?;
    if let Some(v) = magnitude.iter().find(|v| **v < 0.0) {
        return Err(DspError::InvalidParameter { name: "magnitude", reason: format!("must be >= 0, got {v}") });
    }
    let peak = magnitude.iter().fold(0.0, |m: f64, v| m.max(*v));
    if peak == 0.0 {
        return Err(DspError::InvalidParameter { name: "magnitude", reason: "is zero at every bin".into() });
    }
    let floor = peak * 10f64.powf(MIN_PHASE_FLOOR_DB / 20.0);
    let log_mag: Vec<Complex64> = magnitude.iter().map(|m| Complex64::new(m.max(floor).ln(), 0.0)).collect();
    let mut cepstrum = fft::inverse(&log_mag, n)?;
    fold_cepstrum(&mut cepstrum);
    let spectrum: Vec<Complex64> = fft::forward(&cepstrum, n)?.iter().map(|c| c.exp()).collect();
    if spectrum.iter().any(|c| !(c.re.is_finite() && c.im.is_finite())) {
        return Err(DspError::NonFiniteResult { what: "minimum-phase spectrum" });
    }
    Ok(spectrum)
}

/// Folds a real (even) cepstrum onto non-negative quefrencies: `c[0]` kept, `c[1..n/2]` doubled, `c[n/2]` kept for
/// even `n`, the rest zeroed. The result is the cepstrum of the minimum-phase signal with the same magnitude.
pub fn fold_cepstrum(c: &mut [f64]) {
    let n = c.len();
    let half = n / 2;
    for (q, v) in c.iter_mut().enumerate().skip(1) {
        if q < half || (q == half && n % 2 == 1) {
            *v *= 2.0;
        } else if q > half {
            *v = 0.0;
        }
    }
}

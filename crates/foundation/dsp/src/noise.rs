//! Coloured noise: white noise shaped to a pink (1/f power) spectrum over a band, as a masker of auditory cues
//! (the paper's participants heard pink noise on headphones).
//!
//! The shaping is done in the frequency domain over the whole signal: the result is exactly pink over the band
//! (equal power per octave, -3.01 dB per octave of power spectral density), silent outside it, and periodic, so
//! it loops without a click. The white noise comes from the caller (this crate draws no random numbers), so a
//! seeded generator gives the same masker on every platform.

use crate::error::DspError;
use crate::fft;

/// `white` shaped to pink noise over `band_hz = (low, high)` and scaled to an RMS of `rms` (full scale 1.0).
///
/// Valid range: `white` of at least 2 samples, all finite and not all zero; finite `sample_rate_hz > 0`;
/// `0 < low < high`, `low` finite (`high` above Nyquist is taken as Nyquist); at least one FFT bin
/// (`k * sample_rate_hz / white.len()`) inside the band; finite `rms > 0`. The output has `white.len()` samples.
///
/// # Errors
/// [`DspError::Empty`] for fewer than 2 samples; [`DspError::NonFinite`] for a non-finite input sample;
/// [`DspError::InvalidParameter`] for a parameter out of range, a band holding no bin, or a white noise with no
/// energy in the band.
pub fn pink_noise(white: &[f64], sample_rate_hz: f64, band_hz: (f64, f64), rms: f64) -> Result<Vec<f64>, DspError> {
    let n = white.len();
    if n < 2 {
        return Err(DspError::Empty { input: "white noise (at least 2 samples)" });
    }
    let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return invalid("sample_rate_hz", format!("must be finite and > 0, got {sample_rate_hz}"));
    }
    let (low_hz, high_hz) = band_hz;
    if !(low_hz.is_finite() && low_hz > 0.0 && high_hz > low_hz) {
        return invalid("band_hz", format!("must be 0 < low < high with low finite, got ({low_hz}, {high_hz})"));
    }
    if !(rms.is_finite() && rms > 0.0) {
        return invalid("rms", format!("must be finite and > 0, got {rms}"));
    }
    let mut spectrum = fft::forward(white, n)?;
    let mut in_band = 0usize;
    for (k, bin) in spectrum.iter_mut().enumerate() {
        let f_hz = fft::bin_freq_hz(k, n, sample_rate_hz);
        if (low_hz..=high_hz).contains(&f_hz) {
            // Amplitude 1/sqrt(f): power 1/f, the same in every octave.
            *bin *= (low_hz / f_hz).sqrt();
            in_band += 1;
        } else {
            *bin = num_complex::Complex64::new(0.0, 0.0);
        }
    }
    if in_band == 0 {
        return invalid(
            "band_hz",
            format!(
                "({low_hz}, {high_hz}) Hz holds no frequency bin of {n} samples at {sample_rate_hz} Hz (bins are {} Hz apart)",
                sample_rate_hz / n as f64
            ),
        );
    }
    let mut pink = fft::inverse(&spectrum, n)?;
    let power = pink.iter().map(|v| v * v).sum::<f64>() / n as f64;
    if !(power.is_finite() && power > 0.0) {
        return invalid("white", "the white noise has no energy in the band".into());
    }
    let gain = rms / power.sqrt();
    pink.iter_mut().for_each(|v| *v *= gain);
    Ok(pink)
}

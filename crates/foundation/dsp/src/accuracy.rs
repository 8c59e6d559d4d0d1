//! How far a measured response is from a reference: the relative error energy in dB that the tests, the mock lab's
//! accuracy, `metaplate demo` and `metaplate tradeoff` all report, and the band they compare over.

use num_complex::Complex64;

use crate::error::{DspError, check_signal};
use crate::fft;

/// The band a Green's function's error is measured over, Hz: inside the flat part of the paper's deconvolution band
/// (62..625 Hz, with skirts outside it) and the sweep.
pub const ERROR_BAND_HZ: (f64, f64) = (80.0, 600.0);

/// What [`relative_error_db`] returns for a measurement equal to its reference: far below anything f64 rounding
/// resolves, and finite.
pub const IDENTICAL_DB: f64 = -400.0;

/// Relative error of `measured` against `reference`, dB: `10 log10(sum (m - r)^2 / sum r^2)` over their samples
/// (by Parseval, the same as over their spectra). -20 dB is a 10 % error in amplitude; 0 dB an error as large as
/// the reference; a measurement equal to the reference gives [`IDENTICAL_DB`].
///
/// Valid range: finite signals of equal, nonzero length; a reference with some energy.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for either signal; [`DspError::LengthMismatch`] for different
/// lengths; [`DspError::InvalidParameter`] for an all-zero reference.
pub fn relative_error_db(measured: &[f64], reference: &[f64]) -> Result<f64, DspError> {
    check_signal("measured", measured)?;
    check_signal("reference", reference)?;
    same_length(measured.len(), reference.len())?;
    let error: f64 = measured.iter().zip(reference).map(|(m, r)| (m - r) * (m - r)).sum();
    error_ratio_db(error, reference.iter().map(|r| r * r).sum())
}

/// As [`relative_error_db`] over spectra (complex values at the same frequencies, for example the FFT bins of a
/// band): `10 log10(sum |m - r|^2 / sum |r|^2)`.
///
/// # Errors
/// As [`relative_error_db`]; a non-finite real or imaginary part is [`DspError::NonFinite`] at its value's index.
pub fn spectral_error_db(measured: &[Complex64], reference: &[Complex64]) -> Result<f64, DspError> {
    check_spectrum("measured", measured)?;
    check_spectrum("reference", reference)?;
    same_length(measured.len(), reference.len())?;
    let error: f64 = measured.iter().zip(reference).map(|(m, r)| (m - r).norm_sqr()).sum();
    error_ratio_db(error, reference.iter().map(Complex64::norm_sqr).sum())
}

/// The error a measured response probably has against its truth over [`ERROR_BAND_HZ`], dB, from the noise it
/// carries: `10 log10(noise / (E - noise))`, where `E` is the response's energy within the band and `noise` the
/// expected energy of the noise in it there (from the spread of repetitions: [`crate::pipeline::ChannelResult`]).
/// It is the random part of [`spectral_error_db`] against the truth: biases that every repetition shares (an
/// actuator's distortion, a clock's drift) do not show in a spread, so on a rig where they dominate the true error
/// is larger.
///
/// Returns [`IDENTICAL_DB`] for no noise, and 0 dB where the noise is at least half the band's energy (the response
/// is then no larger than its noise, and no finer estimate is meaningful).
///
/// Valid range: a finite, non-empty `ir` at `sample_rate_hz` (finite, > 0) whose DFT has a bin in the band with
/// energy; finite `noise_energy >= 0`, in the units of `ir` squared summed over its samples.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for `ir`; [`DspError::InvalidParameter`] for a bad noise energy or
/// sample rate, or a response with no energy in the band (below 1e-12 of its whole energy: rounding).
pub fn estimated_error_db(ir: &[f64], noise_energy: f64, sample_rate_hz: f64) -> Result<f64, DspError> {
    check_signal("response", ir)?;
    if !(noise_energy.is_finite() && noise_energy >= 0.0) {
        return Err(DspError::InvalidParameter {
            name: "noise_energy",
            reason: format!("{noise_energy}: must be finite and >= 0"),
        });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(DspError::InvalidParameter {
            name: "sample_rate_hz",
            reason: format!("{sample_rate_hz}: must be finite and > 0"),
        });
    }
    let energy = band_energy(ir, ERROR_BAND_HZ, sample_rate_hz)?;
    let total: f64 = ir.iter().map(|v| v * v).sum();
    // Below 1e-12 of the whole the band holds only the FFT's rounding of what lies outside it.
    if !(energy > 1e-12 * total && energy.is_finite()) {
        return Err(DspError::InvalidParameter {
            name: "response",
            reason: format!("has no energy within {ERROR_BAND_HZ:?} Hz ({energy})"),
        });
    }
    if noise_energy == 0.0 {
        return Ok(IDENTICAL_DB);
    }
    let signal = energy - noise_energy;
    if signal <= noise_energy {
        return Ok(0.0);
    }
    Ok((10.0 * (noise_energy / signal).log10()).max(IDENTICAL_DB))
}

/// Energy of `signal` within `band_hz`, in the units of its samples squared summed over them: by Parseval,
/// `(1 / n) sum |X_k|^2` over the two-sided bins in the band (each one-sided bin but DC and Nyquist counts twice).
///
/// Valid range: a finite, non-empty signal; `sample_rate_hz > 0`.
///
/// # Errors
/// As [`fft::forward`].
pub fn band_energy(signal: &[f64], band_hz: (f64, f64), sample_rate_hz: f64) -> Result<f64, DspError> {
    let n = signal.len();
    let spectrum = fft::forward(signal, n)?;
    Ok(spectrum
        .iter()
        .enumerate()
        .filter(|&(k, _)| (band_hz.0..=band_hz.1).contains(&fft::bin_freq_hz(k, n, sample_rate_hz)))
        .map(|(k, x)| if k == 0 || 2 * k == n { 1.0 } else { 2.0 } * x.norm_sqr())
        .sum::<f64>()
        / n as f64)
}

fn same_length(a: usize, b: usize) -> Result<(), DspError> {
    if a != b {
        return Err(DspError::LengthMismatch { what: "measured and reference", a, b });
    }
    Ok(())
}

fn check_spectrum(input: &'static str, x: &[Complex64]) -> Result<(), DspError> {
    if x.is_empty() {
        return Err(DspError::Empty { input });
    }
    match x.iter().enumerate().find(|(_, c)| !(c.re.is_finite() && c.im.is_finite())) {
        Some((index, c)) => {
            Err(DspError::NonFinite { input, index, value: if c.re.is_finite() { c.im } else { c.re } })
        }
        None => Ok(()),
    }
}

/// `10 log10(error / energy)`, at least [`IDENTICAL_DB`]; an error for a reference without energy.
fn error_ratio_db(error: f64, energy: f64) -> Result<f64, DspError> {
    // `!(energy > 0.0)` also refuses a NaN energy (finite inputs whose squares overflow).
    if !(energy > 0.0 && energy.is_finite() && error.is_finite()) {
        return Err(DspError::InvalidParameter {
            name: "reference",
            reason: format!("has no usable energy (error {error}, reference energy {energy})"),
        });
    }
    Ok((10.0 * (error / energy).log10()).max(IDENTICAL_DB))
}

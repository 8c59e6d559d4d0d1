//! How close a measured response is to the lab's ground truth: [`metaplate_dsp::accuracy`]'s error measure against
//! [`MockLab::true_response`], which the scan tests, `metaplate demo` and `metaplate tradeoff` share.

pub use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::accuracy::spectral_error_db;
use metaplate_dsp::error::check_signal;
use metaplate_dsp::fft;
use metaplate_dsp::kirkeby::KirkebyFilter;
use num_complex::Complex64;

use crate::{LabError, MockLab};

impl MockLab {
    /// Relative error energy of a measured response `ir` (m/s per full scale, sampled at `sample_rate_hz`, time 0 at
    /// index 0: see [`time_zero_first`] for a two-sided one) against
    /// [`MockLab::true_response`] of (`point`, `actuator`), over the FFT bins of `ir` (its own length) within
    /// `band_hz`, dB: `10 log10(sum |H - T|^2 / sum |T|^2)`. -20 dB means the error is a tenth of the truth's
    /// amplitude ([`spectral_error_db`]). With `compensation`, the truth is taken through that inverse filter with its modelling delay
    /// removed: what a scan through the filter measures (the loopback carries the delay, and the division cancels
    /// it).
    ///
    /// Valid range: a finite, non-empty `ir`; `0 <= lo < hi <= sample_rate_hz / 2` holding at least one bin where
    /// the truth is not zero.
    ///
    /// # Errors
    /// [`LabError::Dsp`] for an empty or non-finite `ir`; [`LabError::InvalidOption`] for a band with no bin or a
    /// truth of zero energy there, or a filter at another sample rate; as [`MockLab::true_response`] otherwise.
    pub fn response_error_db(
        &self,
        point: usize,
        actuator: usize,
        ir: &[f64],
        sample_rate_hz: f64,
        band_hz: (f64, f64),
        compensation: Option<&KirkebyFilter>,
    ) -> Result<f64, LabError> {
        check_signal("measured response", ir)?;
        let n = ir.len();
        let spectrum = fft::forward(ir, n)?;
        let bins: Vec<usize> = (0..spectrum.len())
            .filter(|&k| (band_hz.0..=band_hz.1).contains(&fft::bin_freq_hz(k, n, sample_rate_hz)))
            .collect();
        let freqs: Vec<f64> = bins.iter().map(|&k| fft::bin_freq_hz(k, n, sample_rate_hz)).collect();
        let mut truth = self.true_response(point, actuator, &freqs)?;
        if let Some(filter) = compensation {
            if filter.sample_rate_hz != sample_rate_hz {
                return Err(LabError::InvalidOption {
                    name: "compensation",
                    reason: format!(
                        "the filter runs at {} Hz, the response at {sample_rate_hz} Hz",
                        filter.sample_rate_hz
                    ),
                });
            }
            let response = filter_response_at_bins(filter, n)?;
            let delay = filter.modelling_delay_samples as f64;
            for (t, &k) in truth.iter_mut().zip(&bins) {
                let advance = Complex64::from_polar(1.0, std::f64::consts::TAU * k as f64 * delay / n as f64);
                *t *= response[k] * advance;
            }
        }
        let measured: Vec<Complex64> = bins.iter().map(|&k| spectrum[k]).collect();
        spectral_error_db(&measured, &truth).map_err(|e| LabError::InvalidOption {
            name: "band_hz",
            reason: format!("{band_hz:?} Hz holds no bin where the truth is non-zero and finite ({e})"),
        })
    }
}

/// A two-sided impulse response (`ir[0]` at time `-pre_samples`) on its DFT's circle: time 0 first, the samples
/// before it wrapped to the end, so that its DFT is the response's spectrum without a delay of `pre_samples`.
/// [`MockLab::response_error_db`] compares responses in that form; a one-sided one (`pre_samples` 0) is returned as
/// it is. A `pre_samples` beyond the response's length wraps the whole response (never panics).
pub fn time_zero_first(ir: &[f64], pre_samples: usize) -> Vec<f64> {
    let mut out = ir.to_vec();
    out.rotate_left(pre_samples.min(ir.len()));
    out
}

/// The filter's frequency response at the bins of an `n`-point DFT: its taps folded modulo `n` (exact: at those
/// frequencies tap `m` and tap `m + n` turn by the same phase), then one FFT.
pub(crate) fn filter_response_at_bins(filter: &KirkebyFilter, n: usize) -> Result<Vec<Complex64>, LabError> {
    let mut folded = vec![0.0; n];
    for (m, h) in filter.taps.iter().enumerate() {
        folded[m % n] += h;
    }
    Ok(fft::forward(&folded, n)?)
}

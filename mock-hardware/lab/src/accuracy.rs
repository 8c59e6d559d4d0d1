//! How close a measured response is to the lab's ground truth: the error measure the scan tests and
//! `metaplate tradeoff` share.

use metaplate_dsp::error::check_signal;
use metaplate_dsp::fft;

use crate::{LabError, MockLab};

/// The band compared by default, Hz: inside the paper's deconvolution band's flat part (62..625 Hz, with skirts
/// outside it) and the sweep.
pub const ERROR_BAND_HZ: (f64, f64) = (80.0, 600.0);

impl MockLab {
    /// Relative error energy of a measured response `ir` (m/s per full scale, sampled at `sample_rate_hz`) against
    /// [`MockLab::true_response`] of (`point`, `actuator`), over the FFT bins of `ir` (its own length) within
    /// `band_hz`, dB: `10 log10(sum |H - T|^2 / sum |T|^2)`. -20 dB means the error is a tenth of the truth's
    /// amplitude.
    ///
    /// Valid range: a finite, non-empty `ir`; `0 <= lo < hi <= sample_rate_hz / 2` holding at least one bin where
    /// the truth is not zero.
    ///
    /// # Errors
    /// [`LabError::Dsp`] for an empty or non-finite `ir`; [`LabError::InvalidOption`] for a band with no bin or a
    /// truth of zero energy there; as [`MockLab::true_response`] otherwise.
    pub fn response_error_db(
        &self,
        point: usize,
        actuator: usize,
        ir: &[f64],
        sample_rate_hz: f64,
        band_hz: (f64, f64),
    ) -> Result<f64, LabError> {
        check_signal("measured response", ir)?;
        let n = ir.len();
        let spectrum = fft::forward(ir, n)?;
        let bins: Vec<usize> = (0..spectrum.len())
            .filter(|&k| (band_hz.0..=band_hz.1).contains(&fft::bin_freq_hz(k, n, sample_rate_hz)))
            .collect();
        let freqs: Vec<f64> = bins.iter().map(|&k| fft::bin_freq_hz(k, n, sample_rate_hz)).collect();
        let truth = self.true_response(point, actuator, &freqs)?;
        let (mut err, mut energy) = (0.0, 0.0);
        for (&k, t) in bins.iter().zip(&truth) {
            err += (spectrum[k] - t).norm_sqr();
            energy += t.norm_sqr();
        }
        if energy.is_nan() || energy <= 0.0 {
            return Err(LabError::InvalidOption {
                name: "band_hz",
                reason: format!("{band_hz:?} Hz holds no bin where the truth is non-zero"),
            });
        }
        Ok(10.0 * (err / energy).log10())
    }
}

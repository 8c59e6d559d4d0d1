//! The operating band and the bins of a propagation matrix that fall inside a band.

use metaplate_control::PropagationMatrices;

use crate::error::AnalysisError;

/// The paper's operating band, Hz: focusing, POD and singular-value authority are all computed over 75 to 400 Hz
/// (Materials and Methods, "Data-Driven Wave Field Control" and "Wave Field Analysis").
pub const OPERATING_BAND_HZ: (f64, f64) = (75.0, 400.0);

/// Positions (`0..g.n_bins()`) of the bins of `g` whose frequency lies in `band_hz = (lo, hi)`, both edges included.
///
/// Valid range: finite `0 <= lo < hi`.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for a band outside that range, or one holding none of `g`'s bins (the error
/// says which frequencies `g` covers).
pub fn bins_in_band(g: &PropagationMatrices, band_hz: (f64, f64)) -> Result<Vec<usize>, AnalysisError> {
    let (lo_hz, hi_hz) = band_hz;
    if !(lo_hz.is_finite() && hi_hz.is_finite() && lo_hz >= 0.0 && lo_hz < hi_hz) {
        return Err(AnalysisError::InvalidParameter {
            name: "band_hz",
            reason: format!("need finite 0 <= lo < hi, got ({lo_hz}, {hi_hz}) Hz"),
        });
    }
    let bins: Vec<usize> =
        g.freqs_hz().iter().enumerate().filter(|(_, f)| (lo_hz..=hi_hz).contains(*f)).map(|(k, _)| k).collect();
    if bins.is_empty() {
        let covered = match (g.freqs_hz().first(), g.freqs_hz().last()) {
            (Some(a), Some(b)) => format!("{a} to {b} Hz"),
            _ => "no frequency".to_owned(),
        };
        return Err(AnalysisError::InvalidParameter {
            name: "band_hz",
            reason: format!("({lo_hz}, {hi_hz}) Hz holds none of the propagation matrices' bins ({covered})"),
        });
    }
    Ok(bins)
}

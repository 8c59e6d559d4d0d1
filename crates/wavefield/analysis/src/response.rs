//! The plate's driven response against frequency: how strongly the actuators move the plate, on average.

use metaplate_control::PropagationMatrices;

use crate::bands::bins_in_band;
use crate::error::AnalysisError;

/// Mean response magnitude per frequency.
#[derive(Debug, Clone, PartialEq)]
pub struct DrivenResponse {
    /// Bin frequencies, Hz, ascending.
    pub freqs_hz: Vec<f64>,
    /// Per bin: the mean over points and actuators of `|G(x, i, f)|`, in `g`'s units (for a ground-truth dataset,
    /// the DFT of the velocity response per newton, (m/s)/N).
    pub mean_magnitude: Vec<f64>,
}

/// Mean of `|G|` over every point and actuator of `g`, per bin of `band_hz`.
///
/// The paper's attenuation plot (Fig. 2B) takes the median over the plate per actuator, then the mean over
/// actuators; this is the plain mean over both, which [`crate::report`] reports as `driven_response`.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for a band outside `0 <= lo < hi` or holding none of `g`'s bins.
pub fn driven_response(g: &PropagationMatrices, band_hz: (f64, f64)) -> Result<DrivenResponse, AnalysisError> {
    let bins = bins_in_band(g, band_hz)?;
    let count = (g.n_points() * g.n_actuators()).max(1) as f64;
    let mean_magnitude = bins
        .iter()
        .map(|&k| {
            g.at_bin(k).map_or(0.0, |gk| {
                let mut sum = 0.0;
                for a in 0..gk.ncols() {
                    for m in 0..gk.nrows() {
                        sum += gk[(m, a)].norm();
                    }
                }
                sum / count
            })
        })
        .collect();
    Ok(DrivenResponse { freqs_hz: bins.iter().map(|&k| g.freqs_hz()[k]).collect(), mean_magnitude })
}

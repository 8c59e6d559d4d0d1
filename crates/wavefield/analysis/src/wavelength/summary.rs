//! Across-actuator summary of per-actuator wavelength estimates.

use super::WavelengthEstimate;
use super::stats::weighted_quantiles;
use crate::error::AnalysisError;

/// How per-actuator statistics are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AcrossActuators {
    /// The mean of each statistic across actuators, as in the paper ("the mean of these statistics across actuators
    /// was taken").
    Mean,
    /// The median of each statistic across actuators (robust to one actuator whose field is dominated by its near
    /// field or by a flagged estimate).
    Median,
}

/// Wavelength at one frequency summarised across actuators.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthSummary {
    /// Combined median wavelength (m).
    pub median_m: f64,
    /// Combined interquartile range (m): (25th, 75th percentile), each combined separately.
    pub iqr_m: (f64, f64),
    /// Number of estimates combined.
    pub actuators: usize,
    /// How many of them carried a range flag (see [`super::EstimateFlags`]); they are included all the same.
    pub flagged: usize,
}

/// Combines per-actuator estimates: the median, the 25th and the 75th percentile are each combined across
/// actuators by `how`.
///
/// # Errors
/// [`AnalysisError::Empty`] for no estimates; [`AnalysisError::NonFinite`] when an estimate holds a non-finite or
/// non-positive wavelength (one not made by [`super::estimate_wavelength`]).
pub fn summarise(estimates: &[WavelengthEstimate], how: AcrossActuators) -> Result<WavelengthSummary, AnalysisError> {
    if estimates.is_empty() {
        return Err(AnalysisError::Empty { input: "wavelength estimates" });
    }
    if let Some(index) =
        estimates.iter().position(|e| ![e.median_m, e.iqr_m.0, e.iqr_m.1].iter().all(|v| v.is_finite() && *v > 0.0))
    {
        return Err(AnalysisError::NonFinite { input: "wavelength estimates", index });
    }
    let combine = |pick: fn(&WavelengthEstimate) -> f64| -> f64 {
        let values: Vec<f64> = estimates.iter().map(pick).collect();
        match how {
            AcrossActuators::Mean => values.iter().sum::<f64>() / values.len() as f64,
            // Non-empty and positive-weighted by construction, so the quantile exists.
            AcrossActuators::Median => {
                weighted_quantiles(&values, &vec![1.0; values.len()], &[0.5]).map_or(f64::NAN, |q| q[0])
            }
        }
    };
    let summary = WavelengthSummary {
        median_m: combine(|e| e.median_m),
        iqr_m: (combine(|e| e.iqr_m.0), combine(|e| e.iqr_m.1)),
        actuators: estimates.len(),
        flagged: estimates.iter().filter(|e| !e.flags.in_range()).count(),
    };
    if [summary.median_m, summary.iqr_m.0, summary.iqr_m.1].iter().all(|v| v.is_finite()) {
        Ok(summary)
    } else {
        Err(AnalysisError::NonFiniteResult { what: "wavelength summary" })
    }
}

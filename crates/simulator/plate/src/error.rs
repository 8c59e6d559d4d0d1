//! The one error type of this crate.

use metaplate_dsp::DspError;

/// Why the plate model refused its input or could not produce a finite result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlateError {
    /// A parameter lies outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Parameter name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// An index (actuator, grid point) does not exist.
    #[error("{what} index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What was indexed.
        what: &'static str,
        /// The offending index.
        index: usize,
        /// How many there are.
        len: usize,
    },
    /// A requested position is not on the discretised plate (outside the outline, or in a sliver narrower than one
    /// grid cell), so the model has no displacement there.
    #[error("{what} {index} at ({x_m} m, {y_m} m) is not on the discretised plate")]
    OffPlate {
        /// What was placed there (a grid point, an actuator, a support).
        what: &'static str,
        /// Its index.
        index: usize,
        /// Its x, m.
        x_m: f64,
        /// Its y, m.
        y_m: f64,
    },
    /// The discretisation or the computation would need more memory than the model allows.
    #[error("{what} needs {needed}, more than the limit of {max}")]
    TooLarge {
        /// What was too large.
        what: &'static str,
        /// Requested size.
        needed: usize,
        /// Limit.
        max: usize,
    },
    /// The system matrix could not be factorised at this frequency (it is singular: an undamped, unsupported plate
    /// at a resonance, for example).
    #[error("the plate system at {freq_hz} Hz could not be solved: {reason}")]
    Solve {
        /// Frequency, Hz.
        freq_hz: f64,
        /// What the solver reported.
        reason: String,
    },
    /// A computation produced NaN or infinity although its inputs were finite: the inputs are outside the model's
    /// valid range.
    #[error("{what} produced a non-finite result; the input is outside the model's valid range")]
    NonFiniteResult {
        /// Which computation.
        what: &'static str,
    },
    /// Reading or writing the Green's-function cache failed.
    #[error("cache file {path}: {reason}")]
    Cache {
        /// The file.
        path: String,
        /// What went wrong.
        reason: String,
    },
    /// A signal-processing step refused its input.
    #[error(transparent)]
    Dsp(#[from] DspError),
}

impl PlateError {
    /// Shorthand for [`PlateError::InvalidParameter`].
    pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        Self::InvalidParameter { name, reason: reason.into() }
    }

    /// Shorthand for [`PlateError::Cache`] about the file or directory at `path`.
    pub(crate) fn cache(path: &std::path::Path, reason: impl ToString) -> Self {
        Self::Cache { path: path.display().to_string(), reason: reason.to_string() }
    }
}

/// Checks that `v` is finite and lies in `[lo, hi]`.
///
/// # Errors
/// [`PlateError::InvalidParameter`] naming `name`.
pub(crate) fn check_range(name: &'static str, v: f64, lo: f64, hi: f64) -> Result<f64, PlateError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(PlateError::invalid(name, format!("must be finite and within [{lo}, {hi}], got {v}")))
    }
}

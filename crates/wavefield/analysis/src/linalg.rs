//! Singular values through faer, with its failure mapped to this crate's error.

use faer::MatRef;
use num_complex::Complex64;

use crate::error::AnalysisError;

/// Singular values of a complex matrix, non-increasing.
pub(crate) fn singular_values_complex(m: MatRef<'_, Complex64>, what: &'static str) -> Result<Vec<f64>, AnalysisError> {
    checked(m.singular_values().map_err(|_| AnalysisError::NonFiniteResult { what })?, what)
}

/// Singular values of a real matrix, non-increasing.
pub(crate) fn singular_values_real(m: MatRef<'_, f64>, what: &'static str) -> Result<Vec<f64>, AnalysisError> {
    checked(m.singular_values().map_err(|_| AnalysisError::NonFiniteResult { what })?, what)
}

fn checked(s: Vec<f64>, what: &'static str) -> Result<Vec<f64>, AnalysisError> {
    if s.iter().all(|v| v.is_finite()) { Ok(s) } else { Err(AnalysisError::NonFiniteResult { what }) }
}

//! Order statistics of measured values: the one median that calibration designs against, checks against, and that
//! the ground truth and the scan's summaries report; quantiles (nearest rank) for error summaries and time estimates.

/// Median of `values` (sorted in place): the middle value, or the mean of the two middle values for an even count.
///
/// Valid range: any number of finite values. Returns `None` for an empty slice, or when a value is NaN or infinite
/// (a median of non-finite values would hide them).
pub fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let mid = values.len() / 2;
    // Halves summed rather than the sum halved: the same value wherever the sum does not overflow, and finite where
    // it would.
    Some(if values.len().is_multiple_of(2) { values[mid - 1] / 2.0 + values[mid] / 2.0 } else { values[mid] })
}

/// The value at quantile `q` of `values` (sorted in place), by nearest rank: the element at `round(q * (n - 1))`
/// of the sorted values, so every result is one of the values (`q = 0` the least, `q = 1` the greatest).
///
/// Valid range: `q` in 0..=1, any number of finite values. Returns `None` for an empty slice, a `q` outside 0..=1
/// or NaN, or when a value is NaN or infinite.
pub fn quantile(values: &mut [f64], q: f64) -> Option<f64> {
    if values.is_empty() || !(0.0..=1.0).contains(&q) || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    values.sort_unstable_by(f64::total_cmp);
    let last = values.len() - 1;
    values.get(((last as f64) * q).round() as usize).copied()
}

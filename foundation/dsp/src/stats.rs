//! Order statistics of measured values: the one median that calibration designs against, checks against, and that
//! the ground truth and the scan's summaries report.

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_one_empty_and_non_finite() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(&mut [7.5]), Some(7.5));
        assert_eq!(median(&mut []), None);
        assert_eq!(median(&mut [1.0, f64::NAN, 2.0]), None);
        assert_eq!(median(&mut [1.0, f64::INFINITY]), None);
        // Extremes of the f64 range stay exact (the mean of two equal huge values does not overflow to infinity).
        assert_eq!(median(&mut [f64::MAX, f64::MAX]), Some(f64::MAX));
        assert_eq!(median(&mut [-f64::MAX, f64::MAX]), Some(0.0));
    }
}

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

    #[test]
    fn quantile_by_nearest_rank_at_the_ends_and_refusals() {
        let mut v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(quantile(&mut v, 0.0), Some(1.0));
        assert_eq!(quantile(&mut v, 1.0), Some(5.0));
        assert_eq!(quantile(&mut v, 0.5), Some(3.0));
        // 0.9 x 4 = 3.6 rounds to rank 4, the fifth value; 0.8 x 4 = 3.2 to rank 3, the fourth.
        assert_eq!(quantile(&mut v, 0.9), Some(5.0));
        assert_eq!(quantile(&mut v, 0.8), Some(4.0));
        assert_eq!(quantile(&mut [7.0], 0.95), Some(7.0));
        assert_eq!(quantile(&mut [], 0.5), None);
        assert_eq!(quantile(&mut [1.0, 2.0], 1.5), None);
        assert_eq!(quantile(&mut [1.0, 2.0], -0.1), None);
        assert_eq!(quantile(&mut [1.0, 2.0], f64::NAN), None);
        assert_eq!(quantile(&mut [1.0, f64::NAN], 0.5), None);
        assert_eq!(quantile(&mut [-f64::MAX, f64::MAX], 1.0), Some(f64::MAX));
    }
}

use metaplate_dsp::stats::*;

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

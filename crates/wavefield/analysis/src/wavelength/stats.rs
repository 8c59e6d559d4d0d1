//! Weighted quantiles of a sample, for the wavelength distribution inside a half-maximum contour.

/// Quantiles `qs` (each in `[0, 1]`) of `values` with non-negative `weights`.
///
/// Each sample stands for a slab of probability centred on its cumulative weight (the midpoint rule); between
/// samples the quantile is interpolated linearly, below the first and above the last it is clamped. With equal
/// weights this is the Hazen quantile (`(i + 0.5) / n`). Returns `None` when there is no sample or no positive
/// total weight; callers turn that into a typed error.
pub(crate) fn weighted_quantiles(values: &[f64], weights: &[f64], qs: &[f64]) -> Option<Vec<f64>> {
    let mut pairs: Vec<(f64, f64)> =
        values.iter().zip(weights).filter(|(_, w)| **w > 0.0).map(|(v, w)| (*v, *w)).collect();
    let total: f64 = pairs.iter().map(|p| p.1).sum();
    if pairs.is_empty() || !(total > 0.0 && total.is_finite()) {
        return None;
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Cumulative midpoint positions in [0, 1].
    let mut positions = Vec::with_capacity(pairs.len());
    let mut cumulative = 0.0;
    for (_, w) in &pairs {
        positions.push((cumulative + 0.5 * w) / total);
        cumulative += w;
    }
    let quantile = |q: f64| {
        let upper = positions.partition_point(|&p| p < q);
        if upper == 0 {
            pairs[0].0
        } else if upper == pairs.len() {
            pairs[pairs.len() - 1].0
        } else {
            let (p0, p1) = (positions[upper - 1], positions[upper]);
            let (v0, v1) = (pairs[upper - 1].0, pairs[upper].0);
            let t = if p1 > p0 { (q - p0) / (p1 - p0) } else { 0.0 };
            v0 + t * (v1 - v0)
        }
    };
    Some(qs.iter().map(|&q| quantile(q)).collect())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn equal_weights_give_hazen_quantiles() {
        let v = [4.0, 1.0, 3.0, 2.0];
        let q = weighted_quantiles(&v, &[1.0; 4], &[0.5, 0.25, 0.75, 0.0, 1.0]).unwrap();
        // Hazen positions 0.125, 0.375, 0.625, 0.875: median midway between 2 and 3; quartiles at 1.5 and 3.5.
        assert!((q[0] - 2.5).abs() < 1e-12);
        assert!((q[1] - 1.5).abs() < 1e-12);
        assert!((q[2] - 3.5).abs() < 1e-12);
        assert_eq!(q[3], 1.0);
        assert_eq!(q[4], 4.0);
    }

    #[test]
    fn a_heavy_sample_pulls_the_median() {
        let q = weighted_quantiles(&[1.0, 2.0, 3.0], &[1.0, 1.0, 10.0], &[0.5]).unwrap();
        // Midpoints at 1.5 / 12 (value 2) and 7 / 12 (value 3): 0.5 lies 9 / 11 of the way from 2 to 3, far past
        // the unweighted median of 2.
        assert!((q[0] - (2.0 + 9.0 / 11.0)).abs() < 1e-12, "{q:?}");
    }

    #[test]
    fn empty_or_weightless_is_none() {
        assert!(weighted_quantiles(&[], &[], &[0.5]).is_none());
        assert!(weighted_quantiles(&[1.0], &[0.0], &[0.5]).is_none());
    }
}

//! The report's statistics: accuracy with a Wilson 95 % interval, the exact one-sided binomial p against chance,
//! and the confusion matrix.

use crate::error::ExperimentError;

/// The standard normal quantile of 97.5 % (two-sided 95 %).
const Z_95: f64 = 1.959_963_984_540_054;

/// Largest trial count [`binomial_p_at_least`] accepts: it sums `n - k + 1` terms.
pub const MAX_BINOMIAL_N: u64 = 10_000_000;

/// Accuracy of `correct` of `n` trials with its Wilson score 95 % interval `[lo, hi]` (Wilson 1927; statsmodels'
/// `proportion_confint(method="wilson")`). Both ends lie in `[0, 1]`; at 0 of n the interval starts at 0, at n of
/// n it ends at 1.
///
/// # Errors
/// [`ExperimentError::InvalidArgument`] when `n == 0` (no accuracy) or `correct > n`.
pub fn wilson_95(correct: u64, n: u64) -> Result<(f64, [f64; 2]), ExperimentError> {
    check_counts(correct, n)?;
    let (k, n) = (correct as f64, n as f64);
    let p = k / n;
    let z2 = Z_95 * Z_95;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = Z_95 / denom * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    Ok((p, [(centre - half).max(0.0), (centre + half).min(1.0)]))
}

/// The exact one-sided binomial p value `P(X >= correct)` for `X ~ Binomial(n, chance)` (scipy's
/// `binomtest(correct, n, chance, alternative="greater")`), with its base-10 logarithm.
///
/// Exact means the sum of the binomial terms, no normal approximation: terms are summed in log space, relative
/// error below 1e-9 for `1 <= n <= MAX_BINOMIAL_N`. A p value below f64's smallest normal number (1e-308, e.g. 500 of
/// 500 at chance 0.2: 10^-349.5) is returned as 0 with its exact logarithm in the second value.
///
/// # Errors
/// [`ExperimentError::InvalidArgument`] when `n == 0`, `correct > n`, `n > MAX_BINOMIAL_N`, or `chance` is not
/// strictly between 0 and 1.
pub fn binomial_p_at_least(correct: u64, n: u64, chance: f64) -> Result<(f64, f64), ExperimentError> {
    check_counts(correct, n)?;
    if n > MAX_BINOMIAL_N {
        return Err(ExperimentError::invalid_argument("n", format!("{n} trials is more than {MAX_BINOMIAL_N}")));
    }
    if !(chance.is_finite() && chance > 0.0 && chance < 1.0) {
        return Err(ExperimentError::invalid_argument("chance", format!("must be between 0 and 1, got {chance}")));
    }
    if correct == 0 {
        return Ok((1.0, 0.0));
    }
    let (ln_p, ln_q) = (chance.ln(), (-chance).ln_1p());
    // ln C(n, i) for i = correct.., built up from ln C(n, correct) = sum of ln((n - j) / (j + 1)), j < correct.
    let mut ln_choose: f64 = (0..correct).map(|j| ((n - j) as f64).ln() - ((j + 1) as f64).ln()).sum();
    let mut terms = Vec::with_capacity((n - correct + 1) as usize);
    for i in correct..=n {
        terms.push(ln_choose + i as f64 * ln_p + (n - i) as f64 * ln_q);
        if i < n {
            ln_choose += ((n - i) as f64).ln() - ((i + 1) as f64).ln();
        }
    }
    let max = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let ln_tail = (max + terms.iter().map(|t| (t - max).exp()).sum::<f64>().ln()).min(0.0);
    Ok((ln_tail.exp(), ln_tail / std::f64::consts::LN_10))
}

fn check_counts(correct: u64, n: u64) -> Result<(), ExperimentError> {
    if n == 0 {
        return Err(ExperimentError::invalid_argument("n", "no scored trials: accuracy is undefined"));
    }
    if correct > n {
        return Err(ExperimentError::invalid_argument("correct", format!("{correct} correct of {n} trials")));
    }
    Ok(())
}

/// Counts of answers against presentations: `counts[presented][answered]`, indices into `labels`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Confusion {
    /// The response labels, rows and columns in this order.
    pub labels: Vec<String>,
    /// `counts[presented][answered]`.
    pub counts: Vec<Vec<u64>>,
}

impl Confusion {
    /// An empty matrix over `labels`.
    pub fn new(labels: &[String]) -> Self {
        Self { labels: labels.to_vec(), counts: vec![vec![0; labels.len()]; labels.len()] }
    }

    /// Counts one trial.
    ///
    /// # Errors
    /// [`ExperimentError::InvalidArgument`] when either label is not in the matrix.
    pub fn add(&mut self, presented: &str, answered: &str) -> Result<(), ExperimentError> {
        let index = |l: &str| {
            self.labels.iter().position(|x| x == l).ok_or_else(|| {
                ExperimentError::invalid_argument("label", format!("`{l}` is not one of {}", self.labels.join(", ")))
            })
        };
        let (p, a) = (index(presented)?, index(answered)?);
        self.counts[p][a] += 1;
        Ok(())
    }

    /// The diagonal's sum: trials answered correctly.
    pub fn correct(&self) -> u64 {
        (0..self.labels.len()).map(|i| self.counts[i][i]).sum()
    }

    /// All trials counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().flatten().sum()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(f64::MIN_POSITIVE)
    }

    // Known values: the upper tails are sums of exact rationals (Python's fractions.Fraction over math.comb, the
    // quantity scipy.stats.binomtest(k, n, p, alternative="greater").pvalue computes), printed as float and log10.
    #[test]
    fn binomial_tails_match_exact_rational_sums() {
        let cases: &[(u64, u64, f64, f64, f64)] = &[
            (5, 10, 0.2, 0.0327934976, -1.484212261056376),
            (3, 10, 0.2, 0.3222004736, -0.4918738255502104),
            (10, 10, 0.2, 1.024e-07, -6.989700043360188),
            (120, 500, 0.2, 0.01609180349401462, -1.7933952794804213),
            (60, 300, 0.2, 0.5230223389694073, -0.281479761450214),
            // The paper's pooled results: experiment 4 (429 of 450), experiment 3 (789 of 800 at 50 %).
            (429, 450, 0.2, 8.229778127524306e-267, -266.08461187308546),
            (789, 800, 0.5, 3.054429147408723e-217, -216.5150699446018),
        ];
        for &(k, n, chance, p, log10_p) in cases {
            let (got, got_log) = binomial_p_at_least(k, n, chance).unwrap();
            assert!(close(got, p, 1e-9), "{k}/{n}: {got} vs {p}");
            assert!((got_log - log10_p).abs() < 1e-9, "{k}/{n}: {got_log} vs {log10_p}");
        }
        // Experiment 1's 493 of 500 at 20 %: 10^-330.097, below f64's range: 0 with the exact logarithm.
        let (p, log10_p) = binomial_p_at_least(493, 500, 0.2).unwrap();
        assert_eq!(p, 0.0);
        assert!((log10_p - -330.09700222805765).abs() < 1e-8, "{log10_p}");
        // 500 of 500: chance^500.
        let (_, log10_p) = binomial_p_at_least(500, 500, 0.2).unwrap();
        assert!((log10_p - 500.0 * 0.2f64.log10()).abs() < 1e-9);
        assert_eq!(binomial_p_at_least(0, 10, 0.2).unwrap(), (1.0, 0.0));
        assert!(binomial_p_at_least(0, 0, 0.2).is_err());
        assert!(binomial_p_at_least(11, 10, 0.2).is_err());
        assert!(binomial_p_at_least(5, 10, 1.0).is_err());
        assert!(binomial_p_at_least(5, 10, f64::NAN).is_err());
        assert!(binomial_p_at_least(5, MAX_BINOMIAL_N + 1, 0.5).is_err());
    }

    // Known values: the Wilson score interval at z = 1.959963984540054 (statsmodels' proportion_confint(k, n,
    // method="wilson")), computed by hand from Wilson's formula in Python; 5 of 10 gives the textbook (0.2366, 0.7634).
    #[test]
    fn wilson_intervals_match_known_values() {
        let cases: &[(u64, u64, [f64; 2])] = &[
            (493, 500, [0.9713869308622147, 0.9932022102091564]),
            (5, 10, [0.236593090512564, 0.7634069094874361]),
            (429, 450, [0.9297150753265546, 0.9692772755710186]),
            (0, 10, [0.0, 0.2775327998628892]),
            (10, 10, [0.7224672001371107, 1.0]),
        ];
        for &(k, n, [lo, hi]) in cases {
            let (acc, [got_lo, got_hi]) = wilson_95(k, n).unwrap();
            assert_eq!(acc, k as f64 / n as f64);
            assert!((got_lo - lo).abs() < 1e-12 && (got_hi - hi).abs() < 1e-12, "{k}/{n}: {got_lo} {got_hi}");
        }
        assert!(matches!(wilson_95(0, 0), Err(ExperimentError::InvalidArgument { name: "n", .. })));
        assert!(wilson_95(3, 2).is_err());
    }

    #[test]
    fn the_confusion_matrix_counts_answers_against_presentations() {
        let labels: Vec<String> = ["l", "r"].iter().map(|s| (*s).to_owned()).collect();
        let mut c = Confusion::new(&labels);
        for (p, a) in [("l", "l"), ("l", "r"), ("r", "r"), ("r", "r")] {
            c.add(p, a).unwrap();
        }
        assert_eq!(c.counts, [[1, 1], [0, 2]]);
        assert_eq!((c.correct(), c.total()), (3, 4));
        assert!(c.add("up", "l").is_err());
    }
}

//! Which channel drives which magnet, by reciprocity: a passive plate's response from actuator `a` to magnet `b`
//! equals the one from `b` to `a` up to the two coils' gains, and a swap of two cables breaks that in a way that
//! names the pair (see the pre-flight's `actuator_wiring` check).

use super::signals::db_ratio;

/// A pair's responses must agree to this, dB (error energy over the response's, after the best gain): a passive
/// plate's are reciprocal, so what is left is the coils' gain spread (fitted away), noise and the coils' small
/// nonlinearity.
pub(super) const RECIPROCITY_LIMIT_DB: f64 = -15.0;

/// The reciprocity of the responses `r[i][j]` (beam on magnet `i`, channel wired to actuator `j`), pair by pair:
/// as wired, `r[a][b]` against `r[b][a]`; and as if `a` and `b` were swapped (then `r[a][a]` and `r[b][b]` are the
/// transfer responses between them, and must agree).
pub(super) struct Reciprocity {
    /// Per pair `a < b`, in order: the error of `r[a][b]` against `r[b][a]`, dB.
    pub(super) as_wired_db: Vec<f64>,
    /// Per pair: the error of `r[a][a]` against `r[b][b]`, dB.
    pub(super) if_swapped_db: Vec<f64>,
    pairs: Vec<(usize, usize)>,
}

impl Reciprocity {
    pub(super) fn of(r: &[Vec<Vec<f64>>]) -> Self {
        let n = r.len();
        let pairs: Vec<(usize, usize)> = (0..n).flat_map(|a| (a + 1..n).map(move |b| (a, b))).collect();
        let at = |i: usize, j: usize| r.get(i).and_then(|row| row.get(j)).map_or(&[][..], Vec::as_slice);
        Self {
            as_wired_db: pairs.iter().map(|&(a, b)| gain_fit_error_db(at(a, b), at(b, a))).collect(),
            if_swapped_db: pairs.iter().map(|&(a, b)| gain_fit_error_db(at(a, a), at(b, b))).collect(),
            pairs,
        }
    }

    /// Pairs that are reciprocal only if swapped, each actuator in one pair at most (the clearest first).
    pub(super) fn swapped_pairs(&self) -> Vec<(usize, usize)> {
        let mut candidates: Vec<(f64, (usize, usize))> = self
            .pairs
            .iter()
            .enumerate()
            .filter(|&(i, _)| {
                self.as_wired_db[i] > RECIPROCITY_LIMIT_DB && self.if_swapped_db[i] <= RECIPROCITY_LIMIT_DB
            })
            .map(|(i, &pair)| (self.if_swapped_db[i], pair))
            .collect();
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut taken: Vec<(usize, usize)> = Vec::new();
        for (_, (a, b)) in candidates {
            if !taken.iter().any(|&(c, d)| [c, d].contains(&a) || [c, d].contains(&b)) {
                taken.push((a, b));
            }
        }
        taken.sort_unstable();
        taken
    }

    /// Pairs that are not reciprocal as wired: (a, b, error dB).
    pub(super) fn unexplained(&self) -> Vec<(usize, usize, f64)> {
        self.pairs
            .iter()
            .zip(&self.as_wired_db)
            .filter(|&(_, &e)| e > RECIPROCITY_LIMIT_DB)
            .map(|(&(a, b), &e)| (a, b, e))
            .collect()
    }

    pub(super) fn worst_as_wired_db(&self) -> f64 {
        self.as_wired_db.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }
}

/// How far `x` is from `y` after the best real gain `g` (least squares): `10 log10(|x - g y|^2 / |x|^2)`, dB; 0 dB
/// (no agreement) when either is silent or the gain is not positive (a sign flip is not a coil's spread).
fn gain_fit_error_db(x: &[f64], y: &[f64]) -> f64 {
    let xy: f64 = x.iter().zip(y).map(|(a, b)| a * b).sum();
    let yy: f64 = y.iter().map(|b| b * b).sum();
    let xx: f64 = x.iter().map(|a| a * a).sum();
    if x.len() != y.len() || xx <= 0.0 || yy <= 0.0 || xy <= 0.0 {
        return 0.0;
    }
    let g = xy / yy;
    let residual: f64 = x.iter().zip(y).map(|(a, b)| (a - g * b).powi(2)).sum();
    db_ratio(residual, xx).min(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gain_is_fitted_away_and_a_shape_or_sign_is_not() {
        let x: Vec<f64> = (0..100).map(|i| (f64::from(i) * 0.3).sin() * (-f64::from(i) / 40.0).exp()).collect();
        let louder: Vec<f64> = x.iter().map(|v| 1.4 * v).collect();
        assert!(gain_fit_error_db(&x, &louder) < -100.0);
        let flipped: Vec<f64> = x.iter().map(|v| -v).collect();
        assert_eq!(gain_fit_error_db(&x, &flipped), 0.0);
        let other: Vec<f64> = (0..100).map(|i| (f64::from(i) * 0.7).cos() * (-f64::from(i) / 40.0).exp()).collect();
        assert!(gain_fit_error_db(&x, &other) > -6.0);
        assert_eq!(gain_fit_error_db(&x, &[]), 0.0);
        assert_eq!(gain_fit_error_db(&[0.0; 3], &[1.0; 3]), 0.0);
    }

    /// Responses of a symmetric 3 x 3 "plate" with distinct driving points, read through a channel permutation.
    fn responses(permutation: [usize; 3]) -> Vec<Vec<Vec<f64>>> {
        let y = |i: usize, j: usize| -> Vec<f64> {
            let (lo, hi) = (i.min(j) as f64, i.max(j) as f64);
            (0..64).map(|t| (f64::from(t) * (0.2 + 0.1 * lo + 0.05 * hi)).sin() / (1.0 + lo + 2.0 * hi)).collect()
        };
        (0..3).map(|i| (0..3).map(|j| y(i, permutation[j])).collect()).collect()
    }

    #[test]
    fn reciprocity_names_a_swapped_pair_and_passes_a_correct_wiring() {
        let wired = Reciprocity::of(&responses([0, 1, 2]));
        assert!(wired.swapped_pairs().is_empty() && wired.unexplained().is_empty());
        let swapped = Reciprocity::of(&responses([0, 2, 1]));
        assert_eq!(swapped.swapped_pairs(), [(1, 2)]);
    }
}

//! Coherent averaging of repetitions, and the signal-to-noise ratio their spread reveals.
//!
//! The repetitions of a measurement carry the same signal and independent noise. Their (weighted) mean keeps the
//! signal and divides the noise power by the total weight; the spread of the repetitions around the mean measures
//! that noise without knowing the signal.
//!
//! Estimator, for `K` repetitions `x_k` with weights `w_k` proportional to the inverse of their noise variance
//! (equal weights when all have the same noise):
//! - mean `m = sum_k w_k x_k / W`, with `W = sum_k w_k`;
//! - noise energy of one unit-weight repetition `s2 = sum_k w_k |x_k - m|^2 / (K - 1)` (unbiased for independent
//!   zero-mean noise; needs `K >= 2`, with `K = 1` there is no spread and no estimate);
//! - noise energy left in the mean `s2 / W`; signal energy of the mean `|m|^2 - s2 / W` (the noise bias removed,
//!   floored at zero); SNR of the mean = signal energy / noise energy.
//!
//! `|.|^2` sums over the samples, each weighted by an optional per-sample gain squared (a band limit on spectra).

use std::ops::{Add, Mul, Sub};

use num_complex::Complex64;

use crate::error::DspError;

/// A coherent average and, from two repetitions on, the noise and signal energies estimated from the spread.
#[derive(Debug, Clone, PartialEq)]
pub struct Average<T> {
    /// The weighted mean of the repetitions, sample by sample.
    pub mean: Vec<T>,
    /// Noise energy left in the mean (sum over samples of gain^2 |noise|^2); `None` with a single repetition.
    pub noise_energy: Option<f64>,
    /// Signal energy of the mean with the noise bias removed, floored at 0; `None` with a single repetition.
    pub signal_energy: Option<f64>,
}

impl<T> Average<T> {
    /// SNR of the mean, dB: signal energy over noise energy.
    ///
    /// `None` when it cannot be estimated: a single repetition (no spread), identical repetitions (no noise seen, the
    /// SNR is unbounded), or no signal above the noise bias (the SNR is below what the spread can resolve).
    pub fn snr_db(&self) -> Option<f64> {
        match (self.signal_energy, self.noise_energy) {
            (Some(s), Some(n)) if s > 0.0 && n > 0.0 => Some(10.0 * (s / n).log10()),
            _ => None,
        }
    }
}

/// Plain mean of equally noisy repetitions of a real signal. See [`weighted_average`].
///
/// # Errors
/// As [`weighted_average`].
pub fn average(repetitions: &[&[f64]]) -> Result<Average<f64>, DspError> {
    weighted_average(repetitions, &vec![1.0; repetitions.len()])
}

/// Weighted mean of repetitions of a real signal, with the noise and signal energies estimated from their spread
/// (see the module documentation for the estimator).
///
/// Valid range: at least one repetition, all of the same non-zero length and finite; one weight per repetition,
/// finite and positive (proportional to the inverse of the repetition's noise variance). The energies must stay
/// below f64 overflow (samples below about 1e150).
///
/// # Errors
/// [`DspError::Empty`] (no repetition, or empty ones), [`DspError::LengthMismatch`] (lengths differ, or the weight
/// count differs from the repetition count), [`DspError::NonFinite`], [`DspError::InvalidParameter`] (a weight not
/// finite and positive), [`DspError::NonFiniteResult`] (overflow).
pub fn weighted_average(repetitions: &[&[f64]], weights: &[f64]) -> Result<Average<f64>, DspError> {
    average_impl(repetitions, weights, None)
}

/// Weighted mean of the spectra of repetitions, with the noise and signal energies estimated from their spread,
/// counting each bin with `bin_gains[b]^2` (a band limit) or 1 when `bin_gains` is `None`.
///
/// Valid range: as [`weighted_average`]; `bin_gains`, when given, has one finite gain `>= 0` per bin.
///
/// # Errors
/// As [`weighted_average`]; [`DspError::LengthMismatch`] or [`DspError::InvalidParameter`] for bad `bin_gains`.
pub fn average_spectra(
    spectra: &[&[Complex64]],
    weights: &[f64],
    bin_gains: Option<&[f64]>,
) -> Result<Average<Complex64>, DspError> {
    average_impl(spectra, weights, bin_gains)
}

/// What the averaging needs of a sample: arithmetic, its power, and a finiteness check.
trait Sample: Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self> {
    fn power(self) -> f64;
    fn is_finite(self) -> bool;
    /// 0 for a finite sample, NaN otherwise (each component times 0, summed).
    fn zero_probe(self) -> f64;
}

impl Sample for f64 {
    fn power(self) -> f64 {
        self * self
    }
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    fn zero_probe(self) -> f64 {
        self * 0.0
    }
}

impl Sample for Complex64 {
    fn power(self) -> f64 {
        self.norm_sqr()
    }
    fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
    fn zero_probe(self) -> f64 {
        self.re * 0.0 + self.im * 0.0
    }
}

/// True when every sample is finite: a NaN probe survives any sum, so one pass without early exit decides, in
/// four partial sums the compiler keeps in vector registers.
fn all_finite<T: Sample>(x: &[T]) -> bool {
    let mut acc = [0.0f64; 4];
    let (chunks, rest) = x.as_chunks::<4>();
    for c in chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v.zero_probe();
        }
    }
    rest.iter().all(|v| v.is_finite()) && acc.iter().sum::<f64>() == 0.0
}

/// Bins `first..last` outside which every gain is 0 (all bins without gains): only they count in the energies.
fn weighted_bins(n: usize, bin_gains: Option<&[f64]>) -> std::ops::Range<usize> {
    match bin_gains {
        None => 0..n,
        Some(g) => match (g.iter().position(|&v| v > 0.0), g.iter().rposition(|&v| v > 0.0)) {
            (Some(first), Some(last)) => first..last + 1,
            _ => 0..0,
        },
    }
}

fn average_impl<T: Sample>(
    repetitions: &[&[T]],
    weights: &[f64],
    bin_gains: Option<&[f64]>,
) -> Result<Average<T>, DspError> {
    let n = check_repetitions(repetitions)?;
    if weights.len() != repetitions.len() {
        return Err(DspError::LengthMismatch {
            what: "weights against repetitions",
            a: weights.len(),
            b: repetitions.len(),
        });
    }
    if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(DspError::InvalidParameter {
            name: "weights",
            reason: format!("must be finite and positive, got {} for repetition {i}", weights[i]),
        });
    }
    if let Some(gains) = bin_gains {
        if gains.len() != n {
            return Err(DspError::LengthMismatch { what: "bin gains against samples", a: gains.len(), b: n });
        }
        if let Some(i) = gains.iter().position(|g| !(g.is_finite() && *g >= 0.0)) {
            return Err(DspError::InvalidParameter {
                name: "bin_gains",
                reason: format!("must be finite and >= 0, got {} at bin {i}", gains[i]),
            });
        }
    }
    let total_weight: f64 = weights.iter().sum();
    let mut mean = vec![T::default(); n];
    for (rep, &w) in repetitions.iter().zip(weights) {
        for (m, &x) in mean.iter_mut().zip(rep.iter()) {
            *m = *m + x * (w / total_weight);
        }
    }
    // Bins of zero gain add exactly 0 to the energies: skipping them (most of the bins for a narrow band) changes
    // no sum.
    let bins = weighted_bins(n, bin_gains);
    let gain2 = |k: usize| bin_gains.map_or(1.0, |g| g[k] * g[k]);
    let (noise_energy, signal_energy) = if repetitions.len() < 2 {
        (None, None)
    } else {
        let spread: f64 = repetitions
            .iter()
            .zip(weights)
            .map(|(rep, &w)| w * bins.clone().map(|k| gain2(k) * (rep[k] - mean[k]).power()).sum::<f64>())
            .sum();
        let noise = spread / (repetitions.len() - 1) as f64 / total_weight;
        let mean_energy: f64 = bins.map(|k| gain2(k) * mean[k].power()).sum();
        (Some(noise), Some((mean_energy - noise).max(0.0)))
    };
    let finite =
        all_finite(&mean) && noise_energy.is_none_or(f64::is_finite) && signal_energy.is_none_or(f64::is_finite);
    if !finite {
        return Err(DspError::NonFiniteResult { what: "coherent average" });
    }
    Ok(Average { mean, noise_energy, signal_energy })
}

/// Checks that there is at least one repetition, all finite, non-empty and of one length; returns that length.
fn check_repetitions<T: Sample>(repetitions: &[&[T]]) -> Result<usize, DspError> {
    let first = repetitions.first().ok_or(DspError::Empty { input: "repetitions" })?;
    let n = first.len();
    if n == 0 {
        return Err(DspError::Empty { input: "repetition" });
    }
    for rep in repetitions {
        if rep.len() != n {
            return Err(DspError::LengthMismatch { what: "repetitions", a: n, b: rep.len() });
        }
        if !all_finite(rep) {
            let index = rep.iter().position(|x| !x.is_finite()).unwrap_or(0);
            return Err(DspError::NonFinite { input: "repetition", index, value: f64::NAN });
        }
    }
    Ok(n)
}

//! Windows and fades, as gain vectors to multiply a signal by.
//!
//! Two conventions, chosen per use:
//! - symmetric: `w[i] == w[n - 1 - i]`, the first and last samples are the window's ends (0 for Hann, Blackman); use
//!   it to taper a finite segment (an impulse response, a filter's taps);
//! - periodic: one period of an `n`-periodic window, as if the symmetric window of length `n + 1` had lost its last
//!   sample; use it for spectral analysis frames that are overlapped and added.
//!
//! Every length is valid: `n = 0` gives an empty vector and `n = 1` gives `[1.0]` (a single sample passes untouched,
//! as in NumPy and SciPy).

use std::f64::consts::PI;

use crate::error::DspError;

/// Which convention a cosine-sum window follows (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// `w[i] == w[n - 1 - i]`, both ends at the window's minimum.
    Symmetric,
    /// One period of the `n`-periodic window: only `w[0]` sits at the minimum.
    Periodic,
}

/// Generalised cosine window `sum_k (-1)^k a_k cos(2 pi k i / m)`, where `m = n - 1` (symmetric) or `n` (periodic).
fn cosine_sum(n: usize, coefficients: &[f64], symmetry: Symmetry) -> Vec<f64> {
    if n <= 1 {
        return vec![1.0; n];
    }
    let m = match symmetry {
        Symmetry::Symmetric => n - 1,
        Symmetry::Periodic => n,
    } as f64;
    (0..n)
        .map(|i| {
            let phase = 2.0 * PI * i as f64 / m;
            coefficients.iter().enumerate().fold(0.0, |acc, (k, a)| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                acc + sign * a * (k as f64 * phase).cos()
            })
        })
        .collect()
}

/// Hann window of `n` samples: `0.5 - 0.5 cos(2 pi i / m)`, gains in `[0, 1]`.
///
/// Symmetric: 0 at both ends, 1 in the middle for odd `n`. Periodic: 0 at `i = 0`, 1 at `i = n / 2` for even `n`.
/// Valid for every `n` (`0` gives empty, `1` gives `[1.0]`).
pub fn hann(n: usize, symmetry: Symmetry) -> Vec<f64> {
    cosine_sum(n, &[0.5, 0.5], symmetry)
}

/// Blackman window of `n` samples: `0.42 - 0.5 cos(2 pi i / m) + 0.08 cos(4 pi i / m)`, gains in `[0, 1]`.
///
/// Lower side lobes (-58 dB) than Hann (-31 dB) for a wider main lobe. Its ends are 0 up to rounding (the
/// coefficients sum to exactly zero only in exact arithmetic; the value is about 1e-17). Valid for every `n`.
pub fn blackman(n: usize, symmetry: Symmetry) -> Vec<f64> {
    cosine_sum(n, &[0.42, 0.5, 0.08], symmetry)
}

/// Symmetric Tukey (tapered-cosine) window of `n` samples: flat at 1 in the middle, with half-Hann tapers covering
/// a fraction `taper_ratio / 2` of the window at each end.
///
/// `taper_ratio = 0` is the rectangular window (all ones); `taper_ratio = 1` is the symmetric Hann window. The
/// position of sample `i` is `x = min(i, n - 1 - i) / (n - 1)`, so the window is symmetric to the last bit.
///
/// # Errors
/// [`DspError::InvalidParameter`] unless `0 <= taper_ratio <= 1`.
pub fn tukey(n: usize, taper_ratio: f64) -> Result<Vec<f64>, DspError> {
    if !(0.0..=1.0).contains(&taper_ratio) {
        return Err(DspError::InvalidParameter {
            name: "taper_ratio",
            reason: format!("must lie in [0, 1], got {taper_ratio}"),
        });
    }
    if n <= 1 || taper_ratio == 0.0 {
        return Ok(vec![1.0; n]);
    }
    let last = (n - 1) as f64;
    let half_taper = taper_ratio / 2.0;
    Ok((0..n)
        .map(|i| {
            let x = i.min(n - 1 - i) as f64 / last;
            if x < half_taper { 0.5 * (1.0 - (PI * x / half_taper).cos()) } else { 1.0 }
        })
        .collect())
}

/// Half-Hann fade-in of `n` samples: `0.5 - 0.5 cos(pi i / n)`, rising from exactly 0 at `i = 0` towards 1 (which the
/// sample just after the fade reaches), so a fade followed by ones is a smooth raised cosine. Valid for every `n`.
pub fn fade_in(n: usize) -> Vec<f64> {
    (0..n).map(|i| 0.5 * (1.0 - (PI * i as f64 / n as f64).cos())).collect()
}

/// Half-Hann fade-out of `n` samples: the mirror image of [`fade_in`], falling from just below 1 to exactly 0 at the
/// last sample. Valid for every `n`.
pub fn fade_out(n: usize) -> Vec<f64> {
    let mut w = fade_in(n);
    w.reverse();
    w
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.
mod tests {
    use super::*;

    // Rounding of cos() near multiples of pi: a few ulps, 1e-15 is safe and still catches any formula slip.
    const TOL: f64 = 1e-15;

    fn assert_symmetric(w: &[f64]) {
        let n = w.len();
        for i in 0..n {
            assert!((w[i] - w[n - 1 - i]).abs() <= TOL, "w[{i}] = {} vs w[{}] = {}", w[i], n - 1 - i, w[n - 1 - i]);
        }
    }

    #[test]
    fn tiny_lengths() {
        for sym in [Symmetry::Symmetric, Symmetry::Periodic] {
            assert!(hann(0, sym).is_empty());
            assert!(blackman(0, sym).is_empty());
            assert_eq!(hann(1, sym), vec![1.0]);
            assert_eq!(blackman(1, sym), vec![1.0]);
        }
        assert_eq!(hann(2, Symmetry::Symmetric), vec![0.0, 0.0]);
        let p = hann(2, Symmetry::Periodic);
        assert!(p[0].abs() <= TOL && (p[1] - 1.0).abs() <= TOL);
        assert!(tukey(0, 0.5).unwrap().is_empty());
        assert_eq!(tukey(1, 0.5).unwrap(), vec![1.0]);
        assert_eq!(tukey(2, 1.0).unwrap(), vec![0.0, 0.0]);
        assert!(fade_in(0).is_empty());
        assert_eq!(fade_in(1), vec![0.0]);
        assert_eq!(fade_out(1), vec![0.0]);
        let f = fade_in(2);
        assert!(f[0] == 0.0 && (f[1] - 0.5).abs() <= TOL);
    }

    #[test]
    fn symmetric_windows_are_symmetric_with_zero_ends_and_unit_middle() {
        for n in [3usize, 4, 5, 64, 65, 1001] {
            for w in [hann(n, Symmetry::Symmetric), blackman(n, Symmetry::Symmetric), tukey(n, 0.3).unwrap()] {
                assert_eq!(w.len(), n);
                assert_symmetric(&w);
                assert!(w[0].abs() <= TOL, "n = {n}: end {}", w[0]);
                assert!(w.iter().all(|v| (-TOL..=1.0 + TOL).contains(v)));
            }
            if n % 2 == 1 {
                assert!((hann(n, Symmetry::Symmetric)[n / 2] - 1.0).abs() <= TOL);
                assert!((blackman(n, Symmetry::Symmetric)[n / 2] - 1.0).abs() <= TOL);
            }
        }
    }

    #[test]
    fn periodic_is_symmetric_of_one_more_sample_without_its_last() {
        for n in [2usize, 7, 64] {
            for (p, s) in [
                (hann(n, Symmetry::Periodic), hann(n + 1, Symmetry::Symmetric)),
                (blackman(n, Symmetry::Periodic), blackman(n + 1, Symmetry::Symmetric)),
            ] {
                for i in 0..n {
                    assert!((p[i] - s[i]).abs() <= TOL);
                }
            }
            // Periodic Hann windows overlapped by half sum to exactly 1 (constant overlap-add).
            if n % 2 == 0 {
                let p = hann(n, Symmetry::Periodic);
                for i in 0..n / 2 {
                    assert!((p[i] + p[i + n / 2] - 1.0).abs() <= TOL);
                }
            }
        }
    }

    #[test]
    fn tukey_extremes_are_rectangular_and_hann() {
        assert!(tukey(33, 0.0).unwrap().iter().all(|&v| v == 1.0));
        let t = tukey(33, 1.0).unwrap();
        let h = hann(33, Symmetry::Symmetric);
        for (a, b) in t.iter().zip(&h) {
            assert!((a - b).abs() <= TOL);
        }
        // Ratio 0.5 on 101 samples: tapers cover x < 0.25, i.e. 25 samples each side; the middle is exactly flat.
        let t = tukey(101, 0.5).unwrap();
        assert!(t[24] < 1.0);
        assert!(t[25..=75].iter().all(|&v| v == 1.0));
        for bad in [-0.1, 1.1, f64::NAN] {
            assert!(matches!(tukey(8, bad), Err(DspError::InvalidParameter { .. })));
        }
    }

    #[test]
    fn fades_mirror_each_other_and_join_smoothly() {
        let n = 50;
        let (a, b) = (fade_in(n), fade_out(n));
        assert_eq!(a[0], 0.0);
        assert_eq!(b[n - 1], 0.0);
        for i in 0..n {
            assert_eq!(a[i], b[n - 1 - i]);
        }
        assert!(a.windows(2).all(|w| w[1] > w[0]), "fade-in rises strictly");
        // The step to the 1.0 after the fade equals the fade's first step (raised-cosine symmetry), so no kink.
        assert!(((1.0 - a[n - 1]) - a[1]).abs() <= TOL);
    }
}

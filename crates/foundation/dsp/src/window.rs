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

//! Linear convolution by FFT.

use num_complex::Complex64;

use crate::error::{DspError, check_result, check_signal};
use crate::fft;

/// Full linear convolution of `a` and `b`: `a.len() + b.len() - 1` samples, computed by FFT at a fast length so it
/// cannot wrap around.
///
/// Valid for any finite inputs whose combined length stays within [`fft::MAX_FFT_LEN`].
///
/// # Errors
/// An empty or non-finite input, or a combined length above the FFT limit.
pub fn convolve(a: &[f64], b: &[f64]) -> Result<Vec<f64>, DspError> {
    check_signal("convolution input a", a)?;
    check_signal("convolution input b", b)?;
    let out_len = a.len() + b.len() - 1;
    let n = fft::fast_len(out_len)?;
    let fa = fft::forward(a, n)?;
    let fb = fft::forward(b, n)?;
    let product: Vec<Complex64> = fa.iter().zip(&fb).map(|(x, y)| x * y).collect();
    let mut y = fft::inverse(&product, n)?;
    y.truncate(out_len);
    check_result("convolution", &y)?;
    Ok(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_direct_convolution() {
        let a = [1.0, -2.0, 3.0, 0.5];
        let b = [0.25, 1.0, -1.0];
        let mut direct = vec![0.0; a.len() + b.len() - 1];
        for (i, x) in a.iter().enumerate() {
            for (j, y) in b.iter().enumerate() {
                direct[i + j] += x * y;
            }
        }
        let fast = convolve(&a, &b).unwrap();
        assert_eq!(fast.len(), direct.len());
        for (f, d) in fast.iter().zip(&direct) {
            assert!((f - d).abs() < 1e-12);
        }
    }

    #[test]
    fn refuses_empty_and_nan() {
        assert!(matches!(convolve(&[], &[1.0]), Err(DspError::Empty { .. })));
        assert!(matches!(convolve(&[1.0], &[f64::INFINITY]), Err(DspError::NonFinite { .. })));
    }
}

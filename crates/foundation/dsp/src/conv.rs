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

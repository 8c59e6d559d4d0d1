//! Real FFTs of any length (realfft/rustfft), with plans cached per thread.
//!
//! Valid range: lengths 1 to [`MAX_FFT_LEN`]. Any length works, primes included (rustfft falls back to Rader and
//! Bluestein); [`fast_len`] gives the next length with only small prime factors when the caller may pad.

use std::cell::RefCell;

use num_complex::Complex64;
use realfft::RealFftPlanner;

use crate::error::{DspError, check_finite};

/// The largest FFT length accepted: 2^25 samples (256 MiB of f64 per buffer). Longer transforms are refused rather
/// than risking an allocation the machine cannot hold.
pub const MAX_FFT_LEN: usize = 1 << 25;

thread_local! {
    static PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
}

fn check_len(n: usize) -> Result<(), DspError> {
    if n == 0 {
        return Err(DspError::InvalidParameter { name: "fft_len", reason: "must be at least 1".into() });
    }
    if n > MAX_FFT_LEN {
        return Err(DspError::TooLong { what: "FFT", len: n, max: MAX_FFT_LEN });
    }
    Ok(())
}

/// Number of bins of a real FFT of length `n`: `n / 2 + 1`.
pub fn bin_count(n: usize) -> usize {
    n / 2 + 1
}

/// Frequency in Hz of bin `k` of a length-`n` FFT at `sample_rate_hz`.
pub fn bin_freq_hz(k: usize, n: usize, sample_rate_hz: f64) -> f64 {
    k as f64 * sample_rate_hz / n as f64
}

/// Forward real FFT of `x`, zero-padded (or truncated) to `n` samples; returns the `n / 2 + 1` non-negative
/// frequency bins, unnormalised.
///
/// # Errors
/// `n` of 0 or above [`MAX_FFT_LEN`]; a non-finite sample in `x` ([`DspError::NonFinite`]).
pub fn forward(x: &[f64], n: usize) -> Result<Vec<Complex64>, DspError> {
    check_len(n)?;
    check_finite("FFT input", x)?;
    let mut input = vec![0.0; n];
    let copied = x.len().min(n);
    input[..copied].copy_from_slice(&x[..copied]);
    let mut output = vec![Complex64::new(0.0, 0.0); bin_count(n)];
    PLANNER.with(|planner| {
        let plan = planner.borrow_mut().plan_fft_forward(n);
        // Lengths were set up from the plan's own n: process only fails on a length mismatch.
        plan.process(&mut input, &mut output)
            .map_err(|e| DspError::InvalidParameter { name: "fft buffers", reason: e.to_string() })
    })?;
    Ok(output)
}

/// Inverse real FFT: `n / 2 + 1` bins back to `n` samples, normalised by `1 / n` so that
/// `inverse(&forward(x, n)?, n)? == x` to rounding.
///
/// The imaginary parts of the DC bin (and of the Nyquist bin for even `n`) cannot belong to a real signal and are
/// ignored.
///
/// # Errors
/// `n` out of range; `spectrum.len() != n / 2 + 1` ([`DspError::LengthMismatch`]); a non-finite bin.
pub fn inverse(spectrum: &[Complex64], n: usize) -> Result<Vec<f64>, DspError> {
    check_len(n)?;
    if spectrum.len() != bin_count(n) {
        return Err(DspError::LengthMismatch {
            what: "inverse FFT bins against n / 2 + 1",
            a: spectrum.len(),
            b: bin_count(n),
        });
    }
    if let Some(index) = spectrum.iter().position(|c| !(c.re.is_finite() && c.im.is_finite())) {
        return Err(DspError::NonFinite { input: "inverse FFT spectrum", index, value: f64::NAN });
    }
    let mut bins = spectrum.to_vec();
    bins[0].im = 0.0;
    if n.is_multiple_of(2) {
        let last = bins.len() - 1;
        bins[last].im = 0.0;
    }
    let mut output = vec![0.0; n];
    PLANNER.with(|planner| {
        let plan = planner.borrow_mut().plan_fft_inverse(n);
        plan.process(&mut bins, &mut output)
            .map_err(|e| DspError::InvalidParameter { name: "inverse fft buffers", reason: e.to_string() })
    })?;
    let scale = 1.0 / n as f64;
    output.iter_mut().for_each(|v| *v *= scale);
    Ok(output)
}

/// Smallest length `>= min_len` whose prime factors are all 2, 3, 5 or 7 (fast for rustfft).
///
/// # Errors
/// The result would exceed [`MAX_FFT_LEN`].
pub fn fast_len(min_len: usize) -> Result<usize, DspError> {
    let target = min_len.max(1);
    if target > MAX_FFT_LEN {
        return Err(DspError::TooLong { what: "FFT", len: target, max: MAX_FFT_LEN });
    }
    let mut best = target.next_power_of_two();
    let mut p7 = 1usize;
    while p7 < best {
        let mut p5 = p7;
        while p5 < best {
            let mut p3 = p5;
            while p3 < best {
                // Smallest power of two times p3 reaching the target.
                let mut n = p3;
                while n < target {
                    n *= 2;
                }
                best = best.min(n);
                p3 *= 3;
            }
            p5 *= 5;
        }
        p7 *= 7;
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_small_lengths() {
        for n in 1..40 {
            let x: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
            let y = inverse(&forward(&x, n).unwrap(), n).unwrap();
            for (a, b) in x.iter().zip(&y) {
                assert!((a - b).abs() < 1e-12, "n = {n}");
            }
        }
    }

    #[test]
    fn length_one_is_identity() {
        let spec = forward(&[2.5], 1).unwrap();
        assert_eq!(spec.len(), 1);
        assert_eq!(spec[0].re, 2.5);
        assert_eq!(inverse(&spec, 1).unwrap(), vec![2.5]);
    }

    #[test]
    fn large_prime_length_round_trips() {
        let n = 100_003; // prime
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.001).sin()).collect();
        let y = inverse(&forward(&x, n).unwrap(), n).unwrap();
        let err = x.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        // Bluestein's algorithm rounds through three FFTs of about 2^18: 1e-9 is generous for f64.
        assert!(err < 1e-9, "max error {err}");
    }

    #[test]
    fn length_two_to_the_24_round_trips() {
        let n = 1 << 24;
        let mut x = vec![0.0; n];
        x[12_345] = 1.0;
        x[n - 1] = -0.5;
        let spec = forward(&x, n).unwrap();
        // A unit impulse at 12345 has unit magnitude in every bin but for the other impulse's contribution.
        assert!((spec[0].re - 0.5).abs() < 1e-9);
        let y = inverse(&spec, n).unwrap();
        assert!((y[12_345] - 1.0).abs() < 1e-9);
        assert!((y[n - 1] + 0.5).abs() < 1e-9);
        let stray =
            y.iter().enumerate().filter(|(i, _)| *i != 12_345 && *i != n - 1).map(|(_, v)| v.abs()).fold(0.0, f64::max);
        assert!(stray < 1e-9, "stray {stray}");
    }

    #[test]
    fn refuses_zero_and_oversized_lengths_and_nan() {
        assert!(matches!(forward(&[1.0], 0), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(forward(&[1.0], MAX_FFT_LEN + 1), Err(DspError::TooLong { .. })));
        assert!(matches!(forward(&[1.0, f64::NAN], 4), Err(DspError::NonFinite { index: 1, .. })));
        assert!(matches!(inverse(&[Complex64::new(1.0, 0.0)], 4), Err(DspError::LengthMismatch { .. })));
    }

    #[test]
    fn fast_len_is_smooth_and_minimal() {
        assert_eq!(fast_len(0).unwrap(), 1);
        assert_eq!(fast_len(1).unwrap(), 1);
        assert_eq!(fast_len(11).unwrap(), 12);
        assert_eq!(fast_len(97).unwrap(), 98);
        assert_eq!(fast_len(1025).unwrap(), 1029);
        fn is_7_smooth(mut k: usize) -> bool {
            for p in [2, 3, 5, 7] {
                while k.is_multiple_of(p) {
                    k /= p;
                }
            }
            k == 1
        }
        for n in [13usize, 1000, 72_001, 144_000] {
            let m = fast_len(n).unwrap();
            assert!(m >= n);
            assert!(is_7_smooth(m), "{m} is not 7-smooth");
            // Minimal: no 7-smooth number in [n, m).
            assert!((n..m).all(|k| !is_7_smooth(k)), "a 7-smooth length below {m} exists");
        }
    }
}

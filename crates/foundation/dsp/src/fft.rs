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
    /// Working buffers reused by every transform on this thread. Allocating them per call cost more than the
    /// transform itself (fresh pages, zero-filled).
    static BUFFERS: RefCell<Buffers> = const { RefCell::new(Buffers::EMPTY) };
}

struct Buffers {
    /// Copies of the inputs, which realfft overwrites: samples of a forward transform, bins of an inverse one.
    real: Vec<f64>,
    bins: Vec<Complex64>,
    /// realfft's scratch.
    scratch: Vec<Complex64>,
}

impl Buffers {
    const EMPTY: Self = Self { real: Vec::new(), bins: Vec::new(), scratch: Vec::new() };
}

/// Longest buffer kept between transforms, elements (8 or 16 MiB): a rare huge transform should not pin its buffers
/// to the thread for good.
const RETAINED_MAX_LEN: usize = 1 << 20;

/// Runs `f` on this thread's buffers, then frees any grown beyond [`RETAINED_MAX_LEN`].
fn with_buffers<R>(f: impl FnOnce(&mut Buffers) -> R) -> R {
    BUFFERS.with(|cell| {
        let mut buffers = cell.borrow_mut();
        let result = f(&mut buffers);
        if buffers.real.capacity() > RETAINED_MAX_LEN {
            buffers.real = Vec::new();
        }
        if buffers.bins.capacity() > RETAINED_MAX_LEN {
            buffers.bins = Vec::new();
        }
        if buffers.scratch.capacity() > RETAINED_MAX_LEN {
            buffers.scratch = Vec::new();
        }
        result
    })
}

/// Resizes `v` to `len` without caring what it holds: the caller overwrites every element.
fn resize_for_overwrite<T: Copy + Default>(v: &mut Vec<T>, len: usize) {
    if v.len() < len {
        v.resize(len, T::default());
    }
    v.truncate(len);
}

/// True when every bin is finite: `v * 0` is 0 for a finite value and NaN otherwise, and a NaN survives any sum, so
/// one pass without early exit decides; four partial sums let the compiler keep them in vector registers.
pub(crate) fn spectrum_is_finite(x: &[Complex64]) -> bool {
    let mut acc = [0.0f64; 4];
    let (chunks, rest) = x.as_chunks::<2>();
    for c in chunks {
        acc[0] += c[0].re * 0.0;
        acc[1] += c[0].im * 0.0;
        acc[2] += c[1].re * 0.0;
        acc[3] += c[1].im * 0.0;
    }
    rest.iter().all(|c| c.re.is_finite() && c.im.is_finite()) && acc.iter().sum::<f64>() == 0.0
}

/// [`DspError::NonFinite`] naming `input` and the first non-finite bin, if any.
pub(crate) fn check_spectrum_finite(input: &'static str, x: &[Complex64]) -> Result<(), DspError> {
    if spectrum_is_finite(x) {
        return Ok(());
    }
    let index = x.iter().position(|c| !(c.re.is_finite() && c.im.is_finite())).unwrap_or(0);
    Err(DspError::NonFinite { input, index, value: f64::NAN })
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
    let mut spectrum = vec![Complex64::new(0.0, 0.0); bin_count(n)];
    forward_into(x, n, &mut spectrum)?;
    Ok(spectrum)
}

/// [`forward`] into a caller's buffer of `n / 2 + 1` bins, which saves allocating one per call in loops.
///
/// # Errors
/// As [`forward`]; [`DspError::LengthMismatch`] when `spectrum.len() != n / 2 + 1`.
pub fn forward_into(x: &[f64], n: usize, spectrum: &mut [Complex64]) -> Result<(), DspError> {
    check_len(n)?;
    check_bin_count("forward FFT bins against n / 2 + 1", spectrum.len(), n)?;
    check_finite("FFT input", x)?;
    let plan = PLANNER.with(|planner| planner.borrow_mut().plan_fft_forward(n));
    with_buffers(|Buffers { real, scratch, .. }| {
        // realfft overwrites its input: work on a copy, padded with zeros (written once, not cleared first).
        resize_for_overwrite(real, n);
        let copied = x.len().min(n);
        real[..copied].copy_from_slice(&x[..copied]);
        real[copied..].fill(0.0);
        resize_for_overwrite(scratch, plan.get_scratch_len());
        // Lengths were set up from the plan's own n: process only fails on a length mismatch.
        plan.process_with_scratch(real, spectrum, scratch)
            .map_err(|e| DspError::InvalidParameter { name: "fft buffers", reason: e.to_string() })
    })
}

/// [`forward`] of `x` at its own length `n = x.len()` into a caller's buffer of `n / 2 + 1` bins, using `x` itself as
/// the transform's working space: `x` holds garbage afterwards. Saves the copy [`forward_into`] makes of its input.
///
/// # Errors
/// An empty `x` or one longer than [`MAX_FFT_LEN`]; a non-finite sample; `spectrum.len() != n / 2 + 1`.
pub fn forward_destructive(x: &mut [f64], spectrum: &mut [Complex64]) -> Result<(), DspError> {
    let n = x.len();
    check_len(n)?;
    check_bin_count("forward FFT bins against n / 2 + 1", spectrum.len(), n)?;
    check_finite("FFT input", x)?;
    let plan = PLANNER.with(|planner| planner.borrow_mut().plan_fft_forward(n));
    with_buffers(|Buffers { scratch, .. }| {
        resize_for_overwrite(scratch, plan.get_scratch_len());
        plan.process_with_scratch(x, spectrum, scratch)
            .map_err(|e| DspError::InvalidParameter { name: "fft buffers", reason: e.to_string() })
    })
}

/// Refuses a spectrum of `bins` bins for an `n`-point real FFT (which has `n / 2 + 1`).
fn check_bin_count(what: &'static str, bins: usize, n: usize) -> Result<(), DspError> {
    if bins != bin_count(n) {
        return Err(DspError::LengthMismatch { what, a: bins, b: bin_count(n) });
    }
    Ok(())
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
    let mut output = vec![0.0; n];
    inverse_into(spectrum, n, &mut output)?;
    Ok(output)
}

/// [`inverse`] into a caller's buffer of `n` samples.
///
/// # Errors
/// As [`inverse`]; [`DspError::LengthMismatch`] when `output.len() != n`.
pub fn inverse_into(spectrum: &[Complex64], n: usize, output: &mut [f64]) -> Result<(), DspError> {
    check_len(n)?;
    check_bin_count("inverse FFT bins against n / 2 + 1", spectrum.len(), n)?;
    if output.len() != n {
        return Err(DspError::LengthMismatch { what: "inverse FFT output against n", a: output.len(), b: n });
    }
    check_spectrum_finite("inverse FFT spectrum", spectrum)?;
    let plan = PLANNER.with(|planner| planner.borrow_mut().plan_fft_inverse(n));
    with_buffers(|Buffers { bins, scratch, .. }| {
        bins.clear();
        bins.extend_from_slice(spectrum);
        bins[0].im = 0.0;
        if n.is_multiple_of(2) {
            let last = bins.len() - 1;
            bins[last].im = 0.0;
        }
        resize_for_overwrite(scratch, plan.get_scratch_len());
        plan.process_with_scratch(bins, output, scratch)
            .map_err(|e| DspError::InvalidParameter { name: "inverse fft buffers", reason: e.to_string() })
    })?;
    let scale = 1.0 / n as f64;
    output.iter_mut().for_each(|v| *v *= scale);
    Ok(())
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

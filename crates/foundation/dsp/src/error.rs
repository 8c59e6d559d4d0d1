//! The one error type of this crate.

/// Why a DSP routine refused its input or could not produce a finite result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DspError {
    /// An input signal had no samples where at least one is needed.
    #[error("{input} is empty")]
    Empty {
        /// Which input.
        input: &'static str,
    },
    /// An input signal held NaN or an infinity (a device glitch, or a corrupt file).
    #[error("{input} contains a non-finite value ({value}) at sample {index}")]
    NonFinite {
        /// Which input.
        input: &'static str,
        /// First offending sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A parameter lies outside the routine's valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Parameter name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// A length would need more memory than the routine allows.
    #[error("{what} needs {len} samples, more than the limit of {max}")]
    TooLong {
        /// What was too long.
        what: &'static str,
        /// Requested length.
        len: usize,
        /// Limit.
        max: usize,
    },
    /// Two inputs that must match in length do not.
    #[error("{what}: lengths {a} and {b} differ")]
    LengthMismatch {
        /// What was compared.
        what: &'static str,
        /// First length.
        a: usize,
        /// Second length.
        b: usize,
    },
    /// The computation overflowed to NaN or infinity although the inputs were finite: the inputs are outside the
    /// routine's valid range (for example, a regularisation of zero on an excitation with spectral zeros).
    #[error("{what} produced a non-finite result; the input is outside the routine's valid range")]
    NonFiniteResult {
        /// Which computation.
        what: &'static str,
    },
}

/// Checks that `x` holds only finite samples.
///
/// # Errors
/// [`DspError::NonFinite`] naming `input` and the first bad sample.
pub fn check_finite(input: &'static str, x: &[f64]) -> Result<(), DspError> {
    if all_finite(x) {
        return Ok(());
    }
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(DspError::NonFinite { input, index, value: x[index] }),
        None => Ok(()),
    }
}

/// Checks that `x` is non-empty and finite.
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`].
pub fn check_signal(input: &'static str, x: &[f64]) -> Result<(), DspError> {
    if x.is_empty() {
        return Err(DspError::Empty { input });
    }
    check_finite(input, x)
}

/// Checks that an output is finite, so that NaN never leaves a library function silently.
///
/// # Errors
/// [`DspError::NonFiniteResult`] naming `what`.
pub fn check_result(what: &'static str, x: &[f64]) -> Result<(), DspError> {
    if all_finite(x) { Ok(()) } else { Err(DspError::NonFiniteResult { what }) }
}

/// True when every sample is finite. `v * 0` is 0 for a finite sample and NaN otherwise, and a NaN survives any sum,
/// so one pass without early exit decides; eight partial sums let the compiler keep them in vector registers (the
/// early-exit search is several times slower on the long recordings checked at every step).
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let (chunks, rest) = x.as_chunks::<8>();
    for c in chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v * 0.0;
        }
    }
    rest.iter().all(|v| v.is_finite()) && acc.iter().sum::<f64>() == 0.0
}

/// Checks a sample rate: finite and positive.
///
/// # Errors
/// [`DspError::InvalidParameter`] otherwise.
pub fn check_sample_rate(sample_rate_hz: f64) -> Result<(), DspError> {
    if sample_rate_hz.is_finite() && sample_rate_hz > 0.0 {
        Ok(())
    } else {
        Err(DspError::InvalidParameter {
            name: "sample_rate_hz",
            reason: format!("must be finite and positive, got {sample_rate_hz}"),
        })
    }
}

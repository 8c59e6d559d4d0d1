//! Smooth band limits: unity gain inside a band, raised-cosine transitions outside it, zero beyond.
//!
//! Deconvolution uses them to keep out-of-band noise out of an impulse response, and the Kirkeby filter uses them to
//! shape its ("trapezoidal") regularisation profile.

use crate::error::DspError;

/// A pass band `[lo_hz, hi_hz]` with raised-cosine skirts of width `lo_transition_hz` below it and
/// `hi_transition_hz` above it. The band itself is untouched (gain exactly 1); the skirts lie outside it.
///
/// Valid range: `0 <= lo_hz < hi_hz`, transitions `>= 0`, all finite. A band starting at 0 Hz or ending at Nyquist
/// is allowed; a skirt that would cross 0 Hz is simply cut there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandLimit {
    /// Lower band edge, Hz.
    pub lo_hz: f64,
    /// Upper band edge, Hz.
    pub hi_hz: f64,
    /// Width of the lower skirt, Hz.
    pub lo_transition_hz: f64,
    /// Width of the upper skirt, Hz.
    pub hi_transition_hz: f64,
}

impl BandLimit {
    /// Builds a checked band limit.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] when an edge is negative or non-finite, `lo_hz >= hi_hz`, or a transition is
    /// negative.
    pub fn new(lo_hz: f64, hi_hz: f64, lo_transition_hz: f64, hi_transition_hz: f64) -> Result<Self, DspError> {
        let band = Self { lo_hz, hi_hz, lo_transition_hz, hi_transition_hz };
        band.validate()?;
        Ok(band)
    }

    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming the offending field.
    pub fn validate(&self) -> Result<(), DspError> {
        let fields = [
            ("lo_hz", self.lo_hz),
            ("hi_hz", self.hi_hz),
            ("lo_transition_hz", self.lo_transition_hz),
            ("hi_transition_hz", self.hi_transition_hz),
        ];
        for (name, v) in fields {
            if !v.is_finite() || v < 0.0 {
                return Err(DspError::InvalidParameter { name, reason: format!("must be finite and >= 0, got {v}") });
            }
        }
        if self.lo_hz >= self.hi_hz {
            return Err(DspError::InvalidParameter {
                name: "hi_hz",
                reason: format!("must exceed lo_hz ({} Hz), got {} Hz", self.lo_hz, self.hi_hz),
            });
        }
        Ok(())
    }

    /// Gain at `f_hz` (use the magnitude for negative frequencies): 1 in the band, a raised cosine across each skirt,
    /// 0 beyond the skirts.
    pub fn gain(&self, f_hz: f64) -> f64 {
        let f = f_hz.abs();
        if f >= self.lo_hz && f <= self.hi_hz {
            1.0
        } else if f < self.lo_hz {
            skirt(self.lo_hz - f, self.lo_transition_hz)
        } else {
            skirt(f - self.hi_hz, self.hi_transition_hz)
        }
    }

    /// Gains at the `n / 2 + 1` bins of a length-`n` real FFT at `sample_rate_hz`.
    pub fn bin_gains(&self, n: usize, sample_rate_hz: f64) -> Vec<f64> {
        (0..n / 2 + 1).map(|k| self.gain(k as f64 * sample_rate_hz / n as f64)).collect()
    }
}

/// Raised-cosine skirt: 1 at distance 0 from the band edge, 0 at `width` and beyond. A zero width is a brick wall.
fn skirt(distance_hz: f64, width_hz: f64) -> f64 {
    if width_hz <= 0.0 || distance_hz >= width_hz {
        0.0
    } else {
        0.5 * (1.0 + (std::f64::consts::PI * distance_hz / width_hz).cos())
    }
}

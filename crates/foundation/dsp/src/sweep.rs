//! Swept-sine excitations: linear and exponential (logarithmic) sweeps.
//!
//! Linear: phase `2 pi (f1 t + (f2 - f1) t^2 / (2 T))`, constant sweep rate, white spectrum; the paper's protocol.
//! Exponential: phase `2 pi f1 L (e^(t / L) - 1)` with `L = T / ln(f2 / f1)`, pink spectrum; its k-th harmonic
//! distortion products arrive `L ln k` before the linear response after deconvolution, so they can be cut away
//! (see [`crate::deconv`]).

use std::f64::consts::PI;

use crate::error::{DspError, check_result, check_sample_rate};
use crate::window;

/// The longest sweep generated: 2^27 samples (about 93 minutes at 24 kHz).
pub const MAX_SWEEP_SAMPLES: usize = 1 << 27;

/// How the instantaneous frequency moves from `f1_hz` to `f2_hz`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SweepKind {
    /// Frequency rises linearly in time.
    Linear,
    /// Frequency rises exponentially in time (equal time per octave).
    Exponential,
}

/// A swept sine.
///
/// Valid range: `0 <= f1_hz < f2_hz <= sample_rate_hz / 2` (and `f1_hz > 0` for an exponential sweep);
/// `duration_s > 0` with at most [`MAX_SWEEP_SAMPLES`] samples; finite positive `amplitude`; fades `>= 0` that
/// together fit inside the sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepSpec {
    /// Linear or exponential.
    pub kind: SweepKind,
    /// Start frequency, Hz.
    pub f1_hz: f64,
    /// End frequency, Hz.
    pub f2_hz: f64,
    /// Duration, s (the sweep has `round(duration_s * sample_rate_hz)` samples).
    pub duration_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Peak amplitude (full scale is 1.0 for an audio output).
    pub amplitude: f64,
    /// Half-Hann fade-in length, s.
    pub fade_in_s: f64,
    /// Half-Hann fade-out length, s.
    pub fade_out_s: f64,
}

impl Default for SweepSpec {
    /// The paper's excitation: a 3 s linear sweep from 62 to 625 Hz at 24 kHz, full amplitude, with 5 ms fades.
    /// The fades are ours: they remove the step at the ends, which would otherwise splatter energy across the band.
    fn default() -> Self {
        Self {
            kind: SweepKind::Linear,
            f1_hz: 62.0,
            f2_hz: 625.0,
            duration_s: 3.0,
            sample_rate_hz: 24_000.0,
            amplitude: 1.0,
            fade_in_s: 0.005,
            fade_out_s: 0.005,
        }
    }
}

impl SweepSpec {
    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming the offending field, or [`DspError::TooLong`].
    pub fn validate(&self) -> Result<(), DspError> {
        check_sample_rate(self.sample_rate_hz)?;
        let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
        let nyquist = self.sample_rate_hz / 2.0;
        let min_f1 = if self.kind == SweepKind::Exponential { f64::MIN_POSITIVE } else { 0.0 };
        if !(self.f1_hz.is_finite() && self.f1_hz >= min_f1) {
            return invalid(
                "f1_hz",
                format!("must be finite and {} 0, got {}", if min_f1 > 0.0 { ">" } else { ">=" }, self.f1_hz),
            );
        }
        if !(self.f2_hz.is_finite() && self.f2_hz > self.f1_hz && self.f2_hz <= nyquist) {
            return invalid("f2_hz", format!("must lie in ({}, {nyquist}] Hz, got {}", self.f1_hz, self.f2_hz));
        }
        if !(self.duration_s.is_finite() && self.duration_s > 0.0) {
            return invalid("duration_s", format!("must be finite and positive, got {}", self.duration_s));
        }
        if !(self.amplitude.is_finite() && self.amplitude > 0.0) {
            return invalid("amplitude", format!("must be finite and positive, got {}", self.amplitude));
        }
        for (name, v) in [("fade_in_s", self.fade_in_s), ("fade_out_s", self.fade_out_s)] {
            if !(v.is_finite() && v >= 0.0) {
                return invalid(name, format!("must be finite and >= 0, got {v}"));
            }
        }
        if self.fade_in_s + self.fade_out_s > self.duration_s {
            return invalid(
                "fade_out_s",
                format!(
                    "fades ({} s + {} s) exceed the duration {} s",
                    self.fade_in_s, self.fade_out_s, self.duration_s
                ),
            );
        }
        let samples = self.duration_s * self.sample_rate_hz;
        if samples > MAX_SWEEP_SAMPLES as f64 {
            return Err(DspError::TooLong { what: "sweep", len: samples as usize, max: MAX_SWEEP_SAMPLES });
        }
        if samples.round() < 1.0 {
            return invalid("duration_s", format!("{} s is less than one sample", self.duration_s));
        }
        Ok(())
    }

    /// Number of samples: `round(duration_s * sample_rate_hz)`.
    pub fn len_samples(&self) -> usize {
        (self.duration_s * self.sample_rate_hz).round() as usize
    }

    /// The exponential sweep's rate constant `L = T / ln(f2 / f1)`, s; `None` for a linear sweep.
    pub fn exp_rate_s(&self) -> Option<f64> {
        match self.kind {
            SweepKind::Linear => None,
            SweepKind::Exponential => Some(self.duration_s / (self.f2_hz / self.f1_hz).ln()),
        }
    }

    /// How much earlier than the linear response the k-th harmonic's impulse response arrives after deconvolution
    /// of an exponential sweep: `L ln k`, s. `None` for a linear sweep or `k == 0`.
    pub fn harmonic_advance_s(&self, k: u32) -> Option<f64> {
        if k == 0 {
            return None;
        }
        self.exp_rate_s().map(|l| l * f64::from(k).ln())
    }

    /// Instantaneous phase at `t_s`, rad.
    pub fn phase_rad(&self, t_s: f64) -> f64 {
        let (f1, f2, duration) = (self.f1_hz, self.f2_hz, self.duration_s);
        match self.kind {
            SweepKind::Linear => 2.0 * PI * (f1 * t_s + (f2 - f1) * t_s * t_s / (2.0 * duration)),
            SweepKind::Exponential => {
                let l = duration / (f2 / f1).ln();
                2.0 * PI * f1 * l * ((t_s / l).exp_m1())
            }
        }
    }

    /// Instantaneous frequency at `t_s`, Hz.
    pub fn instantaneous_freq_hz(&self, t_s: f64) -> f64 {
        match self.kind {
            SweepKind::Linear => self.f1_hz + (self.f2_hz - self.f1_hz) * t_s / self.duration_s,
            SweepKind::Exponential => {
                let l = self.duration_s / (self.f2_hz / self.f1_hz).ln();
                self.f1_hz * (t_s / l).exp()
            }
        }
    }

    /// The sweep's samples, `amplitude * sin(phase)`, with half-Hann fades.
    ///
    /// # Errors
    /// As [`SweepSpec::validate`].
    pub fn generate(&self) -> Result<Vec<f64>, DspError> {
        self.validate()?;
        let n = self.len_samples();
        let fs = self.sample_rate_hz;
        let fade_in = (self.fade_in_s * fs).round() as usize;
        let fade_out = (self.fade_out_s * fs).round() as usize;
        let mut x: Vec<f64> = (0..n).map(|i| self.amplitude * self.phase_rad(i as f64 / fs).sin()).collect();
        let fade_in = fade_in.min(n);
        let fade_out = fade_out.min(n);
        for (v, w) in x.iter_mut().zip(window::fade_in(fade_in)) {
            *v *= w;
        }
        for (v, w) in x[n - fade_out..].iter_mut().zip(window::fade_out(fade_out)) {
            *v *= w;
        }
        check_result("sweep", &x)?;
        Ok(x)
    }
}

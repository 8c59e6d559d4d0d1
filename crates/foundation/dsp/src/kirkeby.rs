//! Kirkeby inverse filters (Kirkeby and Nelson 1999) with frequency-dependent ("trapezoidal") regularisation.
//!
//! Each actuator's measured impulse response `c` is flattened by a FIR `h` designed in the frequency domain:
//!
//! `H(f) = C*(f) D(f) / (|C(f)|^2 + beta_abs B(f))`,
//!
//! with `B` the [`RegularisationProfile`] (small in the band, large outside it), `beta_abs = beta * max_f |C(f)|^2`
//! (so `beta` is relative and the design does not depend on the response's scale), and `D` the target: a pure delay
//! of `modelling_delay_samples`, optionally given the minimum phase of the achieved response (see [`TargetPhase`]).
//! `H` is transformed back, truncated to `fir_len` taps and tapered at both ends.
//!
//! The regularisation bounds the gain everywhere: `|C| / (|C|^2 + beta_abs B)` is at most `1 / (2 sqrt(beta_abs B))`
//! (reached at `|C|^2 = beta_abs B`), so out of the band, where `B` is large, the filter cannot boost noise.

use std::f64::consts::PI;

use num_complex::Complex64;

use crate::band::BandLimit;
use crate::deconv::DeconvConfig;
use crate::error::{DspError, check_result, check_sample_rate, check_signal};
use crate::impulse::minimum_phase_spectrum;
use crate::{conv, fft, window};

/// The regularisation profile `B(f) = in_band + (out_of_band - in_band) * (1 - band.gain(f))`: `in_band` inside the
/// band, `out_of_band` beyond its skirts, a raised-cosine ramp across each skirt (the "trapezoid").
///
/// Both weights are dimensionless multipliers of `beta` (itself relative to the response's peak power).
/// Valid range: a valid `band`, `in_band` and `out_of_band` finite and `>= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegularisationProfile {
    /// The band that is flattened; its skirts set how smoothly the regularisation rises.
    pub band: BandLimit,
    /// Weight inside the band.
    pub in_band: f64,
    /// Weight beyond the skirts.
    pub out_of_band: f64,
}

impl RegularisationProfile {
    /// `B(f_hz)`, dimensionless (see the type).
    pub fn weight(&self, f_hz: f64) -> f64 {
        self.in_band + (self.out_of_band - self.in_band) * (1.0 - self.band.gain(f_hz))
    }

    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming the offending field.
    pub fn validate(&self) -> Result<(), DspError> {
        self.band.validate()?;
        for (name, v) in [("profile.in_band", self.in_band), ("profile.out_of_band", self.out_of_band)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(DspError::InvalidParameter { name, reason: format!("must be finite and >= 0, got {v}") });
            }
        }
        Ok(())
    }
}

/// The phase of the design's target, i.e. of the achieved response `c * h`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetPhase {
    /// Textbook Kirkeby: `D` is a pure delay, so `c * h` is the zero-phase `R(f) = |C|^2 / (|C|^2 + beta_abs B)`
    /// delayed. `R` falls off at the band edges, so `c * h` rings symmetrically before and after the delay: with
    /// the calibration defaults on a model actuator, 1.4 % of its energy (-18.5 dB) comes more than 5 ms before the
    /// delay, and the modelling delay must be about half the filter.
    Linear,
    /// `D` is the pure delay times the minimum-phase all-pass of `R`: `c * h` becomes the minimum-phase filter with
    /// magnitude `R`, delayed, so nothing rings before the delay. Same magnitude (hence the same flatness and
    /// gain bound) as [`TargetPhase::Linear`]; only the phase differs.
    Minimum,
}

/// Design parameters of a Kirkeby inverse filter.
///
/// Valid range: finite positive `sample_rate_hz`; `fir_len >= 1`; `modelling_delay_samples < fir_len`;
/// `response_delay_samples` below the response's length; finite
/// `beta >= 0` (0 is the exact inverse, refused if the response has an exact spectral zero); a valid profile whose
/// band starts below Nyquist; `fft_len`, if given, at least `fir_len`, at least the response length and at most
/// [`fft::MAX_FFT_LEN`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KirkebyConfig {
    /// Sample rate of the response and of the filter, Hz.
    pub sample_rate_hz: f64,
    /// Taps of the final filter.
    pub fir_len: usize,
    /// Delay of the target, samples: room for the acausal part of the inverse.
    pub modelling_delay_samples: usize,
    /// Overall regularisation weight, relative to `max_f |C(f)|^2` (dimensionless, scale-free).
    pub beta: f64,
    /// Index of the response's time 0, samples: the response is two-sided, its first `response_delay_samples`
    /// samples lying before time 0 (as [`crate::deconv::DeconvConfig::pre_samples`] returns it). The design removes
    /// this delay from the response's spectrum, so the filter inverts the response about its own time 0 and `c * h`
    /// (with `c` the causal, physical response) starts at `modelling_delay_samples` as usual. 0 for a causal response.
    pub response_delay_samples: usize,
    /// Frequency dependence of the regularisation.
    pub profile: RegularisationProfile,
    /// Phase of the target.
    pub target: TargetPhase,
    /// Design FFT length; `None` chooses `fft::fast_len(max(4 * fir_len, 2 * response length))`, long enough that
    /// the untruncated inverse barely wraps around.
    pub fft_len: Option<usize>,
}

impl KirkebyConfig {
    /// Defaults for the actuator calibration (3 s linear sweep 50..625 Hz at 24 kHz), for a causal response
    /// (`response_delay_samples` 0). For a response deconvolved from a sweep, use [`KirkebyConfig::calibration`].
    ///
    /// - profile: the sweep band 50..625 Hz with skirts of 25 Hz below (regularisation fully up at 25 Hz) and
    ///   200 Hz above (fully up at 825 Hz); `in_band` 1, `out_of_band` 1e5 (+50 dB). The sweep measures nothing
    ///   outside its band, so the filter must not try to invert there.
    /// - `beta` 1e-5: in band `beta_abs B` lies 50 dB below the response's peak power, so `c * h` is flat within
    ///   0.5 dB wherever the response lies within about 37 dB of its peak (`R = |C|^2 / (|C|^2 + beta_abs B) >= 0.944`
    ///   needs `|C|^2 >= 16.9 beta_abs B`); out of band `beta_abs B` equals the peak power, so there the filter's
    ///   gain is at most `1 / (2 max |C|)`: it never boosts what the sweep did not measure.
    /// - `fir_len` 8192 (341 ms): the minimum-phase response with the 25 Hz skirt and the inverse of a 70 Hz
    ///   suspension resonance ring for about 200 ms; 4096 taps cost up to 0.3 dB of in-band ripple on a model
    ///   actuator, 8192 taps 0.05 dB (see the tests).
    /// - `modelling_delay_samples` 480 (20 ms): with the minimum-phase target only the response's own excess phase
    ///   (latency, non-minimum-phase parts of the mount) needs room before the delay.
    /// - target: [`TargetPhase::Minimum`], so drive signals do not pre-ring.
    pub fn calibration_default() -> Self {
        Self {
            sample_rate_hz: 24_000.0,
            fir_len: 8192,
            modelling_delay_samples: 480,
            response_delay_samples: 0,
            beta: 1e-5,
            profile: RegularisationProfile {
                band: BandLimit { lo_hz: 50.0, hi_hz: 625.0, lo_transition_hz: 25.0, hi_transition_hz: 200.0 },
                in_band: 1.0,
                out_of_band: 1e5,
            },
            target: TargetPhase::Minimum,
            fft_len: None,
        }
    }

    /// The actuator calibration recipe: [`KirkebyConfig::calibration_default`] for a response deconvolved with
    /// `deconv` (normally [`DeconvConfig::calibration`]), i.e. at its sample rate and with `response_delay_samples`
    /// set to its `pre_samples`, so that the design sees the response about its own time 0.
    ///
    /// Recipe: play `SweepSpec { f1_hz: 50.0, amplitude: 0.5, ..SweepSpec::default() }` (3 s, 50..625 Hz, 24 kHz),
    /// record the response with at least `deconv.ir_len` samples of tail, `deconvolve` it with
    /// `DeconvConfig::calibration()` (two-sided: 2048 samples before time 0, 8192 in all; band 50..625 Hz, skirts 20
    /// and 100 Hz; regularisation 1e-4), then `design` with `KirkebyConfig::calibration(&deconv)` (8192 taps,
    /// modelling delay 480 samples = 20 ms, unchanged: the response's pre-samples are removed from its spectrum, not
    /// added to the delay). On a model voice coil (with a 0.01 cubic) the compensated response is flat within
    /// -0.042 .. +0.030 dB over 62..625 Hz (see `tests/calibration.rs`); from a causal cut of the same measurement
    /// (`pre_samples` 0) it is off by -1.38 .. +0.14 dB, failing a +/-1 dB requirement.
    ///
    /// Why not leave `response_delay_samples` at 0 and raise the modelling delay by the pre-samples instead: the
    /// design spectrum, hence the untruncated filter, would be the same, but the taps' fade-in covers a quarter of
    /// the modelling delay, (480 + 2048) / 4 = 632 samples, and so fades the start of the filter, which lies at 480:
    /// measured -0.15 .. +0.48 dB on the same coil.
    pub fn calibration(deconv: &DeconvConfig) -> Self {
        Self {
            sample_rate_hz: deconv.sample_rate_hz,
            response_delay_samples: deconv.pre_samples,
            ..Self::calibration_default()
        }
    }

    /// Checks the valid range stated on the type against a response of `response_len` samples and returns the
    /// design FFT length.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming the offending field, or [`DspError::TooLong`].
    pub fn validate(&self, response_len: usize) -> Result<usize, DspError> {
        check_sample_rate(self.sample_rate_hz)?;
        self.profile.validate()?;
        let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
        if self.fir_len == 0 {
            return invalid("fir_len", "must be at least 1".into());
        }
        if self.modelling_delay_samples >= self.fir_len {
            return invalid(
                "modelling_delay_samples",
                format!("must be below fir_len ({}), got {}", self.fir_len, self.modelling_delay_samples),
            );
        }
        if self.response_delay_samples >= response_len {
            return invalid(
                "response_delay_samples",
                format!("must be below the response's length ({response_len}), got {}", self.response_delay_samples),
            );
        }
        if !(self.beta.is_finite() && self.beta >= 0.0) {
            return invalid("beta", format!("must be finite and >= 0, got {}", self.beta));
        }
        let nyquist_hz = self.sample_rate_hz / 2.0;
        if self.profile.band.lo_hz >= nyquist_hz {
            return invalid(
                "profile.band.lo_hz",
                format!("{} Hz is not below Nyquist ({nyquist_hz} Hz)", self.profile.band.lo_hz),
            );
        }
        let n = match self.fft_len {
            Some(n) => n,
            None => fft::fast_len(self.fir_len.saturating_mul(4).max(response_len.saturating_mul(2)))?,
        };
        if n > fft::MAX_FFT_LEN {
            return Err(DspError::TooLong { what: "Kirkeby design FFT", len: n, max: fft::MAX_FFT_LEN });
        }
        if n < self.fir_len || n < response_len {
            return invalid(
                "fft_len",
                format!("{n} is shorter than fir_len ({}) or the response ({response_len})", self.fir_len),
            );
        }
        Ok(n)
    }
}

/// The design in the frequency domain, on the `fft_len / 2 + 1` bins of the design FFT (bin `k` at
/// `k * sample_rate_hz / fft_len` Hz).
#[derive(Debug, Clone, PartialEq)]
pub struct KirkebySpectrum {
    /// Design FFT length.
    pub fft_len: usize,
    /// `C(f)`: the response's spectrum about its time 0, i.e. with `response_delay_samples` removed (unnormalised
    /// DFT of the response rotated circularly, units of the response).
    pub response: Vec<Complex64>,
    /// `beta_abs * B(f)`: the absolute regularisation added to `|C|^2` (units of the response, squared).
    pub regularisation: Vec<f64>,
    /// `H(f)` before truncation to `fir_len` taps (units of 1 / response).
    pub inverse: Vec<Complex64>,
}

/// A designed inverse filter.
#[derive(Debug, Clone, PartialEq)]
pub struct KirkebyFilter {
    /// The FIR taps, `fir_len` of them, in 1 / (units of the response).
    pub taps: Vec<f64>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Delay of the target, samples: `c * h` starts there ([`TargetPhase::Minimum`]) or is centred there
    /// ([`TargetPhase::Linear`]).
    pub modelling_delay_samples: usize,
    /// How much the filter boosts above the gain that brings the response's strongest frequency to unity:
    /// `20 log10(max_f |H_taps(f)| * max_f |C(f)|)`, dB, both maxima over the design FFT's bins and `H_taps` the
    /// spectrum of the final (truncated) taps. Close to the response's in-band dynamic range for an unconstrained
    /// inverse; it is what the amplifier's headroom must cover.
    pub max_boost_db: f64,
}

/// The design spectrum of a Kirkeby inverse of `response_ir` (see the module documentation for the formula).
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`] for the response; [`DspError::InvalidParameter`] for an invalid
/// configuration (see [`KirkebyConfig`]) or an all-zero response (or one so small that its peak power underflows);
/// [`DspError::NonFiniteResult`] when the inverse overflows (a zero `beta`, or zero weights, where the response has
/// an exact spectral zero).
pub fn design_spectrum(response_ir: &[f64], cfg: &KirkebyConfig) -> Result<KirkebySpectrum, DspError> {
    check_signal("actuator response", response_ir)?;
    let n = cfg.validate(response_ir.len())?;
    let response = if cfg.response_delay_samples == 0 {
        fft::forward(response_ir, n)?
    } else {
        // Advance by the delay: the samples before time 0 move to the end of the circular grid, i.e. to negative
        // time. Exact because the design FFT holds the whole response (n >= its length, checked by validate).
        let mut centred = response_ir.to_vec();
        centred.resize(n, 0.0);
        centred.rotate_left(cfg.response_delay_samples);
        fft::forward(&centred, n)?
    };
    let peak_power = response.iter().map(|c| c.norm_sqr()).fold(0.0, f64::max);
    if peak_power == 0.0 {
        return Err(DspError::InvalidParameter {
            name: "response_ir",
            reason: "is zero (or so small that its power underflows): there is nothing to invert".into(),
        });
    }
    if !peak_power.is_finite() {
        return Err(DspError::NonFiniteResult { what: "response peak power" });
    }
    let beta_abs = cfg.beta * peak_power;
    let fs = cfg.sample_rate_hz;
    let regularisation: Vec<f64> =
        (0..response.len()).map(|k| beta_abs * cfg.profile.weight(fft::bin_freq_hz(k, n, fs))).collect();
    let delay = cfg.modelling_delay_samples as f64;
    let mut inverse: Vec<Complex64> = response
        .iter()
        .zip(&regularisation)
        .enumerate()
        .map(|(k, (c, r))| {
            let target = Complex64::from_polar(1.0, -2.0 * PI * k as f64 * delay / n as f64);
            c.conj() * target / (c.norm_sqr() + r)
        })
        .collect();
    if inverse.iter().any(|h| !(h.re.is_finite() && h.im.is_finite())) {
        return Err(DspError::NonFiniteResult { what: "Kirkeby inverse spectrum" });
    }
    if cfg.target == TargetPhase::Minimum {
        // The achieved response R = C H (delay removed) is real and >= 0; give it its minimum phase.
        let achieved: Vec<f64> =
            response.iter().zip(&regularisation).map(|(c, r)| c.norm_sqr() / (c.norm_sqr() + r)).collect();
        let min_phase = minimum_phase_spectrum(&achieved, n)?;
        for (h, m) in inverse.iter_mut().zip(&min_phase) {
            let norm = m.norm();
            if norm > 0.0 {
                *h *= m / norm;
            }
        }
    }
    Ok(KirkebySpectrum { fft_len: n, response, regularisation, inverse })
}

/// Designs a Kirkeby inverse filter for `response_ir` (sampled at `cfg.sample_rate_hz`).
///
/// The design spectrum ([`design_spectrum`]) is transformed back and truncated to `cfg.fir_len` taps, tapered by
/// half-Hann fades over the first quarter of the taps before the modelling delay and the last quarter of the taps
/// after it, so the main peak near the delay is untouched while the truncation's discontinuities are smoothed.
///
/// # Errors
/// As [`design_spectrum`].
pub fn design(response_ir: &[f64], cfg: &KirkebyConfig) -> Result<KirkebyFilter, DspError> {
    let spectrum = design_spectrum(response_ir, cfg)?;
    let n = spectrum.fft_len;
    let mut taps = fft::inverse(&spectrum.inverse, n)?;
    taps.truncate(cfg.fir_len);
    let delay = cfg.modelling_delay_samples;
    let head = window::fade_in(delay / 4);
    let tail = window::fade_out((cfg.fir_len - delay) / 4);
    taps.iter_mut().zip(&head).for_each(|(t, w)| *t *= w);
    let tail_start = cfg.fir_len - tail.len();
    taps[tail_start..].iter_mut().zip(&tail).for_each(|(t, w)| *t *= w);
    check_result("Kirkeby filter taps", &taps)?;
    let max_response = spectrum.response.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let max_filter = fft::forward(&taps, n)?.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let max_boost_db = 20.0 * (max_filter * max_response).log10();
    if !max_boost_db.is_finite() {
        // All-zero taps (or an overflow): no finite boost to report.
        return Err(DspError::NonFiniteResult { what: "Kirkeby filter maximum boost" });
    }
    Ok(KirkebyFilter { taps, sample_rate_hz: cfg.sample_rate_hz, modelling_delay_samples: delay, max_boost_db })
}

impl KirkebyFilter {
    /// Filters `x` through the taps: full linear convolution (`x.len() + taps.len() - 1` samples), by FFT.
    ///
    /// # Errors
    /// An empty or non-finite `x`, or a combined length above [`fft::MAX_FFT_LEN`].
    pub fn apply(&self, x: &[f64]) -> Result<Vec<f64>, DspError> {
        conv::convolve(x, &self.taps)
    }
}

//! Deconvolution: impulse responses from a recording and the excitation (or loopback reference) that produced it.
//!
//! All modes share one estimator, a regularised spectral division ([`divide_spectra`]):
//! `H = N conj(D) / (|D|^2 + eps)`, then a smooth band limit. The regularisation `eps` is relative
//! (`regularisation * max |D|^2` over the band), so one value suits any excitation level. Within the band, where a
//! sweep puts its energy, `eps` is negligible and the division is exact; outside it, where the excitation is weak,
//! `eps` caps the noise gain at `1 / (2 sqrt(eps))` instead of letting it explode.
//!
//! - [`deconvolve`]: linear deconvolution by the excitation that was played.
//! - [`deconvolve_with_reference`]: by the loopback channel recorded beside the response, so that latency and the
//!   offset between the audio and DAQ clocks cancel.
//! - [`deconvolve_periodic`]: circular deconvolution of one steady-state period of a repeated excitation.
//! - [`separate_harmonics`]: exponential sweeps; cuts the harmonic impulse responses out of the negative-time part of
//!   the deconvolved signal and measures the distortion level.
//!
//! Every mode returns `ir_len` samples from time `-pre_samples` ([`DeconvConfig::pre_samples`], default 0): a
//! band-limited estimate is two-sided, and its negative-time part matters wherever the response's spectrum does.

use std::f64::consts::PI;

use num_complex::Complex64;

use crate::band::BandLimit;
use crate::error::{DspError, check_result, check_sample_rate, check_signal};
use crate::fft;
use crate::sweep::SweepSpec;

/// An excitation whose strongest in-band bin is below this fraction (in amplitude) of its strongest bin overall has
/// "no energy in the band": FFT rounding noise is about `f64::EPSILON * log2(n)`, below 1e-14 of the peak for every
/// length up to [`fft::MAX_FFT_LEN`], so anything under 1e-13 is indistinguishable from rounding.
const MIN_IN_BAND_AMPLITUDE_REL: f64 = 1e-13;

/// How far inside its excited range `[k f1, f2]` a harmonic's level is measured, in Fresnel widths `sqrt(F / L)`
/// (the width of the ripple at the start and end of a sweep running at `F / L` Hz/s). At the ends the k-th
/// harmonic's spectrum and the excitation's do not match (the harmonic starts abruptly at `k f1` while the
/// excitation is in full swing; the excitation fades out at `f2` while the harmonic does not), which biases the
/// ratio by up to 2 dB when a resonance sits at an end; two widths in, the ripple has settled (0.3 dB measured).
pub const FRESNEL_MARGINS: f64 = 2.0;

/// Periods of the narrowest band-limit skirt that the FFT length keeps clear of wrap-around (see
/// [`deconvolve`]): 8, which leaves the skirt's ringing 256 times below a brick wall's.
pub const RINGING_GUARD_CYCLES: f64 = 8.0;

/// Floor of the harmonic levels of [`HarmonicResponses`], dB. Energies below 1e-30 of the linear one are f64 rounding
/// (about 1e-32 of the energy); the floor keeps a perfectly linear system's level finite.
pub const MIN_LEVEL_DB: f64 = -300.0;

/// What a deconvolution returns and how it treats the spectrum.
///
/// Valid range: finite positive `sample_rate_hz`; `ir_len >= 1` (and within the FFT limit); `pre_samples < ir_len`;
/// a `band` whose own checks pass and whose `hi_hz` is at most Nyquist (`sample_rate_hz / 2`); `regularisation`
/// finite and `>= 0`.
/// A regularisation of 0 is plain division: exact for a noise-free excitation without spectral zeros in the band,
/// and reported as [`DspError::NonFiniteResult`] when the excitation has an exact zero there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeconvConfig {
    /// Sample rate of all signals, Hz.
    pub sample_rate_hz: f64,
    /// Number of samples of impulse response returned, the first at time `-pre_samples` (time 0 is the start of the
    /// excitation).
    pub ir_len: usize,
    /// Samples of negative time returned before time 0 (taken from the end of the circular result), so that the
    /// impulse response's time 0 lies at index `pre_samples`. 0 returns the causal part only.
    ///
    /// Why: a band-limited estimate is two-sided. The band limit (and the sweep's own band, both zero-phase) smear
    /// an abrupt onset, such as a voice coil's, into negative time; cutting that part off changes the in-band
    /// spectrum by roughly the Hilbert transform of what was cut, a broad error (up to 1.4 dB over 62..625 Hz on a
    /// model voice coil, see tests/calibration.rs), not a local one. Keep it whenever the response's spectrum (not only its causal waveform) is used, as
    /// in a Kirkeby design (see [`crate::kirkeby::KirkebyConfig::response_delay_samples`]).
    pub pre_samples: usize,
    /// Smooth band limit applied to the result; `None` keeps the full band, 0 Hz to Nyquist.
    pub band: Option<BandLimit>,
    /// Relative regularisation: `eps = regularisation * max |D(f)|^2` over the bins where the band gain is non-zero.
    pub regularisation: f64,
}

impl DeconvConfig {
    /// The paper's measurement: 24 kHz, 0.5 s of impulse response (12000 samples), band 62 to 625 Hz (the sweep's
    /// range) with raised-cosine skirts of 20 Hz below (to 42 Hz) and 50 Hz above (to 675 Hz, well short of the
    /// first resonator mode at 781 Hz), and a regularisation of 1e-3 (-30 dB).
    ///
    /// Why 1e-3: the paper's linear sweep has a flat power spectrum in its band that dips at worst to about a sixth
    /// of its peak in the edge ripple, so the bias `eps / (|D|^2 + eps)` stays below 0.6 % (-44 dB, tested) in the
    /// band, under the noise of an LDV recording, while the noise gain in the skirts is capped at
    /// `1 / (2 sqrt(1e-3))`, about 16 times the in-band gain. An exponential sweep's power falls by 10 dB across
    /// this band, so the same value would bias its top end by up to -25 dB: use about 1e-5 with it.
    pub fn paper() -> Self {
        Self {
            sample_rate_hz: 24_000.0,
            ir_len: 12_000,
            band: Some(BandLimit { lo_hz: 62.0, hi_hz: 625.0, lo_transition_hz: 20.0, hi_transition_hz: 50.0 }),
            regularisation: 1e-3,
            pre_samples: 0,
        }
    }

    /// Actuator calibration (a 3 s linear sweep 50..625 Hz at 24 kHz, deconvolved for a Kirkeby design with
    /// [`crate::kirkeby::KirkebyConfig::calibration`]): a two-sided impulse response of 8192 samples (341 ms), the
    /// first 2048 (85 ms) before time 0; band 50..625 Hz with skirts of 20 Hz below and 100 Hz above; regularisation
    /// 1e-4.
    ///
    /// - `pre_samples` 2048: the voice coil's response starts abruptly, so the band limit smears its onset into
    ///   negative time; cut off, that part would bias the in-band spectrum by a broad, smooth error (1.4 dB on a
    ///   model coil, and -1.38 .. +0.14 dB after compensation: tests/calibration.rs). The smear decays with the 20 Hz skirt, over about its period, 50 ms
    ///   (1200 samples); on a model coil 1024 samples leave 0.04 dB, and 2048 (1.7 periods) gives margin for
    ///   actuators with a stronger low-frequency onset.
    /// - `ir_len` 8192: 6144 samples (256 ms) after time 0, for the same ringing after the response plus the
    ///   suspension's decay (9 ms time constant at 70 Hz, Q 2), with room for a slower mount resonance.
    /// - band 50..625 Hz: the whole sweep, and no narrower than the Kirkeby band (50..625 Hz, see
    ///   [`crate::kirkeby::KirkebyConfig::calibration_default`]): a band limit inside the Kirkeby band
    ///   would look like a roll-off of the actuator and be inverted (the paper's 62 Hz edge costs 0.3 dB at 62 Hz
    ///   and 4 dB more boost). The 100 Hz upper skirt leaves the measured response smooth where the Kirkeby
    ///   regularisation rises (625..825 Hz).
    /// - regularisation 1e-4: its bias `eps / (|D|^2 + eps)` goes straight into the filter (the design inverts it),
    ///   so it is kept ten times below the paper's, under 0.1 % (0.005 dB) in the band; out of the band the noise gain
    ///   is still capped at 50 (34 dB), and the Kirkeby regularisation ignores what lies there.
    pub fn calibration() -> Self {
        Self {
            sample_rate_hz: 24_000.0,
            ir_len: 8192,
            band: Some(BandLimit { lo_hz: 50.0, hi_hz: 625.0, lo_transition_hz: 20.0, hi_transition_hz: 100.0 }),
            regularisation: 1e-4,
            pre_samples: 2048,
        }
    }

    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming the offending field, or [`DspError::TooLong`] for an `ir_len` above
    /// [`fft::MAX_FFT_LEN`].
    pub fn validate(&self) -> Result<(), DspError> {
        check_sample_rate(self.sample_rate_hz)?;
        if self.ir_len == 0 {
            return Err(DspError::InvalidParameter { name: "ir_len", reason: "must be at least 1 sample".into() });
        }
        if self.ir_len > fft::MAX_FFT_LEN {
            return Err(DspError::TooLong { what: "impulse response", len: self.ir_len, max: fft::MAX_FFT_LEN });
        }
        if self.pre_samples >= self.ir_len {
            return Err(DspError::InvalidParameter {
                name: "pre_samples",
                reason: format!(
                    "{} samples before time 0 leave no room for time 0 in an impulse response of {} samples",
                    self.pre_samples, self.ir_len
                ),
            });
        }
        if let Some(band) = &self.band {
            band.validate()?;
            let nyquist_hz = self.sample_rate_hz / 2.0;
            if band.hi_hz > nyquist_hz {
                return Err(DspError::InvalidParameter {
                    name: "band.hi_hz",
                    reason: format!("{} Hz lies above Nyquist ({nyquist_hz} Hz)", band.hi_hz),
                });
            }
        }
        check_regularisation(self.regularisation)
    }
}

fn check_regularisation(regularisation: f64) -> Result<(), DspError> {
    if regularisation.is_finite() && regularisation >= 0.0 {
        Ok(())
    } else {
        Err(DspError::InvalidParameter {
            name: "regularisation",
            reason: format!("must be finite and >= 0, got {regularisation}"),
        })
    }
}

fn check_spectrum(input: &'static str, x: &[Complex64]) -> Result<(), DspError> {
    if x.is_empty() {
        return Err(DspError::Empty { input });
    }
    match x.iter().position(|c| !(c.re.is_finite() && c.im.is_finite())) {
        Some(index) => Err(DspError::NonFinite { input, index, value: x[index].re + x[index].im }),
        None => Ok(()),
    }
}

/// Regularised spectral division `H = N conj(D) / (|D|^2 + eps)`, with `eps = regularisation * max |D|^2` over the
/// bins where the band gain is positive (all bins without gains), then multiplied by the band gains if given. Bins
/// whose gain is exactly 0 are set to 0 without dividing.
///
/// Valid range: slices of equal, non-zero length (`n / 2 + 1` bins of a length-`n` real FFT, though any length
/// works); finite bins with `|D| < 1e150` (so `|D|^2` cannot overflow); gains finite and `>= 0`; `regularisation`
/// finite and `>= 0`.
///
/// # Errors
/// - [`DspError::Empty`] / [`DspError::NonFinite`] / [`DspError::LengthMismatch`] for bad slices;
/// - [`DspError::InvalidParameter`] for a negative or non-finite gain or regularisation, for gains that are all
///   zero, or for a denominator with no energy where the gain is positive (its strongest in-band bin below 1e-13 of
///   its strongest bin: all zero, or content only outside the band);
/// - [`DspError::NonFiniteResult`] when the division overflows, e.g. a regularisation of 0 with an exact spectral
///   zero of the denominator inside the band.
pub fn divide_spectra(
    numerator: &[Complex64],
    denominator: &[Complex64],
    band_gains: Option<&[f64]>,
    regularisation: f64,
) -> Result<Vec<Complex64>, DspError> {
    check_spectrum("numerator spectrum", numerator)?;
    check_spectrum("denominator spectrum", denominator)?;
    if numerator.len() != denominator.len() {
        return Err(DspError::LengthMismatch {
            what: "numerator and denominator spectra",
            a: numerator.len(),
            b: denominator.len(),
        });
    }
    check_regularisation(regularisation)?;
    if let Some(gains) = band_gains {
        if gains.len() != denominator.len() {
            return Err(DspError::LengthMismatch {
                what: "band gains and spectra",
                a: gains.len(),
                b: denominator.len(),
            });
        }
        if let Some(i) = gains.iter().position(|g| !(g.is_finite() && *g >= 0.0)) {
            return Err(DspError::InvalidParameter {
                name: "band_gains",
                reason: format!("must be finite and >= 0, got {} at bin {i}", gains[i]),
            });
        }
    }
    let gain = |k: usize| band_gains.map_or(1.0, |g| g[k]);
    let power: Vec<f64> = denominator.iter().map(Complex64::norm_sqr).collect();
    let peak_power = power.iter().copied().fold(0.0, f64::max);
    let in_band_peak_power =
        power.iter().enumerate().filter(|&(k, _)| gain(k) > 0.0).map(|(_, &p)| p).fold(f64::NEG_INFINITY, f64::max);
    if in_band_peak_power == f64::NEG_INFINITY {
        return Err(DspError::InvalidParameter { name: "band_gains", reason: "are zero at every bin".into() });
    }
    // Compare amplitudes rather than powers so that the threshold's square cannot underflow.
    if peak_power == 0.0 || in_band_peak_power.sqrt() <= MIN_IN_BAND_AMPLITUDE_REL * peak_power.sqrt() {
        return Err(DspError::InvalidParameter {
            name: "denominator spectrum",
            reason: "has no energy in the band (all zero, or content only outside the band): nothing to divide by"
                .into(),
        });
    }
    let eps = regularisation * in_band_peak_power;
    let h: Vec<Complex64> = numerator
        .iter()
        .zip(denominator)
        .zip(&power)
        .enumerate()
        .map(|(k, ((num, den), p))| {
            let g = gain(k);
            if g == 0.0 { Complex64::new(0.0, 0.0) } else { num * den.conj() * (g / (p + eps)) }
        })
        .collect();
    if h.iter().all(|c| c.re.is_finite() && c.im.is_finite()) {
        Ok(h)
    } else {
        Err(DspError::NonFiniteResult { what: "regularised spectral division" })
    }
}

/// How much [`divide_spectra`] scales its numerator at each bin, as an amplitude: `g |D| / (|D|^2 + eps)` with the
/// same `eps` and band gains `g`. The noise of a numerator with variance `v` per bin leaves the division with
/// variance `v` times its square (the row error estimate: `pipeline`).
///
/// Valid range and errors: as [`divide_spectra`] with the denominator alone (no numerator is read).
pub fn division_gains(
    denominator: &[Complex64],
    band_gains: Option<&[f64]>,
    regularisation: f64,
) -> Result<Vec<f64>, DspError> {
    let ones = vec![Complex64::new(1.0, 0.0); denominator.len()];
    // The division of ones by D is conj(D) g / (|D|^2 + eps): its magnitude is the gain, with every check shared.
    Ok(divide_spectra(&ones, denominator, band_gains, regularisation)?.iter().map(|h| h.norm()).collect())
}

/// Refuses a constant excitation of two or more samples: a DC level (an offset, or a dead channel) carries no
/// designed content at any non-zero frequency; dividing by the edges of its rectangle would only amplify noise.
/// A single sample is an impulse, a valid excitation.
pub fn check_not_constant(input: &'static str, x: &[f64]) -> Result<(), DspError> {
    let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let peak = lo.abs().max(hi.abs());
    // A few ulps of spread is still a constant that went through arithmetic.
    if x.len() >= 2 && hi - lo <= 4.0 * f64::EPSILON * peak {
        let reason = if peak == 0.0 {
            "is all zero: it has no energy to divide by".to_string()
        } else {
            format!("is constant ({lo}): a DC level has no energy at any non-zero frequency")
        };
        return Err(DspError::InvalidParameter { name: input, reason });
    }
    Ok(())
}

/// Band-limited, regularised spectrum of `numerator / denominator` at FFT length `n` (both zero-padded to `n`).
fn deconvolved_spectrum(
    numerator: &[f64],
    denominator: &[f64],
    n: usize,
    cfg: &DeconvConfig,
) -> Result<Vec<Complex64>, DspError> {
    let num = fft::forward(numerator, n)?;
    let den = fft::forward(denominator, n)?;
    let gains = cfg.band.map(|b| b.bin_gains(n, cfg.sample_rate_hz));
    divide_spectra(&num, &den, gains.as_deref(), cfg.regularisation)
}

/// `len` samples of the inverse FFT of `spectrum` after delaying it by `delay_samples` (a fractional, circular phase
/// ramp), starting `pre` samples before time 0 (taken from the end of the circular result), checked finite.
/// Needs `pre < len <= n`.
fn window_samples(
    spectrum: &[Complex64],
    n: usize,
    delay_samples: f64,
    pre: usize,
    len: usize,
) -> Result<Vec<f64>, DspError> {
    let mut x = if delay_samples == 0.0 {
        fft::inverse(spectrum, n)?
    } else {
        let step = -2.0 * PI * delay_samples / n as f64;
        let delayed: Vec<Complex64> =
            spectrum.iter().enumerate().map(|(k, c)| c * Complex64::from_polar(1.0, step * k as f64)).collect();
        fft::inverse(&delayed, n)?
    };
    x.rotate_right(pre);
    x.truncate(len);
    check_result("deconvolution", &x)?;
    Ok(x)
}

/// Extra FFT length, samples, that keeps the band limit's ringing from wrapping into the returned samples:
/// `RINGING_GUARD_CYCLES / W` for the narrowest non-zero skirt width `W`. A band limit makes the response
/// non-causal: it rings before time 0 and after the response's end, and a raised-cosine skirt's ringing decays as
/// `(W t)^-3` relative to a brick wall's, which after 8 / W is down by `4 (W t)^2 = 256`. Edges without a skirt
/// (a brick wall, sensible only at 0 Hz or Nyquist) get no guard: their 1/t ringing would need an unbounded one.
fn ringing_guard(cfg: &DeconvConfig) -> usize {
    let Some(band) = cfg.band else { return 0 };
    let narrowest_hz =
        [band.lo_transition_hz, band.hi_transition_hz].into_iter().filter(|w| *w > 0.0).fold(f64::INFINITY, f64::min);
    if narrowest_hz.is_finite() {
        // Capped at the FFT limit, so a sub-hertz skirt gives a TooLong error rather than an overflow.
        (RINGING_GUARD_CYCLES * cfg.sample_rate_hz / narrowest_hz).ceil().min(fft::MAX_FFT_LEN as f64) as usize
    } else {
        0
    }
}

/// Shared linear mode: FFT length `>= max(numerator.len(), denominator.len() + ir_len) + pre_samples` plus the band
/// limit's [`ringing_guard`], so that neither the response tail, nor the negative-time part of the result (noise,
/// harmonics), nor the band limit's ringing wraps into the returned samples (`pre_samples` keeps the recording's
/// end clear of the negative-time samples returned).
fn deconvolve_linear(
    numerator: (&'static str, &[f64]),
    denominator: (&'static str, &[f64]),
    cfg: &DeconvConfig,
) -> Result<Vec<f64>, DspError> {
    cfg.validate()?;
    check_signal(numerator.0, numerator.1)?;
    check_signal(denominator.0, denominator.1)?;
    check_not_constant(denominator.0, denominator.1)?;
    let min_len = numerator
        .1
        .len()
        .max(denominator.1.len().saturating_add(cfg.ir_len))
        .saturating_add(cfg.pre_samples)
        .saturating_add(ringing_guard(cfg));
    let n = fft::fast_len(min_len)?;
    let spectrum = deconvolved_spectrum(numerator.1, denominator.1, n, cfg)?;
    window_samples(&spectrum, n, 0.0, cfg.pre_samples, cfg.ir_len)
}

/// Linear deconvolution of a recording by the excitation that produced it: `cfg.ir_len` samples of the impulse
/// response from time `-cfg.pre_samples` (so time 0, the first sample of the excitation, is at index
/// `cfg.pre_samples`; with the default 0, the first `ir_len` samples from time 0), in recording units per excitation
/// unit.
///
/// The FFT length is a fast length `>= max(recording.len(), excitation.len() + ir_len) + pre_samples`, so the result
/// cannot
/// time-alias, plus a guard of [`RINGING_GUARD_CYCLES`] periods of the band's narrowest skirt, so that the band
/// limit's ringing (before time 0 and after the response's end) does not wrap into it either; for the paper's
/// 3 s sweep and 20 Hz skirt that is 0.4 s more. Exact (to the regularisation bias) when the recording starts with the excitation and holds the whole
/// response tail, i.e. is at least `excitation.len() + (response length) - 1` long.
///
/// Valid range: see [`DeconvConfig`]; finite signals; `recording.len() >= excitation.len()`; an excitation that is
/// not constant and has energy in the band.
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`] for a bad signal; [`DspError::InvalidParameter`] for a bad
/// configuration, a recording shorter than the excitation (the sweep's end was not recorded), or an excitation that
/// is all zero, constant or without energy in the band; [`DspError::NonFiniteResult`] when the division overflows
/// (regularisation 0 on an excitation with an exact spectral zero in the band).
pub fn deconvolve(recording: &[f64], excitation: &[f64], cfg: &DeconvConfig) -> Result<Vec<f64>, DspError> {
    check_signal("recording", recording)?;
    check_signal("excitation", excitation)?;
    check_recording_covers(recording.len(), excitation.len())?;
    deconvolve_linear(("recording", recording), ("excitation", excitation), cfg)
}

fn check_recording_covers(recording_len: usize, excitation_len: usize) -> Result<(), DspError> {
    if recording_len < excitation_len {
        return Err(DspError::InvalidParameter {
            name: "recording",
            reason: format!(
                "holds {recording_len} samples, fewer than the excitation's {excitation_len}: its end was not recorded"
            ),
        });
    }
    Ok(())
}

/// Reference mode: deconvolves the response by the loopback reference recorded beside it on the same DAQ clock, so
/// the start latency of the audio interface and its clock offset against the DAQ cancel: the result is the impulse
/// response from the reference to the response, time 0 being the reference's own timing.
///
/// Both recordings must have the same length (they come from one DAQ acquisition) and should extend past the end of
/// the response tail. FFT length and validity as for [`deconvolve`], with `reference` as the excitation.
///
/// # Errors
/// As [`deconvolve`]; [`DspError::LengthMismatch`] when the two lengths differ.
pub fn deconvolve_with_reference(
    response: &[f64],
    reference: &[f64],
    cfg: &DeconvConfig,
) -> Result<Vec<f64>, DspError> {
    if response.len() != reference.len() {
        return Err(DspError::LengthMismatch {
            what: "response and reference recordings",
            a: response.len(),
            b: reference.len(),
        });
    }
    deconvolve_linear(("response", response), ("reference", reference), cfg)
}

/// Circular (periodic) deconvolution of one steady-state period of a periodically repeated excitation: the FFT
/// length is exactly the period. Returns `cfg.ir_len` samples from time `-cfg.pre_samples` (the negative-time samples
/// are the end of the period).
///
/// Valid when the impulse response (including the band limit's ringing) is shorter than the period, so that the
/// circular convolution does not alias it; `ir_len` must not exceed the period. Both periods must be taken at the
/// same position of the cycle (the reference's timing is time 0).
///
/// # Errors
/// As [`deconvolve_with_reference`]; [`DspError::InvalidParameter`] for an `ir_len` longer than the period.
pub fn deconvolve_periodic(
    response_period: &[f64],
    reference_period: &[f64],
    cfg: &DeconvConfig,
) -> Result<Vec<f64>, DspError> {
    cfg.validate()?;
    check_signal("response period", response_period)?;
    check_signal("reference period", reference_period)?;
    if response_period.len() != reference_period.len() {
        return Err(DspError::LengthMismatch {
            what: "response and reference periods",
            a: response_period.len(),
            b: reference_period.len(),
        });
    }
    check_not_constant("reference period", reference_period)?;
    let n = reference_period.len();
    if cfg.ir_len > n {
        return Err(DspError::InvalidParameter {
            name: "ir_len",
            reason: format!("{} samples exceed the period of {n} samples", cfg.ir_len),
        });
    }
    let spectrum = deconvolved_spectrum(response_period, reference_period, n, cfg)?;
    window_samples(&spectrum, n, 0.0, cfg.pre_samples, cfg.ir_len)
}

/// The impulse responses that an exponential sweep separates: linear and harmonic, with their levels.
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicResponses {
    /// Linear impulse response, `ir_len` samples from time `-pre_samples` (what [`deconvolve`] returns).
    pub linear: Vec<f64>,
    /// Harmonic impulse responses: `harmonics[0]` is order k = 2, up to `max_order`; each `ir_len` samples from
    /// `pre_samples` before its own arrival time `-L ln k`.
    pub harmonics: Vec<Vec<f64>>,
    /// Energy of each harmonic response relative to the linear one at the same output frequencies, dB (floored at
    /// [`MIN_LEVEL_DB`]); `harmonic_level_db[0]` is k = 2.
    pub harmonic_level_db: Vec<f64>,
    /// Total: `10 log10(sum of the harmonic energy ratios)`, dB (THD-like; floored at [`MIN_LEVEL_DB`]).
    pub distortion_db: f64,
}

/// Separates the linear and harmonic impulse responses of a recording made with an exponential sweep
/// (`sweep.generate()` is the excitation; the recording starts with it).
///
/// After deconvolution the k-th harmonic's response arrives `L ln k` before the linear one (`L =
/// sweep.exp_rate_s()`). Windows: each response, linear and harmonic, is the `ir_len` samples starting
/// `cfg.pre_samples` before its arrival time (exactly at it by default), cut rectangularly (no fade), the same cut
/// [`deconvolve`] makes for the linear response: `ir_len` is
/// meant to be long enough for the response to have decayed, and a fade would bias the levels. A fractional arrival
/// time is honoured by a phase ramp before the cut, not rounded. Harmonic k's window ends where harmonic k - 1's
/// begins at the latest; windows that would overlap (`ir_len / fs > L ln(max_order / (max_order - 1))`) are an
/// error, never silently shortened. Orders above `max_order` are not separated: if present, their responses arrive
/// before harmonic `max_order`'s and leak into its window when longer than `L ln((max_order + 1) / max_order)`.
///
/// Levels: harmonic k is excited only at output frequencies from `k f1` to `f2` (the harmonic of the sweep's start
/// up to the sweep's end); its level is the energy of its response over those frequencies, less
/// [`FRESNEL_MARGINS`] at each end and within the band, divided by the linear response's energy over the same
/// frequencies (both from `ir_len`-point FFTs of the cut responses). For a memoryless nonlinearity followed by a linear
/// filter this is `20 log10` of the k-th harmonic's amplitude over the fundamental's at the nonlinearity's output,
/// whatever the filter. `distortion_db` sums the energy ratios.
///
/// FFT length: fast length `>= max(recording.len(), ir_len) + sweep length + pre_samples`, plus the band-limit guard of
/// [`deconvolve`], so that the negative-time harmonics never wrap onto positive-time content.
///
/// Valid range: an exponential [`SweepSpec`] at `cfg.sample_rate_hz`; `2 <= max_order` with a non-empty range
/// (with margins) for `max_order`;
/// windows that fit as above; a finite recording at least as long as the sweep.
///
/// # Errors
/// [`DspError::InvalidParameter`] for a linear sweep, mismatched sample rates, a `max_order` out of range,
/// overlapping windows, a recording shorter than the sweep, or a linear response with no energy where a harmonic is
/// measured (its level would be undefined); otherwise as [`deconvolve`].
pub fn separate_harmonics(
    recording: &[f64],
    sweep: &SweepSpec,
    max_order: u32,
    cfg: &DeconvConfig,
) -> Result<HarmonicResponses, DspError> {
    cfg.validate()?;
    sweep.validate()?;
    let fs = cfg.sample_rate_hz;
    let rate_s = check_harmonic_setup(sweep, max_order, cfg)?;
    let excitation = sweep.generate()?;
    check_signal("recording", recording)?;
    check_recording_covers(recording.len(), excitation.len())?;
    let min_len = recording
        .len()
        .max(cfg.ir_len)
        .saturating_add(excitation.len())
        .saturating_add(cfg.pre_samples)
        .saturating_add(ringing_guard(cfg));
    let n = fft::fast_len(min_len)?;
    let spectrum = deconvolved_spectrum(recording, &excitation, n, cfg)?;
    let linear = window_samples(&spectrum, n, 0.0, cfg.pre_samples, cfg.ir_len)?;
    let linear_spectrum = fft::forward(&linear, cfg.ir_len)?;
    let mut harmonics = Vec::new();
    let mut harmonic_level_db = Vec::new();
    for k in 2..=max_order {
        let arrival_samples = rate_s * f64::from(k).ln() * fs;
        let h = window_samples(&spectrum, n, arrival_samples, cfg.pre_samples, cfg.ir_len)?;
        let range_hz = harmonic_range_hz(sweep, rate_s, k);
        let level = level_db(&fft::forward(&h, cfg.ir_len)?, &linear_spectrum, range_hz, k, cfg)?;
        harmonics.push(h);
        harmonic_level_db.push(level);
    }
    let total: f64 = harmonic_level_db.iter().map(|db| 10f64.powf(db / 10.0)).sum();
    let distortion_db = (10.0 * total.log10()).max(MIN_LEVEL_DB);
    Ok(HarmonicResponses { linear, harmonics, harmonic_level_db, distortion_db })
}

/// Checks what [`separate_harmonics`] needs of the sweep and the orders; returns the sweep's rate `L`, s.
fn check_harmonic_setup(sweep: &SweepSpec, max_order: u32, cfg: &DeconvConfig) -> Result<f64, DspError> {
    let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
    let Some(rate_s) = sweep.exp_rate_s() else {
        return invalid("sweep.kind", "harmonic separation needs an exponential sweep".into());
    };
    if sweep.sample_rate_hz != cfg.sample_rate_hz {
        return invalid(
            "sweep.sample_rate_hz",
            format!("{} Hz differs from the configuration's {} Hz", sweep.sample_rate_hz, cfg.sample_rate_hz),
        );
    }
    if max_order < 2 {
        return invalid("max_order", format!("must be at least 2, got {max_order}"));
    }
    let order = f64::from(max_order);
    let (lo_hz, hi_hz) = harmonic_range_hz(sweep, rate_s, max_order);
    if lo_hz >= hi_hz {
        return invalid(
            "max_order",
            format!(
                "harmonic {max_order} has no clean range to measure: {max_order} x {} Hz plus margins ({lo_hz} Hz) \
                 is not below the sweep's end less margins ({hi_hz} Hz); use a wider or longer sweep",
                sweep.f1_hz
            ),
        );
    }
    let spacing_s = rate_s * (order / (order - 1.0)).ln();
    let ir_len_s = cfg.ir_len as f64 / cfg.sample_rate_hz;
    if ir_len_s > spacing_s {
        return invalid(
            "ir_len",
            format!(
                "{ir_len_s} s is longer than the {spacing_s} s between harmonics {} and {max_order}: the windows \
                 would overlap; use a longer sweep, a shorter ir_len or a lower max_order",
                max_order - 1
            ),
        );
    }
    Ok(rate_s)
}

/// Output frequencies, Hz, where harmonic k is cleanly measured: from `k f1` to `f2`, each end moved inwards by
/// [`FRESNEL_MARGINS`] Fresnel widths.
fn harmonic_range_hz(sweep: &SweepSpec, rate_s: f64, k: u32) -> (f64, f64) {
    let lo_hz = f64::from(k) * sweep.f1_hz;
    let hi_hz = sweep.f2_hz;
    // At output frequency F every order sweeps at dF/dt = F / L, so the edge ripple is sqrt(F / L) wide.
    (lo_hz + FRESNEL_MARGINS * (lo_hz / rate_s).sqrt(), hi_hz - FRESNEL_MARGINS * (hi_hz / rate_s).sqrt())
}

/// Energy of `harmonic` over `linear` at the bins in `[range_hz.0, range_hz.1]` with a positive band gain, dB.
fn level_db(
    harmonic: &[Complex64],
    linear: &[Complex64],
    range_hz: (f64, f64),
    k: u32,
    cfg: &DeconvConfig,
) -> Result<f64, DspError> {
    let (mut e_harmonic, mut e_linear, mut bins) = (0.0, 0.0, 0usize);
    for (j, (h, l)) in harmonic.iter().zip(linear).enumerate() {
        let f_hz = fft::bin_freq_hz(j, cfg.ir_len, cfg.sample_rate_hz);
        let in_band = cfg.band.is_none_or(|b| b.gain(f_hz) > 0.0);
        if f_hz >= range_hz.0 && f_hz <= range_hz.1 && in_band {
            e_harmonic += h.norm_sqr();
            e_linear += l.norm_sqr();
            bins += 1;
        }
    }
    if bins == 0 || e_linear == 0.0 {
        return Err(DspError::InvalidParameter {
            name: "recording",
            reason: format!(
                "the linear response has no energy ({bins} bins) from {} to {} Hz within the band, where harmonic \
                 {k} is measured: its level is undefined",
                range_hz.0, range_hz.1
            ),
        });
    }
    let level = (10.0 * (e_harmonic / e_linear).log10()).max(MIN_LEVEL_DB);
    if level.is_finite() { Ok(level) } else { Err(DspError::NonFiniteResult { what: "harmonic level" }) }
}

//! Clock drift between the player (audio interface) and the recorder (DAQ): where each repetition of an excitation
//! lies in a recording, and the straight line through those positions (latency and drift). The band-limited
//! resampling that puts a recording back on the player's clock is [`crate::resample`] (re-exported here).
//!
//! Model: player sample `j` is recorded at recorder position `latency_samples + j * (1 + drift_ppm * 1e-6)`.
//! Valid range: `|drift_ppm| <= MAX_DRIFT_PPM` and a latency that keeps every repetition inside the recording.
//!
//! Positions come from the loopback channel, a clean copy of the played signal. Each repetition is cut out at its
//! predicted place, circularly cross-correlated with the excitation in the frequency domain, and its delay read from
//! the phase slope of the cross-spectrum, `arg sum_k C(k+1) conj(C(k))`: the weighted mean group delay. It needs no
//! phase unwrapping, is unambiguous up to half a period, and moves exactly with the signal (shift-equivariant), so a
//! drift, which stretches every repetition alike, biases every position by the same amount and the slope of the
//! line stays unbiased. A second pass, once the drift is roughly known, measures that bias on the excitation
//! stretched by the drift and removes it, so the positions are the repetitions' starts.

use std::f64::consts::PI;

use num_complex::Complex64;

use crate::band::BandLimit;
use crate::error::{DspError, check_finite, check_result, check_sample_rate, check_signal};
use crate::fft;
pub use crate::resample::{Interpolator, MAX_RESAMPLE_LEN};

/// Largest clock drift accepted, ppm. Real converters are within tens of ppm; 1000 ppm means a wrong sample rate.
pub const MAX_DRIFT_PPM: f64 = 1000.0;

/// How far beyond [`MAX_DRIFT_PPM`] a fitted drift may land and still be accepted, ppm: a drift right at the limit
/// must not be refused for the estimate's own noise (0.01 ppm on a clean loopback).
pub const DRIFT_SLACK_PPM: f64 = 1.0;

/// Smallest coherence (normalised cross-correlation at the found delay, 0 to 1) for a repetition to count as found.
/// A clean loopback scores above 0.99; below 0.5 the recording is mostly something other than the excitation.
pub const MIN_COHERENCE: f64 = 0.5;

/// Largest rms distance of the positions from their fitted line, samples. Clean loopbacks fit within 0.01 sample;
/// more than a sample means a dropout or a glitch moved a repetition, and averaging it would smear the result.
pub const MAX_FIT_RESIDUAL_SAMPLES: f64 = 1.0;

/// Stretch per copy, samples, above which the copies' positions are measured a second time (see `refine`). Below
/// it the first pass's windows sit within twice that of their copies, inside the first 5 ms (120 samples at
/// 24 kHz) of a faded excitation, where the paper's sweep stays below 2e-3 of full scale.
const REFINE_STRETCH_SAMPLES: f64 = 4.0;

/// Delay of a signal relative to a template, from [`delay_from_spectra`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayEstimate {
    /// Circular delay of the signal relative to the template, samples, in `(-n / 2, n / 2]`.
    pub delay_samples: f64,
    /// Normalised cross-correlation at that delay, 0 (unrelated) to 1 (an exact shifted copy).
    pub coherence: f64,
}

/// Circular delay of a signal relative to a template, both given as the `n / 2 + 1` bins of their length-`n` real
/// FFT, over the bins weighted by `bin_gains` (all bins when `None`).
///
/// Estimator: the phase of `sum_k C(k+1) conj(C(k))` with the cross-spectrum `C = g^2 X conj(T)`, which is
/// `-2 pi delay / n` for a pure delay. Valid range: `n >= 2`; delays within half a period; finite spectra of matching
/// length. A signal that is a stretched copy gets its energy-weighted mean group delay.
///
/// # Errors
/// [`DspError::LengthMismatch`] (lengths differ from `n / 2 + 1`), [`DspError::NonFinite`],
/// [`DspError::InvalidParameter`] (`n < 2`, or no common energy: the cross-spectrum is zero).
pub fn delay_from_spectra(
    signal: &[Complex64],
    template: &[Complex64],
    n: usize,
    bin_gains: Option<&[f64]>,
) -> Result<DelayEstimate, DspError> {
    if n < 2 {
        return Err(DspError::InvalidParameter { name: "n", reason: format!("must be at least 2, got {n}") });
    }
    let bins = fft::bin_count(n);
    for (what, len) in [("signal spectrum", signal.len()), ("template spectrum", template.len())] {
        if len != bins {
            return Err(DspError::LengthMismatch { what, a: len, b: bins });
        }
    }
    if let Some(g) = bin_gains
        && g.len() != bins
    {
        return Err(DspError::LengthMismatch { what: "bin gains", a: g.len(), b: bins });
    }
    fft::check_spectrum_finite("signal spectrum", signal)?;
    fft::check_spectrum_finite("template spectrum", template)?;
    delay_over_span(signal, template, n, bin_gains, weighted_span(n, bin_gains))
}

/// Bins `(first, last)` that carry a phase slope and weight: strictly between DC and Nyquist (those two are real),
/// and within them the span where the gains are non-zero (a band is often a few percent of the bins). Empty when
/// `first > last`.
fn weighted_span(n: usize, bin_gains: Option<&[f64]>) -> (usize, usize) {
    let top = (n - 1) / 2;
    match bin_gains {
        _ if top == 0 => (1, 0),
        Some(g) => {
            let inner = &g[1..=top];
            match (inner.iter().position(|&v| v > 0.0), inner.iter().rposition(|&v| v > 0.0)) {
                (Some(a), Some(b)) => (a + 1, b + 1),
                _ => (1, 0),
            }
        }
        None => (1, top),
    }
}

/// [`delay_from_spectra`] over the bins `first..=last` (from [`weighted_span`]) of spectra whose lengths have been
/// checked. Only those bins are read, so only their finiteness matters: a non-finite one makes the energies
/// non-finite, reported as [`DspError::NonFinite`].
fn delay_over_span(
    signal: &[Complex64],
    template: &[Complex64],
    n: usize,
    bin_gains: Option<&[f64]>,
    (first, last): (usize, usize),
) -> Result<DelayEstimate, DspError> {
    let gain2 = |k: usize| bin_gains.map_or(1.0, |g| g[k] * g[k]);
    let cross = |k: usize| signal[k] * template[k].conj() * gain2(k);
    let (mut step, mut signal_energy, mut template_energy) = (Complex64::new(0.0, 0.0), 0.0, 0.0);
    let mut previous = cross(first);
    for k in first..=last {
        let g2 = gain2(k);
        signal_energy += g2 * signal[k].norm_sqr();
        template_energy += g2 * template[k].norm_sqr();
        if k < last {
            let next = cross(k + 1);
            step += next * previous.conj();
            previous = next;
        }
    }
    if !(signal_energy.is_finite() && template_energy.is_finite() && step.re.is_finite() && step.im.is_finite()) {
        // Rare: find the culprit for the message (or report the span's first bin if only the sums overflowed).
        let bad = |c: &Complex64| !(c.re.is_finite() && c.im.is_finite());
        let index = (first..=last).find(|&k| bad(&signal[k]) || bad(&template[k])).unwrap_or(first);
        return Err(DspError::NonFinite { input: "spectra in the band", index, value: f64::NAN });
    }
    let norm = (signal_energy * template_energy).sqrt();
    if step.norm() == 0.0 || !(norm > 0.0 && norm.is_finite()) {
        return Err(DspError::InvalidParameter {
            name: "spectra",
            reason: "have no energy in common in the band: no delay to measure".into(),
        });
    }
    let delay_samples = -step.arg() * n as f64 / (2.0 * PI);
    let turn = Complex64::from_polar(1.0, 2.0 * PI * delay_samples / n as f64);
    // Undo the delay bin by bin with a running phasor: rounding grows by ~1e-16 per bin, 1e-11 over 2^25 bins.
    let mut phasor = turn.powu(first as u32);
    let mut aligned = Complex64::new(0.0, 0.0);
    for k in first..=last {
        aligned += cross(k) * phasor;
        phasor *= turn;
    }
    let coherence = (aligned.norm() / norm).min(1.0);
    Ok(DelayEstimate { delay_samples, coherence })
}

/// Delays `x` circularly by `delay_samples` (any real number; negative advances) with an FFT phase ramp: exact for
/// a periodic band-limited signal. The Nyquist bin of an even length, which cannot carry a fractional delay and stay
/// real, is scaled by `cos(pi delay)`.
///
/// # Errors
/// An empty or non-finite `x`, or a non-finite delay.
pub fn delay_circular(x: &[f64], delay_samples: f64) -> Result<Vec<f64>, DspError> {
    check_signal("signal to delay", x)?;
    if !delay_samples.is_finite() {
        return Err(DspError::InvalidParameter {
            name: "delay_samples",
            reason: format!("must be finite, got {delay_samples}"),
        });
    }
    let n = x.len();
    let mut spectrum = fft::forward(x, n)?;
    // Reduce the delay modulo n so the phase stays accurate for huge delays.
    let d = delay_samples.rem_euclid(n as f64);
    for (k, bin) in spectrum.iter_mut().enumerate() {
        if n.is_multiple_of(2) && k == n / 2 {
            *bin *= (PI * d).cos();
        } else {
            *bin *= Complex64::from_polar(1.0, -2.0 * PI * k as f64 * d / n as f64);
        }
    }
    let y = fft::inverse(&spectrum, n)?;
    check_result("circular delay", &y)?;
    Ok(y)
}

/// Index of the first sample whose magnitude reaches half the signal's peak: a gain-free onset marker.
fn onset(x: &[f64]) -> Option<usize> {
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if peak > 0.0 { x.iter().position(|v| v.abs() >= 0.5 * peak) } else { None }
}

/// Start positions of `repetitions` back-to-back copies of `excitation` in `recording` (a loopback), in recorder
/// samples from the recording's first sample, with sub-sample resolution (see the module documentation). With a
/// single copy the drift is unknown and its stretch biases the position by up to `2 |drift| * len` samples. `band`
/// restricts the estimate to where the excitation has its energy (`None`: all bins).
///
/// Valid range: an excitation of at least 2 samples that starts and ends quietly (a faded sweep; an abrupt one
/// biases the first and last positions, which border silence); copies played back to back at the excitation's
/// length; `|drift| <= MAX_DRIFT_PPM`; the first copy starting within the recording, the recording holding all
/// copies. A noisy loopback is fine as long as each copy's coherence stays above [`MIN_COHERENCE`].
///
/// Locating copies of one excitation in many recordings: prepare it once with [`ExcitationTemplate::new`].
///
/// # Errors
/// Empty or non-finite input, `repetitions == 0`, an invalid band or sample rate; [`DspError::InvalidParameter`]
/// naming `recording` when a copy is not found (silent recording, coherence below [`MIN_COHERENCE`], or a copy
/// outside the recording).
pub fn locate_repetitions(
    recording: &[f64],
    excitation: &[f64],
    repetitions: usize,
    band: Option<&BandLimit>,
    sample_rate_hz: f64,
) -> Result<Vec<f64>, DspError> {
    ExcitationTemplate::new(excitation, band, sample_rate_hz)?.locate(recording, repetitions)
}

/// An excitation prepared for locating its copies and measuring delays against it: its spectrum, its band's bin
/// gains and the span of bins they weight, and its onset, computed once for every recording of it (every actuator
/// at every grid point).
#[derive(Debug, Clone, PartialEq)]
pub struct ExcitationTemplate {
    excitation: Vec<f64>,
    spectrum: Vec<Complex64>,
    gains: Option<Vec<f64>>,
    /// Bins weighted by the delay estimate, from [`weighted_span`].
    span: (usize, usize),
    /// First sample at half the peak magnitude; `None` for a silent excitation.
    onset: Option<usize>,
}

impl ExcitationTemplate {
    /// Prepares `excitation` (one period, at `sample_rate_hz`) with the band `band` (`None`: all bins).
    ///
    /// Valid range: as [`locate_repetitions`]: a finite excitation of at least 2 samples, a valid band, a finite
    /// positive sample rate.
    ///
    /// # Errors
    /// [`DspError::Empty`] / [`DspError::NonFinite`] for the excitation, [`DspError::InvalidParameter`] for one of a
    /// single sample, the band's own errors, or a bad sample rate.
    pub fn new(excitation: &[f64], band: Option<&BandLimit>, sample_rate_hz: f64) -> Result<Self, DspError> {
        check_signal("excitation", excitation)?;
        check_sample_rate(sample_rate_hz)?;
        let n = excitation.len();
        if n < 2 {
            return Err(DspError::InvalidParameter { name: "excitation", reason: "needs at least 2 samples".into() });
        }
        let gains = match band {
            Some(b) => {
                b.validate()?;
                Some(b.bin_gains(n, sample_rate_hz))
            }
            None => None,
        };
        Ok(Self {
            excitation: excitation.to_vec(),
            spectrum: fft::forward(excitation, n)?,
            span: weighted_span(n, gains.as_deref()),
            gains,
            onset: onset(excitation),
        })
    }

    /// The excitation's length, samples: the period of its repetitions and the FFT length of its spectrum.
    pub fn period_samples(&self) -> usize {
        self.excitation.len()
    }

    /// The `n / 2 + 1` bins of the excitation's length-`n` FFT, unnormalised.
    pub fn spectrum(&self) -> &[Complex64] {
        &self.spectrum
    }

    /// The band's gains on those bins; `None` without a band.
    pub fn bin_gains(&self) -> Option<&[f64]> {
        self.gains.as_deref()
    }

    /// Start positions of `repetitions` copies in `recording`: [`locate_repetitions`] with this excitation and band.
    ///
    /// # Errors
    /// As [`locate_repetitions`].
    pub fn locate(&self, recording: &[f64], repetitions: usize) -> Result<Vec<f64>, DspError> {
        check_signal("recording", recording)?;
        self.locate_in_checked(recording, repetitions)
    }

    /// [`ExcitationTemplate::locate`] in a recording already checked non-empty and finite (a pass over a long
    /// recording saved).
    pub(crate) fn locate_in_checked(&self, recording: &[f64], repetitions: usize) -> Result<Vec<f64>, DspError> {
        if repetitions == 0 {
            return Err(DspError::InvalidParameter { name: "repetitions", reason: "must be at least 1".into() });
        }
        let n = self.period_samples();
        let (Some(rec_onset), Some(exc_onset)) = (onset(recording), self.onset) else {
            return Err(not_found("is silent (or the excitation is): no repetition to locate".into()));
        };
        let mut finder = Finder::new(self, recording);
        let mut positions: Vec<f64> = Vec::with_capacity(repetitions);
        for r in 0..repetitions {
            let predicted = match positions.as_slice() {
                [] => rec_onset as f64 - exc_onset as f64,
                [p0] => p0 + n as f64,
                // Extrapolate the line through the positions so far: carries the drift forward.
                ps => {
                    let (a, b) = fit_line(ps);
                    a + b * r as f64
                }
            };
            positions.push(finder.find(r, predicted)?);
        }
        if repetitions >= 2 {
            refine(&mut finder, &mut positions)?;
        }
        Ok(positions)
    }

    /// Circular delay of a length-`n` signal, given as its `n / 2 + 1` FFT bins, relative to the excitation, over the
    /// band: [`delay_from_spectra`] against this template.
    ///
    /// # Errors
    /// As [`delay_from_spectra`].
    pub fn delay_of(&self, spectrum: &[Complex64]) -> Result<DelayEstimate, DspError> {
        if spectrum.len() != self.spectrum.len() {
            return Err(DspError::LengthMismatch {
                what: "signal spectrum",
                a: spectrum.len(),
                b: self.spectrum.len(),
            });
        }
        delay_over_span(spectrum, &self.spectrum, self.period_samples(), self.bin_gains(), self.span)
    }
}

/// Second pass over the positions once the drift is roughly known (from the first pass's line).
///
/// A drift stretches each copy, which moves the delay estimate by a bias `beta` (its mean group delay changes by
/// up to twice the stretch for a linear sweep: 150 samples at 1000 ppm over 3 s). `beta` is measured on the
/// excitation stretched by the drift and subtracted, so the positions are the copies' starts.
///
/// The first pass centred its windows on the biased delays, so they sat `beta` away from the copies, and the first
/// and last windows held silence where the others held a neighbour. When the stretch exceeds
/// `REFINE_STRETCH_SAMPLES` that matters, and the copies are measured again: each window starts at its copy, and
/// everything after the copy's end is blanked (a copy shorter than the window would leave it to the next copy's
/// start, or to silence after the last one), so every window holds one copy and nothing else, in the same place.
fn refine(finder: &mut Finder<'_>, positions: &mut [f64]) -> Result<(), DspError> {
    let template = finder.template;
    let n = template.period_samples();
    let (_, span) = fit_line(positions);
    let ratio = span / n as f64;
    // Far outside the accepted drift the line is meaningless; `fit_clock` refuses it with a clear message.
    if ratio.is_nan() || (ratio - 1.0).abs() > 2.0 * MAX_DRIFT_PPM * 1e-6 {
        return Ok(());
    }
    finder.blank = if span < n as f64 { ((n as f64 - span).ceil() as usize).min(n / 2) } else { 0 };
    // Only the weighted bins count: the kernel need only be accurate up to the last of them.
    let top_bin = template.gains.as_deref().and_then(|g| g.iter().rposition(|&v| v > 0.0)).unwrap_or(n / 2);
    let interpolator = Interpolator::for_band(top_bin as f64 / n as f64, 1.0);
    let mut stretched = interpolator.resample(&template.excitation, 0.0, 1.0 / ratio, n)?;
    stretched[n - finder.blank..].fill(0.0);
    fft::forward_into(&stretched, n, &mut finder.spectrum)?;
    let bias = template.delay_of(&finder.spectrum)?.delay_samples;
    if (span - n as f64).abs() <= REFINE_STRETCH_SAMPLES {
        // The first pass's windows were close enough: only the bias needs removing.
        positions.iter_mut().for_each(|p| *p -= bias);
        return Ok(());
    }
    for (r, p) in positions.iter_mut().enumerate() {
        let start = (*p - bias).round() as i64;
        let est = finder.measure(r, start)?;
        check_coherence(r, start, est)?;
        *p = start as f64 + est.delay_samples - bias;
    }
    Ok(())
}

fn check_coherence(r: usize, start: i64, est: DelayEstimate) -> Result<(), DspError> {
    if est.coherence < MIN_COHERENCE {
        return Err(not_found(format!(
            "repetition {r} near sample {start} matches the excitation with coherence {:.3}, below {MIN_COHERENCE}",
            est.coherence
        )));
    }
    Ok(())
}

fn not_found(reason: String) -> DspError {
    DspError::InvalidParameter { name: "recording", reason }
}

/// Finds one copy of the excitation near a predicted position of a recording.
struct Finder<'a> {
    template: &'a ExcitationTemplate,
    recording: &'a [f64],
    /// Working buffers for one window and its spectrum, reused by every measurement.
    window: Vec<f64>,
    spectrum: Vec<Complex64>,
    /// Samples zeroed at the window's end.
    blank: usize,
}

impl<'a> Finder<'a> {
    fn new(template: &'a ExcitationTemplate, recording: &'a [f64]) -> Self {
        let n = template.period_samples();
        Self {
            template,
            recording,
            window: vec![0.0; n],
            spectrum: vec![Complex64::new(0.0, 0.0); fft::bin_count(n)],
            blank: 0,
        }
    }

    /// Position of copy `r`, starting the search at `predicted` (anywhere within half a period of the truth).
    fn find(&mut self, r: usize, predicted: f64) -> Result<f64, DspError> {
        let mut start = predicted.round() as i64;
        let mut est = self.measure(r, start)?;
        // Re-centre the window until the copy sits within a few samples of its start, where a faded excitation is
        // still silent (see `REFINE_STRETCH_SAMPLES`): the circular model is exact only when the window holds the
        // whole copy. Three more passes suffice from any start within half a period.
        for _ in 0..3 {
            if est.delay_samples.abs() <= REFINE_STRETCH_SAMPLES {
                break;
            }
            start += est.delay_samples.round() as i64;
            est = self.measure(r, start)?;
        }
        check_coherence(r, start, est)?;
        Ok(start as f64 + est.delay_samples)
    }

    /// Delay of copy `r` relative to a window starting at `start`.
    fn measure(&mut self, r: usize, start: i64) -> Result<DelayEstimate, DspError> {
        let n = self.window.len();
        if start <= -(n as i64) || start >= self.recording.len() as i64 {
            return Err(not_found(format!("repetition {r} would start at sample {start}, outside the recording")));
        }
        // A window inside the recording and without blanking goes to the FFT as it is, without a copy.
        let inside = usize::try_from(start).ok().and_then(|s| self.recording.get(s..s + n));
        match inside {
            Some(slice) if self.blank == 0 => fft::forward_into(slice, n, &mut self.spectrum)?,
            _ => {
                fill_window(self.recording, start, &mut self.window);
                self.window[n - self.blank..].fill(0.0);
                fft::forward_into(&self.window, n, &mut self.spectrum)?
            }
        };
        self.template
            .delay_of(&self.spectrum)
            .map_err(|_| not_found(format!("holds nothing of the excitation where repetition {r} should be")))
    }
}

/// Copies `recording[start .. start + window.len()]` into `window`, with zeros where that range leaves the recording.
fn fill_window(recording: &[f64], start: i64, window: &mut [f64]) {
    window.fill(0.0);
    let len = window.len() as i64;
    // Overlap of [start, start + len) with the recording, in window and recording indices.
    let from = start.max(0);
    let to = (start + len).min(recording.len() as i64);
    if from < to {
        let (a, b) = ((from - start) as usize, (to - start) as usize);
        window[a..b].copy_from_slice(&recording[from as usize..to as usize]);
    }
}

/// Least-squares line `p = a + b r` through `(r, positions[r])`; `(a, b)`. Needs two or more positions.
fn fit_line(positions: &[f64]) -> (f64, f64) {
    let k = positions.len() as f64;
    let r_mean = (k - 1.0) / 2.0;
    let p_mean = positions.iter().sum::<f64>() / k;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (r, p) in positions.iter().enumerate() {
        let dr = r as f64 - r_mean;
        sxy += dr * (p - p_mean);
        sxx += dr * dr;
    }
    let b = sxy / sxx;
    (p_mean - b * r_mean, b)
}

/// The player-to-recorder clock mapping fitted by [`fit_clock`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockFit {
    /// Recorder position of the player's first sample (of the first repetition), samples.
    pub latency_samples: f64,
    /// Recorder clock relative to player clock minus one, ppm: positive when the recorder runs fast, so that a
    /// repetition spans more recorder samples than it has.
    pub drift_ppm: f64,
    /// Rms distance of the positions from the fitted line, samples.
    pub residual_rms_samples: f64,
}

impl ClockFit {
    /// Recorder samples per player sample: `1 + drift_ppm * 1e-6`.
    pub fn ratio(&self) -> f64 {
        1.0 + self.drift_ppm * 1e-6
    }

    /// Recorder position, samples, of player sample `player_samples` (fractional allowed).
    pub fn recorder_position(&self, player_samples: f64) -> f64 {
        self.latency_samples + player_samples * self.ratio()
    }
}

/// Least-squares line through the positions of back-to-back repetitions of a `period_samples`-long excitation:
/// position `r` is modelled as `latency + r * period_samples * (1 + drift_ppm * 1e-6)`.
///
/// Valid range: at least 2 finite positions (one gives no slope); `period_samples >= 1`; the fitted drift within
/// `MAX_DRIFT_PPM` (plus [`DRIFT_SLACK_PPM`] for estimation noise); positions within [`MAX_FIT_RESIDUAL_SAMPLES`]
/// rms of the line.
///
/// # Errors
/// [`DspError::InvalidParameter`] for fewer than 2 positions, a zero period, a drift out of range, or positions off
/// their line; [`DspError::NonFinite`] for a non-finite position.
pub fn fit_clock(positions: &[f64], period_samples: usize) -> Result<ClockFit, DspError> {
    check_finite("positions", positions)?;
    if positions.len() < 2 {
        return Err(DspError::InvalidParameter {
            name: "positions",
            reason: format!("need at least 2 to fit a drift, got {}", positions.len()),
        });
    }
    if period_samples == 0 {
        return Err(DspError::InvalidParameter { name: "period_samples", reason: "must be at least 1".into() });
    }
    let (a, b) = fit_line(positions);
    let drift_ppm = (b / period_samples as f64 - 1.0) * 1e6;
    if drift_ppm.is_nan() || drift_ppm.abs() > MAX_DRIFT_PPM + DRIFT_SLACK_PPM {
        return Err(DspError::InvalidParameter {
            name: "positions",
            reason: format!("imply a drift of {drift_ppm:.1} ppm, beyond the {MAX_DRIFT_PPM} ppm accepted"),
        });
    }
    let sq: f64 = positions.iter().enumerate().map(|(r, p)| (p - a - b * r as f64).powi(2)).sum();
    let residual_rms_samples = (sq / positions.len() as f64).sqrt();
    if residual_rms_samples > MAX_FIT_RESIDUAL_SAMPLES {
        return Err(DspError::InvalidParameter {
            name: "positions",
            reason: format!(
                "lie {residual_rms_samples:.2} samples rms off a straight line (more than \
                 {MAX_FIT_RESIDUAL_SAMPLES}): a dropout or glitch moved a repetition"
            ),
        });
    }
    Ok(ClockFit { latency_samples: a, drift_ppm, residual_rms_samples })
}

#[cfg(test)]
mod tests {
    use metaplate_core::rng::SplitMix64;

    use super::*;
    use crate::sweep::{SweepKind, SweepSpec};

    const FS: f64 = 24_000.0;

    /// A 0.2 s linear sweep 200 Hz..3 kHz with 5 ms fades: 4800 samples.
    fn sweep() -> Vec<f64> {
        let spec =
            SweepSpec { kind: SweepKind::Linear, f1_hz: 200.0, f2_hz: 3000.0, duration_s: 0.2, ..SweepSpec::default() };
        spec.generate().unwrap()
    }

    fn band() -> BandLimit {
        BandLimit::new(300.0, 2500.0, 50.0, 200.0).unwrap()
    }

    #[test]
    fn circular_delay_is_exact_on_periodic_band_limited_signals() {
        // Three sinusoids on FFT bins of a 64-sample period: periodic and band-limited, so a circular delay is an
        // exact time shift; f64 FFT rounding stays below 1e-12.
        let n = 64;
        let bins = [(3.0, 1.0, 0.2), (10.0, 0.5, 1.0), (25.0, 0.25, -0.7)];
        let signal =
            |t: f64| -> f64 { bins.iter().map(|&(k, a, p)| a * (2.0 * PI * k * t / n as f64 + p).sin()).sum() };
        let x: Vec<f64> = (0..n).map(|i| signal(i as f64)).collect();
        for delay in [0.0, 2.3, -7.75, 64.0, 1e9 + 0.5] {
            let y = delay_circular(&x, delay).unwrap();
            for (i, v) in y.iter().enumerate() {
                let expected = signal(i as f64 - delay.rem_euclid(n as f64));
                assert!((v - expected).abs() < 1e-9, "delay {delay} at {i}: {v} vs {expected}");
            }
        }
        assert!(matches!(delay_circular(&[], 1.0), Err(DspError::Empty { .. })));
        assert!(matches!(delay_circular(&[1.0], f64::INFINITY), Err(DspError::InvalidParameter { .. })));
        // Length one: a constant, unchanged by any delay.
        assert_eq!(delay_circular(&[2.0], 0.3).unwrap(), vec![2.0]);
    }

    #[test]
    fn delay_from_spectra_reads_circular_delays_up_to_half_a_period() {
        let e = sweep();
        let n = e.len();
        let template = fft::forward(&e, n).unwrap();
        let gains = band().bin_gains(n, FS);
        // A circularly delayed copy has exactly the template's spectrum times a phase ramp: the estimate is exact to
        // rounding (1e-9 sample), the coherence 1, for delays right up to half the period.
        for delay in [0.0, 0.25, -3.7, 1234.56, -(n as f64) / 2.0 + 0.5, n as f64 / 2.0 - 0.5] {
            let copy = fft::forward(&delay_circular(&e, delay).unwrap(), n).unwrap();
            let est = delay_from_spectra(&copy, &template, n, Some(&gains)).unwrap();
            assert!((est.delay_samples - delay).abs() < 1e-6, "{delay}: {}", est.delay_samples);
            assert!(est.coherence > 0.999_999, "{delay}: coherence {}", est.coherence);
        }
        // Noise has no coherence with the sweep: 1 / sqrt(in-band bins), about 0.05 here; 0.2 is a wide margin.
        let mut rng = SplitMix64::new(1, 0);
        let noise: Vec<f64> = (0..n).map(|_| rng.uniform() * 2.0 - 1.0).collect();
        let est = delay_from_spectra(&fft::forward(&noise, n).unwrap(), &template, n, Some(&gains)).unwrap();
        assert!(est.coherence < 0.2, "noise coherence {}", est.coherence);
        let zero = vec![Complex64::new(0.0, 0.0); template.len()];
        assert!(matches!(delay_from_spectra(&zero, &template, n, None), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(delay_from_spectra(&template[1..], &template, n, None), Err(DspError::LengthMismatch { .. })));
        assert!(matches!(delay_from_spectra(&template, &template, 1, None), Err(DspError::InvalidParameter { .. })));
    }

    /// `repetitions` copies of `e` played back to back, recorded from `latency` with `drift_ppm`, then a tail.
    fn recording(e: &[f64], repetitions: usize, latency: f64, drift_ppm: f64, tail: usize) -> Vec<f64> {
        let played: Vec<f64> = e.iter().copied().cycle().take(e.len() * repetitions).collect();
        let ratio = 1.0 + drift_ppm * 1e-6;
        let len = (latency + played.len() as f64 * ratio).ceil() as usize + tail;
        // Recorder sample m holds player position (m - latency) / ratio: a start of -latency / ratio, a step of
        // 1 / ratio (the library's interpolator here; the round-trip tests use an independent one).
        Interpolator::new(16).unwrap().resample(&played, -latency / ratio, 1.0 / ratio, len).unwrap()
    }

    #[test]
    fn locate_and_fit_recover_latency_and_drift_across_the_valid_range() {
        let e = sweep();
        let n = e.len();
        let b = band();
        // Latency from the recording's first sample to 3 periods in; drift across the accepted range. Clean
        // copies: positions to ~1e-4 sample, so over 3 periods of 4800 samples the drift to ~0.01 ppm; 0.1 ppm and
        // 0.01 sample are margins.
        for latency in [0.0, 0.4, 14_400.3] {
            for drift_ppm in [-MAX_DRIFT_PPM, -37.0, 0.0, 250.0, MAX_DRIFT_PPM] {
                let rec = recording(&e, 4, latency, drift_ppm, 500);
                let positions = locate_repetitions(&rec, &e, 4, Some(&b), FS).unwrap();
                let fit = fit_clock(&positions, n).unwrap();
                let case = format!("latency {latency}, drift {drift_ppm}");
                assert!((fit.drift_ppm - drift_ppm).abs() < 0.1, "{case}: drift {}", fit.drift_ppm);
                assert!((fit.latency_samples - latency).abs() < 0.01, "{case}: latency {}", fit.latency_samples);
                assert!(fit.residual_rms_samples < 0.01, "{case}: residual {}", fit.residual_rms_samples);
                assert!((fit.recorder_position(n as f64) - positions[1]).abs() < 0.01, "{case}");
            }
        }
    }

    #[test]
    fn a_prepared_template_locates_and_measures_as_the_free_functions() {
        let e = sweep();
        let n = e.len();
        let b = band();
        let template = ExcitationTemplate::new(&e, Some(&b), FS).unwrap();
        assert_eq!(template.period_samples(), n);
        assert_eq!(template.spectrum(), fft::forward(&e, n).unwrap().as_slice());
        assert_eq!(template.bin_gains(), Some(b.bin_gains(n, FS).as_slice()));
        // One template for several recordings (different latencies and drifts): the same positions, bit for bit.
        for (latency, drift_ppm) in [(0.0, 0.0), (321.7, -250.0), (14_400.3, MAX_DRIFT_PPM)] {
            let rec = recording(&e, 3, latency, drift_ppm, 500);
            assert_eq!(template.locate(&rec, 3).unwrap(), locate_repetitions(&rec, &e, 3, Some(&b), FS).unwrap());
        }
        // Its delay over the band is `delay_from_spectra`'s, also without a band (all bins).
        let copy = fft::forward(&delay_circular(&e, 37.25).unwrap(), n).unwrap();
        let expected = delay_from_spectra(&copy, template.spectrum(), n, template.bin_gains()).unwrap();
        assert_eq!(template.delay_of(&copy).unwrap(), expected);
        let full = ExcitationTemplate::new(&e, None, FS).unwrap();
        assert_eq!(full.delay_of(&copy).unwrap(), delay_from_spectra(&copy, full.spectrum(), n, None).unwrap());
        assert!(matches!(template.delay_of(&copy[1..]), Err(DspError::LengthMismatch { .. })));
        let mut bad = copy.clone();
        bad[100].re = f64::NAN; // in the band (100 bins of 5 Hz: 500 Hz)
        assert!(matches!(template.delay_of(&bad), Err(DspError::NonFinite { .. })));
        // The valid range of the excitation, band and sample rate.
        assert!(matches!(ExcitationTemplate::new(&[], None, FS), Err(DspError::Empty { .. })));
        assert!(matches!(ExcitationTemplate::new(&[1.0], None, FS), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(ExcitationTemplate::new(&[1.0, f64::NAN], None, FS), Err(DspError::NonFinite { .. })));
        assert!(ExcitationTemplate::new(&[1.0, -1.0], None, FS).is_ok());
        assert!(ExcitationTemplate::new(&e, None, 0.0).is_err());
        let inverted = BandLimit { lo_hz: 2500.0, hi_hz: 300.0, ..b };
        assert!(ExcitationTemplate::new(&e, Some(&inverted), FS).is_err());
    }

    #[test]
    fn locate_refuses_what_holds_no_excitation() {
        let e = sweep();
        assert!(matches!(
            locate_repetitions(&vec![0.0; 20_000], &e, 2, None, FS),
            Err(DspError::InvalidParameter { name: "recording", .. })
        ));
        let mut rng = SplitMix64::new(2, 0);
        let noise: Vec<f64> = (0..20_000).map(|_| rng.uniform() * 2.0 - 1.0).collect();
        assert!(matches!(
            locate_repetitions(&noise, &e, 2, Some(&band()), FS),
            Err(DspError::InvalidParameter { name: "recording", .. })
        ));
        let rec = recording(&e, 2, 100.0, 0.0, 100);
        assert!(matches!(locate_repetitions(&rec, &e, 0, None, FS), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(locate_repetitions(&rec, &[], 1, None, FS), Err(DspError::Empty { .. })));
        assert!(matches!(locate_repetitions(&rec, &e, 1, None, f64::NAN), Err(DspError::InvalidParameter { .. })));
        // Asked for more copies than were played: the last ones are not where the line says.
        assert!(locate_repetitions(&rec, &e, 4, None, FS).is_err());
    }

    #[test]
    fn fit_clock_checks_its_line() {
        let n = 1000;
        let exact: Vec<f64> = (0..5).map(|r| 12.5 + r as f64 * n as f64 * (1.0 + 20e-6)).collect();
        let fit = fit_clock(&exact, n).unwrap();
        assert!((fit.drift_ppm - 20.0).abs() < 1e-6 && (fit.latency_samples - 12.5).abs() < 1e-9);
        assert!((fit.ratio() - 1.000_02).abs() < 1e-12);
        assert!(matches!(fit_clock(&exact[..1], n), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(fit_clock(&exact, 0), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(fit_clock(&[0.0, f64::NAN], n), Err(DspError::NonFinite { .. })));
        // 1500 ppm: beyond the limit and its slack.
        assert!(fit_clock(&[0.0, 1001.5], n).is_err());
        // The limit itself, and just within the slack.
        assert!(fit_clock(&[0.0, 1001.0], n).is_ok() && fit_clock(&[0.0, 999.0005], n).is_ok());
        // One copy 3 samples off the line of the others (a dropout): refused.
        let mut glitch = exact.clone();
        glitch[2] += 3.0;
        assert!(matches!(fit_clock(&glitch, n), Err(DspError::InvalidParameter { .. })));
    }
}

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

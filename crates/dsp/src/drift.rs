//! Clock drift between the player (audio interface) and the recorder (DAQ): where each repetition of an excitation
//! lies in a recording, the straight line through those positions (latency and drift), and the band-limited
//! resampling that puts a recording back on the player's clock.
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
use std::sync::OnceLock;

use num_complex::Complex64;

use crate::band::BandLimit;
use crate::error::{DspError, check_finite, check_result, check_sample_rate, check_signal};
use crate::fft;

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

/// log2 of [`Interpolator::PHASES`].
const PHASE_BITS: u32 = 12;

/// Longest output of [`Interpolator::resample`]: 2^27 samples (about 93 minutes at 24 kHz).
pub const MAX_RESAMPLE_LEN: usize = 1 << 27;

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
    for (input, s) in [("signal spectrum", signal), ("template spectrum", template)] {
        if let Some(index) = s.iter().position(|c| !(c.re.is_finite() && c.im.is_finite())) {
            return Err(DspError::NonFinite { input, index, value: f64::NAN });
        }
    }
    let gain2 = |k: usize| bin_gains.map_or(1.0, |g| g[k] * g[k]);
    let cross = |k: usize| signal[k] * template[k].conj() * gain2(k);
    // Bins strictly between DC and Nyquist (those two are real and carry no phase slope), and within them only the
    // span where the gains are non-zero: a band is often a few percent of the bins.
    let top = (n - 1) / 2;
    let (first, last) = match bin_gains {
        _ if top == 0 => (1, 0),
        Some(g) => {
            let inner = &g[1..=top];
            match (inner.iter().position(|&v| v > 0.0), inner.iter().rposition(|&v| v > 0.0)) {
                (Some(a), Some(b)) => (a + 1, b + 1),
                _ => (1, 0),
            }
        }
        None => (1, top),
    };
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
/// single copy the drift is unknown and its stretch biases the position by up to `2 |drift| * len` samples. `band` restricts
/// the estimate to where the excitation has its energy (`None`: all bins).
///
/// Valid range: an excitation of at least 2 samples that starts and ends quietly (a faded sweep; an abrupt one
/// biases the first and last positions, which border silence); copies played back to back at the excitation's
/// length; `|drift| <= MAX_DRIFT_PPM`; the first copy starting within the recording, the recording holding all
/// copies. A noisy loopback is fine as long as each copy's coherence stays above [`MIN_COHERENCE`].
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
    check_signal("excitation", excitation)?;
    check_sample_rate(sample_rate_hz)?;
    let n = excitation.len();
    let gains = match band {
        Some(b) => {
            b.validate()?;
            Some(b.bin_gains(n, sample_rate_hz))
        }
        None => None,
    };
    let template = fft::forward(excitation, n)?;
    locate_with_template(recording, excitation, &template, repetitions, gains.as_deref())
}

/// [`locate_repetitions`] with the excitation's spectrum and bin gains already computed (length `excitation.len()`).
pub(crate) fn locate_with_template(
    recording: &[f64],
    excitation: &[f64],
    template: &[Complex64],
    repetitions: usize,
    bin_gains: Option<&[f64]>,
) -> Result<Vec<f64>, DspError> {
    check_signal("recording", recording)?;
    if repetitions == 0 {
        return Err(DspError::InvalidParameter { name: "repetitions", reason: "must be at least 1".into() });
    }
    let n = excitation.len();
    let (Some(rec_onset), Some(exc_onset)) = (onset(recording), onset(excitation)) else {
        return Err(not_found("is silent (or the excitation is): no repetition to locate".into()));
    };
    let mut finder = Finder { recording, template, bin_gains, window: vec![0.0; n], blank: 0 };
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
        refine(&mut finder, excitation, &mut positions)?;
    }
    Ok(positions)
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
fn refine(finder: &mut Finder<'_>, excitation: &[f64], positions: &mut [f64]) -> Result<(), DspError> {
    let n = excitation.len();
    let (_, span) = fit_line(positions);
    let ratio = span / n as f64;
    // Far outside the accepted drift the line is meaningless; `fit_clock` refuses it with a clear message.
    if ratio.is_nan() || (ratio - 1.0).abs() > 2.0 * MAX_DRIFT_PPM * 1e-6 {
        return Ok(());
    }
    finder.blank = if span < n as f64 { ((n as f64 - span).ceil() as usize).min(n / 2) } else { 0 };
    // Only the weighted bins count: the kernel need only be accurate up to the last of them.
    let top_bin = finder.bin_gains.and_then(|g| g.iter().rposition(|&v| v > 0.0)).unwrap_or(n / 2);
    let interpolator = Interpolator::for_band(top_bin as f64 / n as f64, 1.0);
    let mut stretched = interpolator.resample(excitation, 0.0, 1.0 / ratio, n)?;
    stretched[n - finder.blank..].fill(0.0);
    let bias = delay_from_spectra(&fft::forward(&stretched, n)?, finder.template, n, finder.bin_gains)?.delay_samples;
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
    recording: &'a [f64],
    template: &'a [Complex64],
    bin_gains: Option<&'a [f64]>,
    window: Vec<f64>,
    /// Samples zeroed at the window's end.
    blank: usize,
}

impl Finder<'_> {
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
        let spectrum = match inside {
            Some(slice) if self.blank == 0 => fft::forward(slice, n)?,
            _ => {
                fill_window(self.recording, start, &mut self.window);
                self.window[n - self.blank..].fill(0.0);
                fft::forward(&self.window, n)?
            }
        };
        delay_from_spectra(&spectrum, self.template, n, self.bin_gains)
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
/// `MAX_DRIFT_PPM` (plus [`DRIFT_SLACK_PPM`] for estimation noise); positions within [`MAX_FIT_RESIDUAL_SAMPLES`] rms of the line.
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

/// Band-limited interpolation by a Kaiser-windowed sinc, tabulated at [`Interpolator::PHASES`] fractional positions.
///
/// Accuracy on a full-scale sinusoid (worst error over fractional positions, measured in the tests), including the
/// table's rounding of the position to 1 / 8192 sample (a phase error of `2 pi f / 8192`, 1e-5 at 0.01 fs):
/// half-width 4: 2e-4 up to 0.1 fs; half-width 8: 3e-4 up to 0.3 fs; half-width 16: 4e-4 up to 0.4 fs. Above that
/// the kernel attenuates towards Nyquist. [`Interpolator::for_band`] picks the shortest that suits a band.
#[derive(Debug, Clone, PartialEq)]
pub struct Interpolator {
    half_width: usize,
    /// Row `p` holds the `2 * half_width` taps for fractional position `p / PHASES`, normalised to unit sum.
    table: Vec<f64>,
}

impl Interpolator {
    /// Fractional positions tabulated per sample.
    pub const PHASES: usize = 1 << PHASE_BITS;
    /// Largest half-width accepted, samples.
    pub const MAX_HALF_WIDTH: usize = 64;
    /// Kaiser window shape: beta 9 puts the window's sidelobes near -90 dB.
    const KAISER_BETA: f64 = 9.0;

    /// Builds the table for a kernel reaching `half_width` samples either side.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] unless `1 <= half_width <= MAX_HALF_WIDTH`.
    pub fn new(half_width: usize) -> Result<Self, DspError> {
        if !(1..=Self::MAX_HALF_WIDTH).contains(&half_width) {
            return Err(DspError::InvalidParameter {
                name: "half_width",
                reason: format!("must lie in 1..={}, got {half_width}", Self::MAX_HALF_WIDTH),
            });
        }
        let taps = 2 * half_width;
        let h = half_width as f64;
        let i0_beta = bessel_i0(Self::KAISER_BETA);
        let mut table = Vec::with_capacity((Self::PHASES + 1) * taps);
        for p in 0..=Self::PHASES {
            let mu = p as f64 / Self::PHASES as f64;
            let row: Vec<f64> = (0..taps)
                .map(|i| {
                    let t = mu + h - 1.0 - i as f64;
                    let u = t / h;
                    let window =
                        if u.abs() < 1.0 { bessel_i0(Self::KAISER_BETA * (1.0 - u * u).sqrt()) / i0_beta } else { 0.0 };
                    sinc(t) * window
                })
                .collect();
            let sum: f64 = row.iter().sum();
            table.extend(row.iter().map(|v| v / sum));
        }
        Ok(Self { half_width, table })
    }

    /// The shortest shared interpolator (half-width 4, 8 or 16, each built once per process) accurate for content
    /// up to `max_freq_hz` at `sample_rate_hz` (see the accuracy table on the type); above 0.4 of the sample rate,
    /// the longest.
    pub fn for_band(max_freq_hz: f64, sample_rate_hz: f64) -> &'static Self {
        static SHORT: OnceLock<Interpolator> = OnceLock::new();
        static MEDIUM: OnceLock<Interpolator> = OnceLock::new();
        static LONG: OnceLock<Interpolator> = OnceLock::new();
        let rel = max_freq_hz / sample_rate_hz;
        let (cell, half_width) = if rel <= 0.1 {
            (&SHORT, 4)
        } else if rel <= 0.3 {
            (&MEDIUM, 8)
        } else {
            (&LONG, 16)
        };
        cell.get_or_init(|| Self::build(half_width))
    }

    fn build(half_width: usize) -> Self {
        match Self::new(half_width) {
            Ok(i) => i,
            // Called with 4, 8 or 16 only, so `new` cannot fail; nearest-sample interpolation (one tap at unit
            // gain) is only a formal fallback.
            Err(_) => Self { half_width: 1, table: [1.0, 0.0].repeat(Self::PHASES + 1) },
        }
    }

    /// Kernel half-width, samples.
    pub fn half_width(&self) -> usize {
        self.half_width
    }

    /// Samples `x` at positions `start_samples + j * step_samples` for `j` in `0..out_len`, treating `x` as zero
    /// outside its samples.
    ///
    /// Valid range: finite `x`; finite `start_samples` within `±MAX_RESAMPLE_LEN`; `0.5 <= step_samples <= 2`;
    /// `out_len <= MAX_RESAMPLE_LEN`. A step above 1 lowers the rate: content above `0.5 / step_samples` of the
    /// input rate then aliases, so the input must not have any (true of drift correction, where the step is within
    /// 1e-3 of 1 and the content far below Nyquist).
    ///
    /// # Errors
    /// [`DspError::NonFinite`] in `x`; [`DspError::InvalidParameter`] for a start or step out of range;
    /// [`DspError::TooLong`] for `out_len`.
    pub fn resample(
        &self,
        x: &[f64],
        start_samples: f64,
        step_samples: f64,
        out_len: usize,
    ) -> Result<Vec<f64>, DspError> {
        check_finite("signal to resample", x)?;
        let limit = MAX_RESAMPLE_LEN as f64;
        if !(start_samples.is_finite() && start_samples.abs() <= limit) {
            return Err(DspError::InvalidParameter {
                name: "start_samples",
                reason: format!("must be finite and within ±{limit}, got {start_samples}"),
            });
        }
        if !(0.5..=2.0).contains(&step_samples) {
            return Err(DspError::InvalidParameter {
                name: "step_samples",
                reason: format!("must lie in [0.5, 2], got {step_samples}"),
            });
        }
        if out_len > MAX_RESAMPLE_LEN {
            return Err(DspError::TooLong { what: "resampled signal", len: out_len, max: MAX_RESAMPLE_LEN });
        }
        let mut out = vec![0.0; out_len];
        // Fixed tap counts let the compiler unroll the inner product: three times faster than the generic loop.
        match self.half_width {
            4 => self.fill::<8>(x, start_samples, step_samples, &mut out),
            8 => self.fill::<16>(x, start_samples, step_samples, &mut out),
            16 => self.fill::<32>(x, start_samples, step_samples, &mut out),
            _ => self.fill_any(x, start_samples, step_samples, &mut out),
        }
        check_result("resampled signal", &out)?;
        Ok(out)
    }

    /// Kernel row and first input index for output position `t`.
    fn locate(&self, t: f64) -> (usize, i64) {
        // floor and round by integer conversion: the f64 methods are library calls on baseline x86-64.
        let mut base = t as i64;
        if (base as f64) > t {
            base -= 1;
        }
        let phase = ((t - base as f64) * Self::PHASES as f64 + 0.5) as usize;
        (phase, base - self.half_width as i64 + 1)
    }

    fn fill<const TAPS: usize>(&self, x: &[f64], start: f64, step: f64, out: &mut [f64]) {
        let (rows, _) = self.table.as_chunks::<TAPS>();
        // Positions in fixed point, re-anchored to the exact `start + j * step` every block so that the rounding
        // of the step (2^-32 sample) cannot accumulate: integer steps replace two float-to-integer conversions per
        // output, the costliest part of the loop after the taps.
        const FRAC_BITS: u32 = 32;
        const BLOCK: usize = 4096;
        let scale = (1u64 << FRAC_BITS) as f64;
        let step_fixed = (step * scale).round() as i64;
        let half_phase = 1i64 << (FRAC_BITS - PHASE_BITS - 1);
        for (b, block) in out.chunks_mut(BLOCK).enumerate() {
            let mut pos = ((start + (b * BLOCK) as f64 * step) * scale).round() as i64;
            for y in block.iter_mut() {
                // Position rounded to the table's resolution, then split into sample and phase.
                let rounded = (pos + half_phase) >> (FRAC_BITS - PHASE_BITS);
                let phase = (rounded & (Self::PHASES as i64 - 1)) as usize;
                let first = (rounded >> PHASE_BITS) - self.half_width as i64 + 1;
                let window = usize::try_from(first).ok().and_then(|f| x.get(f..)).and_then(|s| s.first_chunk::<TAPS>());
                *y = match (rows.get(phase), window) {
                    (Some(row), Some(input)) => dot_fixed(row, input),
                    _ => self.edge_sample(x, phase, first),
                };
                pos += step_fixed;
            }
        }
    }

    fn fill_any(&self, x: &[f64], start: f64, step: f64, out: &mut [f64]) {
        let taps = 2 * self.half_width;
        for (j, y) in out.iter_mut().enumerate() {
            let (phase, first) = self.locate(start + j as f64 * step);
            let row = &self.table[phase * taps..(phase + 1) * taps];
            *y = match usize::try_from(first).ok().and_then(|f| x.get(f..f + taps)) {
                Some(input) => row.iter().zip(input).map(|(w, v)| w * v).sum(),
                None => self.edge_sample(x, phase, first),
            };
        }
    }

    /// One output whose kernel overlaps the ends of `x` (zero beyond them).
    fn edge_sample(&self, x: &[f64], phase: usize, first: i64) -> f64 {
        let taps = 2 * self.half_width;
        let row = &self.table[phase * taps..(phase + 1) * taps];
        row.iter()
            .enumerate()
            .map(|(i, w)| {
                let idx = first + i as i64;
                if idx >= 0 && (idx as usize) < x.len() { w * x[idx as usize] } else { 0.0 }
            })
            .sum()
    }
}

/// Inner product of fixed length with four partial sums, which the compiler keeps in vector registers.
fn dot_fixed<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0; 4];
    for i in 0..N {
        acc[i % 4] += a[i] * b[i];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

fn sinc(t: f64) -> f64 {
    if t == 0.0 { 1.0 } else { (PI * t).sin() / (PI * t) }
}

/// Modified Bessel function of the first kind, order 0, by its power series (converges for all real x; the
/// arguments here are at most 9, where 40 terms reach full f64 precision).
fn bessel_i0(x: f64) -> f64 {
    let q = x * x / 4.0;
    let mut term = 1.0;
    let mut sum = 1.0;
    for k in 1..60 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < sum * 1e-17 {
            break;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

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

    /// Worst error of `interp` on a unit sinusoid at `f` cycles per sample, over positions stepping by `step`.
    fn worst_error(interp: &Interpolator, f: f64, step: f64) -> f64 {
        let w = 2.0 * PI * f;
        let x: Vec<f64> = (0..1000).map(|i| (w * i as f64 + 0.3).sin()).collect();
        let start = 100.0 + 1.0 / 3.0;
        let y = interp.resample(&x, start, step, 300).unwrap();
        y.iter().enumerate().map(|(j, v)| (v - (w * (start + j as f64 * step) + 0.3).sin()).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn interpolators_meet_their_documented_accuracy() {
        // The bounds stated on `Interpolator`; a step just off 1 walks through all fractional positions.
        let step = 1.0 + 1.0 / 997.0;
        for (hw, f, bound) in [(4, 0.01, 2e-4), (4, 0.1, 2e-4), (8, 0.3, 3e-4), (16, 0.4, 4e-4)] {
            let err = worst_error(&Interpolator::new(hw).unwrap(), f, step);
            assert!(err < bound, "half-width {hw} at {f} fs: {err:e}");
        }
        // The step's extremes, on content that survives the halved rate (0.05 fs < 0.25 fs).
        for step in [0.5, 2.0] {
            let err = worst_error(&Interpolator::new(8).unwrap(), 0.05, step);
            assert!(err < 3e-4, "step {step}: {err:e}");
        }
        assert_eq!(Interpolator::for_band(675.0, FS).half_width(), 4);
        assert_eq!(Interpolator::for_band(5000.0, FS).half_width(), 8);
        assert_eq!(Interpolator::for_band(12_000.0, FS).half_width(), 16);
    }

    #[test]
    fn integer_positions_copy_and_outside_is_zero() {
        let x: Vec<f64> = (0..50).map(|i| (i as f64 * 0.37).cos()).collect();
        let y = Interpolator::new(8).unwrap().resample(&x, -10.0, 1.0, 70).unwrap();
        // The kernel at an integer position is one tap of 1 and zeros of sinc(k) = sin(pi k) / (pi k), 1e-17.
        for (j, v) in y.iter().enumerate() {
            let expected = if (10..60).contains(&j) { x[j - 10] } else { 0.0 };
            assert!((v - expected).abs() < 1e-12, "{j}: {v} vs {expected}");
        }
    }

    #[test]
    fn resample_refuses_bad_parameters() {
        let i = Interpolator::new(4).unwrap();
        assert!(matches!(i.resample(&[1.0, f64::NAN], 0.0, 1.0, 2), Err(DspError::NonFinite { .. })));
        assert!(matches!(i.resample(&[1.0], f64::NAN, 1.0, 2), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(i.resample(&[1.0], 1e12, 1.0, 2), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(i.resample(&[1.0], 0.0, 0.49, 2), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(i.resample(&[1.0], 0.0, 2.01, 2), Err(DspError::InvalidParameter { .. })));
        assert!(matches!(i.resample(&[1.0], 0.0, 1.0, MAX_RESAMPLE_LEN + 1), Err(DspError::TooLong { .. })));
        assert!(i.resample(&[], 0.0, 1.0, 3).unwrap().iter().all(|v| *v == 0.0));
        assert!(Interpolator::new(0).is_err());
        assert!(Interpolator::new(Interpolator::MAX_HALF_WIDTH + 1).is_err());
        // Odd half-widths take the generic path and agree with the specialised ones in accuracy.
        assert!(worst_error(&Interpolator::new(5).unwrap(), 0.05, 1.001) < 2e-4);
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
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let noise: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
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
    fn locate_refuses_what_holds_no_excitation() {
        let e = sweep();
        assert!(matches!(
            locate_repetitions(&vec![0.0; 20_000], &e, 2, None, FS),
            Err(DspError::InvalidParameter { name: "recording", .. })
        ));
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let noise: Vec<f64> = (0..20_000).map(|_| rng.random_range(-1.0..1.0)).collect();
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

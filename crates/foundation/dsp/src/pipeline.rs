//! What a recipe runs per actuator per grid point: one DAQ acquisition (velocity and loopback) of a repeated
//! excitation in, one impulse response with its SNR, clock drift and latency out.
//!
//! Steps:
//! 1. Locate every repetition in the loopback and fit the player-to-recorder clock line ([`crate::drift`]).
//! 2. Resample both channels onto the player's clock with one band-limited interpolator (the same positions for
//!    both, so whatever the interpolator does to one it does to the other, and the reference division cancels it).
//!    Resampling, rather than shifting each period by its own sub-sample offset, also undoes the stretch *within* a
//!    period: at 50 ppm one 3 s period at 24 kHz spans 3.6 more recorder samples than it has, which would misalign
//!    the wrap-around of the response tail at the period boundary by 3.6 samples, 34 degrees at 625 Hz.
//! 3. Cut periods: because the excitation repeats back to back, every period after the first is a steady-state
//!    circular convolution, and the first period plus the tail after the last one make one more. Periods start a
//!    few samples before each repetition (a guard), which keeps that sum exact.
//! 4. Average the velocity periods coherently, weighting the first-plus-tail one by its larger noise; deconvolve the
//!    mean velocity spectrum by the spectrum of a steady-state loopback period (reference mode: latency and any
//!    residual offset cancel). The spread of the velocity spectra gives the SNR ([`crate::average`]).
//!
//! With a single repetition there is nothing to average and the drift is not observable; the channel is then
//! deconvolved linearly by the loopback (reference mode), which needs no drift correction.

use num_complex::Complex64;

use crate::accuracy::ERROR_BAND_HZ;
use crate::average::average_spectra;
use crate::deconv::{DeconvConfig, deconvolve_with_reference, divide_spectra, division_gains};
use crate::drift::{ExcitationTemplate, MAX_DRIFT_PPM, fit_clock};
use crate::error::{DspError, check_result, check_signal};
use crate::fft;
use crate::resample::Interpolator;

/// Samples by which every period starts before its repetition, plus `|drift| * period`. A period that starts a
/// little early stays exact (see step 3); one that starts late would lose the copy's first samples. The positions
/// are good to 0.01 sample on a clean loopback, so this is a wide margin; it also leaves room after the impulse
/// response for its conversion to the recorder's clock (`|drift| * ir_len` plus the interpolator's reach, 8).
pub const GUARD_SAMPLES: usize = 16;

/// A repeated excitation as played: `repetitions` copies of `excitation` back to back, then silence.
///
/// Valid range: a finite excitation of at least 2 samples that starts and ends quietly (a faded sweep) with energy
/// in the deconvolution band; `repetitions >= 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct RepetitionLayout {
    /// One period of the played signal, player samples (full scale 1.0).
    pub excitation: Vec<f64>,
    /// How many copies were played back to back.
    pub repetitions: usize,
}

impl RepetitionLayout {
    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`DspError::Empty`] or [`DspError::NonFinite`] for the excitation; [`DspError::InvalidParameter`] for an
    /// excitation of one sample or zero repetitions.
    pub fn validate(&self) -> Result<(), DspError> {
        check_signal("excitation", &self.excitation)?;
        if self.excitation.len() < 2 {
            return Err(DspError::InvalidParameter { name: "excitation", reason: "needs at least 2 samples".into() });
        }
        if self.repetitions == 0 {
            return Err(DspError::InvalidParameter { name: "repetitions", reason: "must be at least 1".into() });
        }
        Ok(())
    }

    /// Recorder samples an acquisition needs at zero latency and drift: the repetitions, then a tail of `ir_len`
    /// samples for the last response to ring out, plus the guard. Add the latency, and `|drift| * repetitions *
    /// period` for the worst drift expected.
    pub fn min_recording_samples(&self, ir_len: usize) -> usize {
        self.repetitions * self.excitation.len() + ir_len + 2 * GUARD_SAMPLES
    }
}

/// The outcome for one channel (one actuator at one point).
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelResult {
    /// Impulse response from the loopback (the played signal) to the velocity, `cfg.ir_len` samples at
    /// `cfg.sample_rate_hz`, time 0 at the loopback's timing; velocity units per loopback unit.
    pub ir: Vec<f64>,
    /// In-band SNR of the averaged velocity, dB (signal energy over noise energy left after averaging, counted with
    /// the band gains squared), estimated from the spread of the repetitions. `None` with one repetition, or when
    /// the spread cannot resolve it (see [`crate::average::Average::snr_db`]).
    pub snr_db: Option<f64>,
    /// Clock drift measured and corrected, ppm (recorder relative to player). 0 with one repetition: not
    /// observable, and not needed by the linear reference deconvolution used then.
    pub drift_ppm: f64,
    /// Recorder position of the playback's first sample, samples from the start of the recording. With one
    /// repetition the unknown drift's stretch biases it by up to `2 |drift| * period`.
    pub latency_samples: f64,
    /// Expected energy of the noise left in `ir` within [`ERROR_BAND_HZ`] (the sum of its squares over the
    /// `ir_len` samples, in `ir`'s units squared), from the spread of the repetitions: each bin's variance of the
    /// mean through the division, summed over the band and spread evenly over the period, of which the response
    /// keeps `ir_len` samples. `None` with one repetition, like `snr_db`.
    pub noise_energy: Option<f64>,
}

impl ChannelResult {
    /// The error this response probably has against the truth over [`ERROR_BAND_HZ`], dB, from its noise
    /// ([`crate::accuracy::estimated_error_db`]; what every repetition shares does not show); `None` without a
    /// noise estimate or when the response has no energy in the band.
    pub fn estimated_error_db(&self, sample_rate_hz: f64) -> Option<f64> {
        let noise = self.noise_energy?;
        crate::accuracy::estimated_error_db(&self.ir, noise, sample_rate_hz).ok()
    }
}

/// Turns one acquisition of a repeated excitation into an impulse response (see the module documentation).
///
/// Valid range: `velocity` and `loopback` finite, of equal length, holding the latency, all repetitions and a tail of
/// at least `cfg.ir_len` samples (see [`RepetitionLayout::min_recording_samples`]); the latency `>= 0` (the
/// recording started before the playback); `|drift| <= MAX_DRIFT_PPM`; `cfg` valid with `cfg.ir_len` plus the guard
/// (16 samples plus `|drift| * period`) within one period, for two repetitions or more.
///
/// This prepares the layout for one channel; channels that share a layout and configuration (the actuators of a
/// grid point, and every point) save that work with [`PreparedLayout`].
///
/// # Errors
/// Input errors as named ([`DspError::Empty`], [`DspError::NonFinite`], [`DspError::LengthMismatch`]);
/// [`DspError::InvalidParameter`] naming `recording` when a repetition is not found in the loopback or the
/// recording is too short, `positions` when the drift is out of range or the repetitions do not lie on a line,
/// `ir_len` when it does not fit a period; deconvolution errors as in [`crate::deconv`].
pub fn process_channel(
    velocity: &[f64],
    loopback: &[f64],
    layout: &RepetitionLayout,
    cfg: &DeconvConfig,
) -> Result<ChannelResult, DspError> {
    PreparedLayout::new(layout, cfg)?.process_channel(velocity, loopback)
}

/// A repetition layout and deconvolution configuration checked and prepared once for every channel that shares
/// them: the excitation's spectrum, band gains and onset ([`ExcitationTemplate`]) and the resampling kernel.
/// Immutable once built, so one can serve channels processed on several threads at once.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedLayout {
    layout: RepetitionLayout,
    cfg: DeconvConfig,
    template: ExcitationTemplate,
    interpolator: &'static Interpolator,
}

impl PreparedLayout {
    /// Checks `layout` and `cfg` and prepares them.
    ///
    /// # Errors
    /// As [`RepetitionLayout::validate`] and [`DeconvConfig::validate`].
    pub fn new(layout: &RepetitionLayout, cfg: &DeconvConfig) -> Result<Self, DspError> {
        cfg.validate()?;
        layout.validate()?;
        let template = ExcitationTemplate::new(&layout.excitation, cfg.band.as_ref(), cfg.sample_rate_hz)?;
        // The shortest kernel accurate over the band and its skirts: beyond them the band limit zeroes the result.
        let top_hz = cfg.band.map_or(cfg.sample_rate_hz / 2.0, |b| b.hi_hz + b.hi_transition_hz);
        let interpolator = Interpolator::for_band(top_hz, cfg.sample_rate_hz);
        Ok(Self { layout: layout.clone(), cfg: *cfg, template, interpolator })
    }

    /// The layout prepared.
    pub fn layout(&self) -> &RepetitionLayout {
        &self.layout
    }

    /// The configuration prepared.
    pub fn config(&self) -> &DeconvConfig {
        &self.cfg
    }

    /// [`process_channel`] with this layout and configuration.
    ///
    /// # Errors
    /// As [`process_channel`].
    pub fn process_channel(&self, velocity: &[f64], loopback: &[f64]) -> Result<ChannelResult, DspError> {
        let positions = self.locate(velocity, loopback)?;
        if self.layout.repetitions == 1 {
            return single_repetition(velocity, loopback, positions[0], self.layout.excitation.len(), &self.cfg);
        }
        let mut results = self.periodic(velocity, &positions, loopback, &[0])?;
        results.pop().ok_or(DspError::Empty { input: "responses" })
    }

    /// One acquisition of several sources each playing the layout's periods circularly shifted by its own number
    /// of samples (`shifts`, each below the period), as [`PreparedLayout::process_channel`] processes one: source
    /// `i`'s response is the period's response from `shifts[i]` on (its precursor from just before), `cfg.ir_len`
    /// samples on the recorder's clock. Every response shares the acquisition's drift, latency and noise (the
    /// period's noise spread evenly, of which each keeps `cfg.ir_len` samples); the SNR is the acquisition's, less
    /// the source's share of the response energy.
    ///
    /// Valid range: as [`PreparedLayout::process_channel`] with two repetitions or more; each response within
    /// its slot up to the next shift (beyond it, it lands in the next source's response).
    ///
    /// # Errors
    /// As [`PreparedLayout::process_channel`]; [`DspError::InvalidParameter`] for fewer than two repetitions, no
    /// shift, or a shift not below the period.
    pub fn process_shifted(
        &self,
        velocity: &[f64],
        loopback: &[f64],
        shifts: &[usize],
    ) -> Result<Vec<ChannelResult>, DspError> {
        let n = self.layout.excitation.len();
        if self.layout.repetitions < 2 || shifts.is_empty() || shifts.iter().any(|&s| s >= n) {
            return Err(DspError::InvalidParameter {
                name: "shifts",
                reason: format!(
                    "{} shifts (each below the period of {n} samples) over {} repetitions (at least 2)",
                    shifts.len(),
                    self.layout.repetitions
                ),
            });
        }
        let positions = self.locate(velocity, loopback)?;
        self.periodic(velocity, &positions, loopback, shifts)
    }

    /// Step 1 for one acquisition: the inputs checked, and the repetitions located in the loopback.
    fn locate(&self, velocity: &[f64], loopback: &[f64]) -> Result<Vec<f64>, DspError> {
        check_signal("velocity", velocity)?;
        check_signal("loopback", loopback)?;
        if velocity.len() != loopback.len() {
            return Err(DspError::LengthMismatch {
                what: "velocity and loopback",
                a: velocity.len(),
                b: loopback.len(),
            });
        }
        self.template.locate_in_checked(loopback, self.layout.repetitions)
    }

    /// Steps 1 to 4 from the repetitions' positions (two or more), one response per circular shift.
    fn periodic(
        &self,
        velocity: &[f64],
        positions: &[f64],
        loopback: &[f64],
        shifts: &[usize],
    ) -> Result<Vec<ChannelResult>, DspError> {
        let (layout, cfg) = (&self.layout, &self.cfg);
        let n = layout.excitation.len();
        let gains = self.template.bin_gains();
        let clock = fit_clock(positions, n)?;
        let ratio = clock.ratio();
        let guard = (clock.drift_ppm.abs() * 1e-6 * n as f64).ceil() as usize + GUARD_SAMPLES;
        let tail_len = guard + cfg.ir_len;
        if tail_len > n {
            return Err(DspError::InvalidParameter {
                name: "ir_len",
                reason: format!("{} samples plus a guard of {guard} exceed the period of {n} samples", cfg.ir_len),
            });
        }
        let out_len = layout.repetitions * n + tail_len;
        let grid_start = clock.latency_samples - guard as f64 * ratio;
        let grid_end = grid_start + (out_len - 1) as f64 * ratio;
        if grid_end > (velocity.len() - 1) as f64 {
            return Err(too_short(velocity.len(), grid_end));
        }
        let interpolator = self.interpolator;
        let periods = Periods { repetitions: layout.repetitions, n, tail_len, grid_start, ratio };
        let velocity_spectra = periods.spectra(interpolator, velocity)?;
        let spectra: Vec<&[Complex64]> = velocity_spectra.chunks_exact(fft::bin_count(n)).collect();
        let velocity_mean = average_spectra(&spectra, &periods.weights(), gains)?;
        // The loopback is the played signal itself, so every steady-state period of it is the same. One period, the
        // second, serves as the reference for all, which saves resampling the rest; its noise (a 16-bit DAQ
        // channel's, some 80 dB below the signal) then enters the IR unaveraged, at that level.
        let mut reference_period = vec![0.0; n];
        interpolator.resample_into(loopback, periods.start(1), ratio, &mut reference_period)?;
        let mut reference = vec![Complex64::new(0.0, 0.0); fft::bin_count(n)];
        fft::forward_destructive(&mut reference_period, &mut reference)?;

        let response = divide_spectra(&velocity_mean.mean, &reference, gains, cfg.regularisation)?;
        let period_ir = fft::inverse(&response, n)?;
        let noise_energy = band_noise_energy(&spectra, &periods.weights(), &reference, gains, cfg, n)?;

        // Refine the latency on the resampled loopback, which no longer has a stretch: its offset from the
        // excitation is where the first repetition starts within the first period.
        let offset = self.template.delay_of(&reference)?;
        let latency_samples = grid_start + offset.delay_samples * ratio;
        check_latency(latency_samples)?;
        let irs = shifts
            .iter()
            .map(|&shift| {
                let mut own = period_ir.clone();
                own.rotate_left(shift);
                to_recorder_clock(&own, ratio, cfg.ir_len, cfg.pre_samples, interpolator)
            })
            .collect::<Result<Vec<_>, _>>()?;
        // Each source's share of the velocity's signal: its response's energy over all of theirs.
        let energies: Vec<f64> = irs.iter().map(|ir| ir.iter().map(|v| v * v).sum()).collect();
        let total: f64 = energies.iter().sum();
        Ok(irs
            .into_iter()
            .zip(energies)
            .map(|(ir, energy)| {
                let share_db = if shifts.len() == 1 { Some(0.0) } else { share_db(energy, total) };
                ChannelResult {
                    ir,
                    snr_db: velocity_mean.snr_db().zip(share_db).map(|(snr, share)| snr + share),
                    drift_ppm: clock.drift_ppm,
                    latency_samples,
                    noise_energy,
                }
            })
            .collect())
    }
}

/// `10 log10(part / total)`, dB; `None` where not finite (no energy).
fn share_db(part: f64, total: f64) -> Option<f64> {
    let db = 10.0 * (part / total).log10();
    db.is_finite().then_some(db)
}

/// The noise energy a response of `cfg.ir_len` samples keeps within [`ERROR_BAND_HZ`] (see
/// [`ChannelResult::noise_energy`]): the spread of the periods' spectra around their mean, per bin, through the
/// division by `reference` ([`division_gains`]), summed over the band's bins. By Parseval with the inverse FFT's
/// `1 / n`, a bin's variance `v` puts `2 v / n^2` into every sample of the period's response (twice: the bin and its
/// mirror), so the kept `ir_len` samples hold `ir_len` times that. `None` for fewer than two periods.
fn band_noise_energy(
    spectra: &[&[Complex64]],
    weights: &[f64],
    reference: &[Complex64],
    band_gains: Option<&[f64]>,
    cfg: &DeconvConfig,
    n: usize,
) -> Result<Option<f64>, DspError> {
    let mut gains = division_gains(reference, band_gains, cfg.regularisation)?;
    for (k, g) in gains.iter_mut().enumerate() {
        let f = fft::bin_freq_hz(k, n, cfg.sample_rate_hz);
        if !(ERROR_BAND_HZ.0..=ERROR_BAND_HZ.1).contains(&f) {
            *g = 0.0;
        }
    }
    let spread = average_spectra(spectra, weights, Some(&gains))?;
    Ok(spread.noise_energy.map(|v| 2.0 * v / (n as f64 * n as f64) * cfg.ir_len as f64))
}

/// The impulse response on the recorder's clock from one period of it on the player's clock (`period_ir`, `n`
/// samples, circular): `h_rec[m] = h_player(m / ratio) / ratio` for `m` from `-pre_samples` on, `ir_len` samples,
/// the scaling that keeps its integral. Without it the response would be stretched by the drift, 0.35 sample at the
/// end of 0.4 s at 37 ppm, -50 dB at 625 Hz. The period is circular, so the band limit's precursor (negative time)
/// lies at its end: a two-sided response (`pre_samples > 0`) takes it from there.
fn to_recorder_clock(
    period_ir: &[f64],
    ratio: f64,
    ir_len: usize,
    pre_samples: usize,
    interpolator: &Interpolator,
) -> Result<Vec<f64>, DspError> {
    let n = period_ir.len();
    let hw = interpolator.half_width().min(n / 2);
    // Player samples before time 0 the first output sample needs: its own time plus the kernel's half-width (for a
    // one-sided response exactly the half-width, so that its positions, and so its bits, are as they always were).
    let before = if pre_samples == 0 { hw } else { ((pre_samples as f64 / ratio).ceil() as usize + hw + 1).min(n / 2) };
    // The last recorder sample reaches player time `(ir_len - pre_samples) / ratio`, plus the half-width.
    let reach = ((ir_len.saturating_sub(pre_samples) as f64 / ratio).ceil() as usize + hw + 1).min(n - before);
    // Circular extension: time 0 needs the end of the period, which precedes it.
    let extended: Vec<f64> = period_ir[n - before..].iter().chain(&period_ir[..reach]).copied().collect();
    let start = before as f64 - pre_samples as f64 / ratio;
    let mut ir = interpolator.resample(&extended, start, 1.0 / ratio, ir_len)?;
    ir.iter_mut().for_each(|v| *v /= ratio);
    check_result("impulse response", &ir)?;
    Ok(ir)
}

/// How the recording splits into periods on the player's clock, and the weight of each in the average.
struct Periods {
    repetitions: usize,
    n: usize,
    tail_len: usize,
    /// Recorder position of the first period's first sample, and recorder samples per player sample.
    grid_start: f64,
    ratio: f64,
}

impl Periods {
    /// Recorder position of period `k`'s first sample (`k == repetitions`: the tail's).
    fn start(&self, k: usize) -> f64 {
        self.grid_start + (k * self.n) as f64 * self.ratio
    }

    /// Inverse relative noise energy: 1 for a steady-state period, `n / (n + tail_len)` for the first one, which
    /// also carries the tail's noise.
    fn weights(&self) -> Vec<f64> {
        let mut weights = vec![1.0; self.repetitions];
        weights[0] = self.n as f64 / (self.n + self.tail_len) as f64;
        weights
    }

    /// Spectra, back to back (`n / 2 + 1` bins each), of the first period plus the tail, then of each steady-state
    /// period, resampled from `recording` one period at a time into a buffer that stays in cache.
    fn spectra(&self, interpolator: &Interpolator, recording: &[f64]) -> Result<Vec<Complex64>, DspError> {
        let (n, bins) = (self.n, fft::bin_count(self.n));
        let mut tail = vec![0.0; self.tail_len];
        interpolator.resample_into(recording, self.start(self.repetitions), self.ratio, &mut tail)?;
        let mut period = vec![0.0; n];
        let mut spectra = vec![Complex64::new(0.0, 0.0); self.repetitions * bins];
        for (k, spectrum) in spectra.chunks_exact_mut(bins).enumerate() {
            interpolator.resample_into(recording, self.start(k), self.ratio, &mut period)?;
            if k == 0 {
                period.iter_mut().zip(&tail).for_each(|(p, t)| *p += t);
            }
            fft::forward_destructive(&mut period, spectrum)?;
        }
        Ok(spectra)
    }
}

/// One repetition: linear reference deconvolution of the stretch of recording that holds the repetition and its
/// tail. The reference division cancels latency and drift, so neither needs correcting.
fn single_repetition(
    velocity: &[f64],
    loopback: &[f64],
    position: f64,
    n: usize,
    cfg: &DeconvConfig,
) -> Result<ChannelResult, DspError> {
    check_latency(position)?;
    let start = (position.floor() as usize).saturating_sub(GUARD_SAMPLES);
    // The repetition and its tail, with a guard either side; more, up to the worst stretch of the accepted drift,
    // when the recording has it (the drift is unknown with one repetition).
    let needed = start + n + cfg.ir_len + 2 * GUARD_SAMPLES;
    if needed > velocity.len() {
        return Err(too_short(velocity.len(), needed as f64));
    }
    let slack = (MAX_DRIFT_PPM * 1e-6 * n as f64).ceil() as usize;
    let end = (needed + slack).min(velocity.len());
    let ir = deconvolve_with_reference(&velocity[start..end], &loopback[start..end], cfg)?;
    Ok(ChannelResult { ir, snr_db: None, drift_ppm: 0.0, latency_samples: position, noise_energy: None })
}

fn check_latency(latency_samples: f64) -> Result<(), DspError> {
    // Half a sample of slack for the estimate's own noise.
    if latency_samples < -0.5 {
        return Err(DspError::InvalidParameter {
            name: "recording",
            reason: format!(
                "starts {:.1} samples after the playback's first sample: the first repetition was cut",
                -latency_samples
            ),
        });
    }
    Ok(())
}

fn too_short(len: usize, needed_end: f64) -> DspError {
    DspError::InvalidParameter {
        name: "recording",
        reason: format!(
            "holds {len} samples but the repetitions and a tail of ir_len reach sample {:.0}: record longer",
            needed_end.ceil()
        ),
    }
}

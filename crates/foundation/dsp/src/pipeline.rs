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
const GUARD_SAMPLES: usize = 16;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::band::BandLimit;
    use crate::conv::convolve;
    use crate::sweep::{SweepKind, SweepSpec};

    const FS: f64 = 24_000.0;

    fn layout(repetitions: usize) -> RepetitionLayout {
        let spec =
            SweepSpec { kind: SweepKind::Linear, f1_hz: 200.0, f2_hz: 3000.0, duration_s: 0.2, ..SweepSpec::default() };
        RepetitionLayout { excitation: spec.generate().unwrap(), repetitions }
    }

    fn cfg() -> DeconvConfig {
        DeconvConfig {
            sample_rate_hz: FS,
            ir_len: 512,
            band: Some(BandLimit::new(300.0, 2500.0, 50.0, 200.0).unwrap()),
            regularisation: 1e-3,
            pre_samples: 0,
        }
    }

    #[test]
    fn the_noise_energy_predicts_the_error_noise_leaves_in_the_response() {
        // A 450 Hz decaying tone through 6 repetitions, white noise on the velocity at three levels; the response
        // from the noisy recording against the one from the clean recording, within the error band (here 300..600
        // Hz: the excitation's band limit starts at 300), against the estimate. Averaged over 8 noise draws in
        // power: one draw's error over the ~7 bins of a 512-sample response in that band scatters by about 1.5 dB,
        // the mean of 8 by about 0.5 dB, so 1 dB is the bar.
        let l = layout(6);
        let ir: Vec<f64> = (0..300)
            .map(|i| (-(i as f64) / 60.0).exp() * (std::f64::consts::TAU * 450.0 * i as f64 / FS).sin())
            .collect();
        let (clean_v, loopback) = acquisition(&l, 1000, 700, &ir);
        let clean = process_channel(&clean_v, &loopback, &l, &cfg()).unwrap();
        // No noise: the spread is rounding alone.
        assert!(clean.estimated_error_db(FS).is_some_and(|db| db < -200.0), "{:?}", clean.estimated_error_db(FS));
        for noise_rms in [1e-4, 1e-3, 1e-2] {
            let (mut measured, mut estimated) = (0.0, 0.0);
            for seed in 0..8u64 {
                let mut rng = metaplate_core::rng::SplitMix64::new(seed, 0);
                let noisy_v: Vec<f64> = clean_v.iter().map(|v| v + noise_rms * rng.normal()).collect();
                let noisy = process_channel(&noisy_v, &loopback, &l, &cfg()).unwrap();
                let diff: Vec<f64> = noisy.ir.iter().zip(&clean.ir).map(|(a, b)| a - b).collect();
                let band = crate::accuracy::ERROR_BAND_HZ;
                measured += crate::accuracy::band_energy(&diff, band, FS).unwrap()
                    / crate::accuracy::band_energy(&clean.ir, band, FS).unwrap();
                estimated += 10f64.powf(noisy.estimated_error_db(FS).unwrap() / 10.0);
            }
            let (measured_db, estimated_db) = (10.0 * (measured / 8.0).log10(), 10.0 * (estimated / 8.0).log10());
            assert!(
                (measured_db - estimated_db).abs() < 1.0,
                "noise {noise_rms}: {measured_db:.2} vs {estimated_db:.2} dB"
            );
        }
        // One repetition: no spread, no estimate.
        let (v1, l1) = acquisition(&layout(1), 1000, 700, &ir);
        assert_eq!(process_channel(&v1, &l1, &layout(1), &cfg()).unwrap().noise_energy, None);
    }

    #[test]
    fn a_two_sided_response_takes_the_precursor_from_the_end_of_the_period() {
        // A pure delay of 3 samples: band-limited, it rings on both sides of sample 3. The two-sided response is
        // the one-sided one shifted by pre_samples, with the precursor in front, and matches the band-limited truth
        // on both sides (the one-sided one misses the precursor).
        let l = layout(3);
        let mut ir = vec![0.0; 4];
        ir[3] = 0.5;
        let (velocity, loopback) = acquisition(&l, 1000, 700, &ir);
        let pre = 64;
        let one = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
        let two = process_channel(&velocity, &loopback, &l, &DeconvConfig { pre_samples: pre, ..cfg() }).unwrap();
        assert_eq!(two.ir.len(), 512);
        for (a, b) in one.ir[..512 - pre].iter().zip(&two.ir[pre..]) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        let precursor: f64 = two.ir[..pre].iter().map(|v| v * v).sum();
        assert!(precursor > 1e-6, "the band limit rings before time 0: {precursor:e}");
        // Against the band-limited truth, both sides of it.
        let err_two = two_sided_in_band_error(&two.ir, &ir, 4800, pre);
        assert!(err_two < BIAS_BOUND, "two-sided in-band error {err_two:e}");
    }

    /// Loopback: the copies from `latency` (whole samples, no drift), then `tail` samples of silence; velocity:
    /// the loopback through `ir`.
    fn acquisition(layout: &RepetitionLayout, latency: usize, tail: usize, ir: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = layout.excitation.len();
        let mut loopback = vec![0.0; latency];
        loopback.extend(layout.excitation.iter().cycle().take(n * layout.repetitions));
        loopback.extend(std::iter::repeat_n(0.0, tail));
        let mut velocity = convolve(&loopback, ir).unwrap();
        velocity.truncate(loopback.len());
        (velocity, loopback)
    }

    /// Relative in-band error energy of `ir` against `truth` band-limited like the pipeline does (the band's gains
    /// on a length-n FFT) and truncated alike: the band limit's skirts ring for ~1 / 50 Hz, as long as the IR.
    fn in_band_error(ir: &[f64], truth: &[f64], n: usize) -> f64 {
        two_sided_in_band_error(ir, truth, n, 0)
    }

    /// As [`in_band_error`] for an `ir` from time `-pre` on: both it and the reference are laid on the length-n
    /// circle with time 0 first and the precursor wrapped to the end.
    fn two_sided_in_band_error(ir: &[f64], truth: &[f64], n: usize, pre: usize) -> f64 {
        let g = cfg().band.unwrap().bin_gains(n, FS);
        let limited: Vec<Complex64> = fft::forward(truth, n).unwrap().iter().zip(&g).map(|(c, g)| c * g).collect();
        let period = fft::inverse(&limited, n).unwrap();
        let on_circle = |x: &[f64]| {
            let mut c = vec![0.0; n];
            c[..x.len() - pre].copy_from_slice(&x[pre..]);
            c[n - pre..].copy_from_slice(&x[..pre]);
            c
        };
        let mut reference_two_sided = period[n - pre..].to_vec();
        reference_two_sided.extend_from_slice(&period[..ir.len() - pre]);
        let reference = on_circle(&reference_two_sided);
        let diff: Vec<f64> = on_circle(ir).iter().zip(&reference).map(|(a, b)| a - b).collect();
        let (e, t) = (fft::forward(&diff, n).unwrap(), fft::forward(&reference, n).unwrap());
        let band = |k: &usize| (300.0..=2500.0).contains(&fft::bin_freq_hz(*k, n, FS));
        let err: f64 = (0..e.len()).filter(band).map(|k| e[k].norm_sqr()).sum();
        err / (0..t.len()).filter(band).map(|k| t[k].norm_sqr()).sum::<f64>()
    }

    /// The regularisation's bias on a flat response, eps / (|D|^2 + eps) with eps = 1e-3 max |D|^2, stays below
    /// 1e-2 where this short sweep's power is above a tenth of its peak, true over 300..2500 Hz (its Fresnel ripple
    /// is a few dB): a relative error energy below 1e-4.
    const BIAS_BOUND: f64 = 1e-4;

    #[test]
    fn a_pure_delay_comes_back_in_band() {
        // IR: 0.5 at 3 samples, back to within the regularisation's bias.
        let l = layout(3);
        let mut ir = vec![0.0; 4];
        ir[3] = 0.5;
        let (velocity, loopback) = acquisition(&l, 1000, 700, &ir);
        let out = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
        assert_eq!(out.ir.len(), 512);
        let err = in_band_error(&out.ir, &ir, 4800);
        assert!(err < BIAS_BOUND, "in-band error {err:e}");
        // No drift, a whole-sample latency: both to rounding of the estimates (1e-3 ppm, 1e-4 sample).
        assert!(out.drift_ppm.abs() < 1e-3, "drift {}", out.drift_ppm);
        assert!((out.latency_samples - 1000.0).abs() < 1e-4, "latency {}", out.latency_samples);
        // Noise-free: the repetitions differ by rounding only, so the SNR is either unresolvable-high or huge.
        assert!(out.snr_db.is_none_or(|s| s > 150.0), "snr {:?}", out.snr_db);
    }

    #[test]
    fn latency_zero_and_a_minimal_tail_work() {
        // Latency 0 (the grid starts before the recording: zeros) and the shortest tail the layout asks for.
        let l = layout(2);
        let c = cfg();
        let (velocity, loopback) = acquisition(&l, 0, c.ir_len + 2 * GUARD_SAMPLES, &[0.0, 1.0]);
        assert_eq!(velocity.len(), l.min_recording_samples(c.ir_len));
        let out = process_channel(&velocity, &loopback, &l, &c).unwrap();
        let err = in_band_error(&out.ir, &[0.0, 1.0], 4800);
        assert!(err < BIAS_BOUND, "in-band error {err:e}");
        assert!(out.latency_samples.abs() < 1e-4, "latency {}", out.latency_samples);
    }

    #[test]
    fn one_repetition_has_no_snr_and_no_drift() {
        let l = layout(1);
        // The shortest recording the layout asks for.
        let (velocity, loopback) = acquisition(&l, 333, cfg().ir_len + 2 * GUARD_SAMPLES, &[0.0, 0.0, 0.25]);
        let out = process_channel(&velocity, &loopback, &l, &cfg()).unwrap();
        assert_eq!(out.snr_db, None);
        assert_eq!(out.drift_ppm, 0.0);
        assert!((out.latency_samples - 333.0).abs() < 1e-3, "latency {}", out.latency_samples);
        // Linear deconvolution, whose band limit acts on a longer FFT: the same bound holds up to the small
        // difference in how the skirts' ringing is truncated.
        let err = in_band_error(&out.ir, &[0.0, 0.0, 0.25], 4800);
        assert!(err < BIAS_BOUND, "in-band error {err:e}");
    }

    #[test]
    fn shifted_sources_each_get_their_own_response_and_bad_shifts_are_refused() {
        // Two sources in one acquisition: the second plays the excitation circularly shifted by half the period
        // (2400 of 4800 samples), so its response lies 2400 samples later in the period. Cut at its shift, each
        // comes back as process_channel returns a source alone; at shift 0 the result is process_channel's, bit
        // for bit.
        let l = layout(3);
        let n = l.excitation.len();
        let (a, b) = (vec![0.0, 0.5, 0.0, -0.25], vec![0.0, 0.0, 0.3]);
        let (va, loopback) = acquisition(&l, 500, 700, &a);
        let mut shifted = l.excitation.clone();
        shifted.rotate_right(n / 2);
        let mut drive = vec![0.0; 500];
        drive.extend(shifted.iter().cycle().take(n * l.repetitions));
        drive.extend(std::iter::repeat_n(0.0, 700));
        let mut vb = convolve(&drive, &b).unwrap();
        vb.truncate(drive.len());
        let velocity: Vec<f64> = va.iter().zip(&vb).map(|(x, y)| x + y).collect();
        let prepared = PreparedLayout::new(&l, &cfg()).unwrap();
        let both = prepared.process_shifted(&velocity, &loopback, &[0, n / 2]).unwrap();
        assert_eq!(both.len(), 2);
        for (got, truth) in both.iter().zip([&a, &b]) {
            let err = in_band_error(&got.ir, truth, 4800);
            assert!(err < BIAS_BOUND, "in-band error {err:e}");
            assert!(got.snr_db.is_none_or(|s| s > 100.0), "noise-free: {:?}", got.snr_db);
        }
        let alone = prepared.process_channel(&va, &loopback).unwrap();
        assert_eq!(prepared.process_shifted(&va, &loopback, &[0]).unwrap(), vec![alone]);
        // No shift, a shift of a whole period or more, one repetition: refused, naming the shifts.
        for shifts in [vec![], vec![0, n]] {
            let err = prepared.process_shifted(&velocity, &loopback, &shifts).unwrap_err();
            assert!(matches!(err, DspError::InvalidParameter { name: "shifts", .. }), "{err}");
        }
        let one = PreparedLayout::new(&layout(1), &cfg()).unwrap();
        let (v1, l1) = acquisition(&layout(1), 100, 700, &a);
        assert!(matches!(one.process_shifted(&v1, &l1, &[0]), Err(DspError::InvalidParameter { name: "shifts", .. })));
    }

    #[test]
    fn a_prepared_layout_gives_what_process_channel_gives() {
        // One preparation for several channels (latencies, responses, repetition counts): bit-identical results.
        for repetitions in [1, 3] {
            let l = layout(repetitions);
            let prepared = PreparedLayout::new(&l, &cfg()).unwrap();
            assert_eq!(prepared.layout(), &l);
            assert_eq!(prepared.config(), &cfg());
            for (latency, ir) in [(0, vec![0.0, 1.0]), (517, vec![0.5, 0.0, -0.25])] {
                let (velocity, loopback) = acquisition(&l, latency, 700, &ir);
                let out = prepared.process_channel(&velocity, &loopback).unwrap();
                assert_eq!(out, process_channel(&velocity, &loopback, &l, &cfg()).unwrap());
            }
        }
        // A bad layout or configuration is refused when preparing, a bad channel when processing.
        let none = RepetitionLayout { repetitions: 0, ..layout(2) };
        assert!(matches!(PreparedLayout::new(&none, &cfg()), Err(DspError::InvalidParameter { .. })));
        let bad_cfg = DeconvConfig { regularisation: -1.0, ..cfg() };
        assert!(matches!(PreparedLayout::new(&layout(2), &bad_cfg), Err(DspError::InvalidParameter { .. })));
        let prepared = PreparedLayout::new(&layout(2), &cfg()).unwrap();
        assert!(matches!(prepared.process_channel(&[1.0; 10], &[1.0; 9]), Err(DspError::LengthMismatch { .. })));
        assert!(matches!(prepared.process_channel(&[], &[]), Err(DspError::Empty { .. })));
    }

    #[test]
    fn refuses_bad_input() {
        let l = layout(2);
        let c = cfg();
        let (velocity, loopback) = acquisition(&l, 100, 700, &[1.0]);
        let run = |v: &[f64], lb: &[f64], lay: &RepetitionLayout, c: &DeconvConfig| process_channel(v, lb, lay, c);
        assert!(matches!(run(&velocity[1..], &loopback, &l, &c), Err(DspError::LengthMismatch { .. })));
        assert!(matches!(run(&[], &[], &l, &c), Err(DspError::Empty { .. })));
        let mut nan = velocity.clone();
        nan[10] = f64::NAN;
        assert!(matches!(run(&nan, &loopback, &l, &c), Err(DspError::NonFinite { .. })));
        let none = RepetitionLayout { repetitions: 0, ..l.clone() };
        assert!(matches!(run(&velocity, &loopback, &none, &c), Err(DspError::InvalidParameter { .. })));
        let tiny = RepetitionLayout { excitation: vec![1.0], repetitions: 2 };
        assert!(matches!(run(&velocity, &loopback, &tiny, &c), Err(DspError::InvalidParameter { .. })));
        // A tail shorter than ir_len: the last response was not recorded.
        let cut = velocity.len() - 400;
        assert!(matches!(
            run(&velocity[..cut], &loopback[..cut], &l, &c),
            Err(DspError::InvalidParameter { name: "recording", .. })
        ));
        // An impulse response as long as the period cannot be told from its wrap-around.
        let long = DeconvConfig { ir_len: 4800, ..c };
        assert!(matches!(run(&velocity, &loopback, &l, &long), Err(DspError::InvalidParameter { name: "ir_len", .. })));
        // The recording started after the playback: the first copy is cut.
        assert!(matches!(
            run(&velocity[150..], &loopback[150..], &l, &c),
            Err(DspError::InvalidParameter { name: "recording", .. })
        ));
        let bad_cfg = DeconvConfig { sample_rate_hz: 0.0, ..c };
        assert!(run(&velocity, &loopback, &l, &bad_cfg).is_err());
    }
}

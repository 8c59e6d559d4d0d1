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

use crate::average::average_spectra;
use crate::deconv::{DeconvConfig, deconvolve_with_reference, divide_spectra};
use crate::drift::{self, Interpolator, MAX_DRIFT_PPM, delay_from_spectra, fit_clock};
use crate::error::{DspError, check_result, check_signal};
use crate::fft;

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
}

/// Turns one acquisition of a repeated excitation into an impulse response (see the module documentation).
///
/// Valid range: `velocity` and `loopback` finite, of equal length, holding the latency, all repetitions and a tail of
/// at least `cfg.ir_len` samples (see [`RepetitionLayout::min_recording_samples`]); the latency `>= 0` (the
/// recording started before the playback); `|drift| <= MAX_DRIFT_PPM`; `cfg` valid with `cfg.ir_len` plus the guard
/// (16 samples plus `|drift| * period`) within one period, for two repetitions or more.
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
    cfg.validate()?;
    layout.validate()?;
    check_signal("velocity", velocity)?;
    check_signal("loopback", loopback)?;
    if velocity.len() != loopback.len() {
        return Err(DspError::LengthMismatch { what: "velocity and loopback", a: velocity.len(), b: loopback.len() });
    }
    let n = layout.excitation.len();
    let gains = cfg.band.map(|b| b.bin_gains(n, cfg.sample_rate_hz));
    let template = fft::forward(&layout.excitation, n)?;
    let positions =
        drift::locate_with_template(loopback, &layout.excitation, &template, layout.repetitions, gains.as_deref())?;
    if layout.repetitions == 1 {
        return single_repetition(velocity, loopback, positions[0], n, cfg);
    }
    let clock = fit_clock(&positions, n)?;
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
    // The shortest kernel accurate over the band and its skirts: beyond them the band limit zeroes the result.
    let top_hz = cfg.band.map_or(cfg.sample_rate_hz / 2.0, |b| b.hi_hz + b.hi_transition_hz);
    let interpolator = Interpolator::for_band(top_hz, cfg.sample_rate_hz);
    let velocity = interpolator.resample(velocity, grid_start, ratio, out_len)?;
    // The loopback is the played signal itself, so every steady-state period of it is the same. One period, the
    // second, serves as the reference for all, which saves resampling the rest; its noise (a 16-bit DAQ channel's,
    // some 80 dB below the signal) then enters the IR unaveraged, at that level.
    let reference = interpolator.resample(loopback, grid_start + n as f64 * ratio, ratio, n)?;
    let periods = Periods::new(layout.repetitions, n, tail_len);

    let velocity_spectra = periods.spectra(&velocity)?;
    let spectra: Vec<&[Complex64]> = velocity_spectra.iter().map(Vec::as_slice).collect();
    let velocity_mean = average_spectra(&spectra, &periods.weights, gains.as_deref())?;
    let reference = fft::forward(&reference, n)?;

    let response = divide_spectra(&velocity_mean.mean, &reference, gains.as_deref(), cfg.regularisation)?;
    let ir = to_recorder_clock(&fft::inverse(&response, n)?, ratio, cfg.ir_len, interpolator)?;

    // Refine the latency on the resampled loopback, which no longer has a stretch: its offset from the excitation
    // is where the first repetition starts within the first period.
    let offset = delay_from_spectra(&reference, &template, n, gains.as_deref())?;
    let latency_samples = grid_start + offset.delay_samples * ratio;
    check_latency(latency_samples)?;
    Ok(ChannelResult { ir, snr_db: velocity_mean.snr_db(), drift_ppm: clock.drift_ppm, latency_samples })
}

/// The impulse response on the recorder's clock from one period of it on the player's clock (`period_ir`, `n`
/// samples, circular): `h_rec[m] = h_player(m / ratio) / ratio`, the scaling that keeps its integral. Without it
/// the response would be stretched by the drift, 0.35 sample at the end of 0.4 s at 37 ppm, -50 dB at 625 Hz.
fn to_recorder_clock(
    period_ir: &[f64],
    ratio: f64,
    ir_len: usize,
    interpolator: &Interpolator,
) -> Result<Vec<f64>, DspError> {
    let n = period_ir.len();
    let hw = interpolator.half_width().min(n / 2);
    // The first `ir_len` recorder samples reach player time `ir_len / ratio`, plus the kernel's half-width.
    let reach = ((ir_len as f64 / ratio).ceil() as usize + hw + 1).min(n - hw);
    // Circular extension: the kernel at time 0 needs the end of the period, which precedes time 0.
    let extended: Vec<f64> = period_ir[n - hw..].iter().chain(&period_ir[..reach]).copied().collect();
    let mut ir = interpolator.resample(&extended, hw as f64, 1.0 / ratio, ir_len)?;
    ir.iter_mut().for_each(|v| *v /= ratio);
    check_result("impulse response", &ir)?;
    Ok(ir)
}

/// How the resampled recording splits into periods, and the weight of each in the average.
struct Periods {
    repetitions: usize,
    n: usize,
    tail_len: usize,
    /// Inverse relative noise energy: 1 for a steady-state period, `n / (n + tail_len)` for the first one, which
    /// also carries the tail's noise.
    weights: Vec<f64>,
}

impl Periods {
    fn new(repetitions: usize, n: usize, tail_len: usize) -> Self {
        let mut weights = vec![1.0; repetitions];
        weights[0] = n as f64 / (n + tail_len) as f64;
        Self { repetitions, n, tail_len, weights }
    }

    /// Spectra of the first period plus the tail, then of each steady-state period; `u` holds
    /// `repetitions * n + tail_len` samples.
    fn spectra(&self, u: &[f64]) -> Result<Vec<Vec<Complex64>>, DspError> {
        let n = self.n;
        let mut first = u[..n].to_vec();
        let tail = &u[self.repetitions * n..self.repetitions * n + self.tail_len];
        first.iter_mut().zip(tail).for_each(|(f, t)| *f += t);
        std::iter::once(fft::forward(&first, n))
            .chain((1..self.repetitions).map(|k| fft::forward(&u[k * n..(k + 1) * n], n)))
            .collect()
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
    Ok(ChannelResult { ir, snr_db: None, drift_ppm: 0.0, latency_samples: position })
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
        let g = cfg().band.unwrap().bin_gains(n, FS);
        let limited: Vec<Complex64> = fft::forward(truth, n).unwrap().iter().zip(&g).map(|(c, g)| c * g).collect();
        let reference = &fft::inverse(&limited, n).unwrap()[..ir.len()];
        let diff: Vec<f64> = ir.iter().zip(reference).map(|(a, b)| a - b).collect();
        let (e, t) = (fft::forward(&diff, n).unwrap(), fft::forward(reference, n).unwrap());
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

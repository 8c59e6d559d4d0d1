//! The scan's acquisition of a point: the beam aimed, then every pending actuator recorded (one at a time, or every
//! shot of a simultaneous protocol, round after round for an adaptive one), each recording through the engine's
//! `acquire` with the scan's retry policy.

use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{Decoder, ExcitationProtocol};

use crate::drive::{AudioPlayback, DrivePlayback};
use crate::engine::acquire::{RetryPolicy, acquire};
use crate::engine::aim::aim;
use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::events::{Observer, RunControl};
use crate::plans::calibrate::Calibration;
use crate::plans::scan::points::{PointBook, Problem};
use crate::plans::scan::processing::{Channel, Gates, Job, Work};
use crate::plans::scan::simultaneous::{Averager, Simultaneous};
use crate::plans::scan::{ScanConfig, ScanPlan};

/// What the scan's acquisition needs, fixed for the run.
pub(crate) struct PointAcquisition<'p> {
    pub plan: &'p ScanPlan,
    pub cfg: &'p ScanConfig,
    /// Each actuator's playback at the audio rate (sequential protocols).
    pub playbacks: &'p [AudioPlayback],
    /// The simultaneous protocol, if the scan plays one.
    pub simultaneous: Option<&'p Simultaneous>,
    /// The protocol's decoder at the DAQ rate (adaptive rounds are decoded here, to decide on the next).
    pub decoder: &'p Decoder,
    pub gates: &'p Gates,
    pub actuators: usize,
    /// Samples per DAQ channel to record per acquisition.
    pub record: usize,
    /// How often an unusable acquisition is repeated.
    pub retry: RetryPolicy,
}

impl PointAcquisition<'_> {
    /// Aims at `point` and records every actuator still to measure there; `None` if abandoned on request.
    pub(crate) fn acquire_point(
        &self,
        book: &mut PointBook,
        instruments: &mut Instruments<'_>,
        point: usize,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Option<Job>, RecipeError> {
        let (visit, pending) = book.visit(point);
        let position = self.plan.grid.position_m(point);
        let aimed = aim(instruments, position, (self.cfg.seed, point as u64, visit), &self.cfg.aim, control, observer)?;
        if let Some(sim) = self.simultaneous {
            let work = match self.acquire_simultaneous(book, instruments, point, &pending, sim, control, observer)? {
                Some(work) => work,
                None => return Ok(None),
            };
            return Ok(Some(Job { point, aimed, work }));
        }
        let mut channels = Vec::with_capacity(pending.len());
        for actuator in pending {
            let buffers = self.playbacks[actuator].buffers();
            let Some(acquired) = acquire(instruments, &buffers, self.record, self.retry, point, control, observer)?
            else {
                return Ok(None);
            };
            book.count_acquisitions(point, actuator, acquired.attempts);
            let problem = acquired.problem.map(Problem::from);
            channels.push(Channel { actuator, acquisition: acquired.acquisition, problem });
        }
        Ok(Some(Job { point, aimed, work: Work::Channels(channels) }))
    }

    /// Plays every shot of a simultaneous protocol at `point` (the beam already there), round after round for an
    /// adaptive one; `None` if abandoned on request.
    #[allow(clippy::too_many_arguments)] // The plan's book, the session, the point and its shots, control, observer.
    fn acquire_simultaneous(
        &self,
        book: &mut PointBook,
        instruments: &mut Instruments<'_>,
        point: usize,
        pending: &[usize],
        sim: &Simultaneous,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Option<Work>, RecipeError> {
        let mut rounds = Averager::new(self.actuators);
        let max_rounds = sim.adaptive.map_or(1, |a| a.max_rounds);
        let mut retries = 0;
        loop {
            let mut acquisitions = Vec::with_capacity(sim.playback.signs.len());
            let mut worst = None;
            for shot in 0..sim.playback.signs.len() {
                let buffers = sim
                    .playback
                    .buffers(shot)
                    .ok_or_else(|| RecipeError::Internal(format!("shot {shot} has no buffers")))?;
                // Each shot is converted with its own scale, so a round may mix velocity ranges after a clip.
                let Some(acquired) = acquire(instruments, &buffers, self.record, self.retry, point, control, observer)?
                else {
                    return Ok(None);
                };
                retries += acquired.attempts - 1;
                worst = worst.or(acquired.problem.map(Problem::from));
                acquisitions.push(acquired.acquisition);
            }
            for &a in pending {
                book.count_acquisitions(point, a, retries + u32::from(rounds.count == 0));
            }
            retries = 0;
            let Some(adaptive) = sim.adaptive else {
                return Ok(Some(Work::Shots { pending: pending.to_vec(), acquisitions, problem: worst }));
            };
            // Adaptive: decode this round now, to decide whether another is needed.
            if worst.is_some() {
                let decoded = Err(Problem::Processing("an acquisition of the round failed".into()));
                return Ok(Some(Work::Done(sim.outcomes(pending, decoded, worst, self.gates))));
            }
            match sim.decode(self.decoder, &acquisitions, self.gates) {
                Ok(results) => rounds.add(&results),
                Err(problem) => return Ok(Some(Work::Done(sim.outcomes(pending, Err(problem), None, self.gates)))),
            }
            let snrs = rounds.snr_db(pending);
            let reached = snrs.iter().all(|s| s.is_some_and(|s| s >= adaptive.target_snr_db));
            if reached || rounds.count >= max_rounds {
                let averaged = rounds.averaged();
                let mut outcomes = sim.outcomes(pending, Ok(averaged), None, self.gates);
                for (outcome, snr) in outcomes.iter_mut().zip(snrs) {
                    if outcome.2.is_none() && snr.is_none_or(|s| s < adaptive.target_snr_db) {
                        outcome.2 = Some(Problem::Unreached {
                            snr_db: snr,
                            target_db: adaptive.target_snr_db,
                            rounds: rounds.count,
                        });
                    }
                }
                return Ok(Some(Work::Done(outcomes)));
            }
        }
    }
}

pub(crate) type Playbacks = (DrivePlayback, Vec<AudioPlayback>);

/// Each actuator's playback at the audio rate (built once for the whole scan), and one at the DAQ rate for the
/// recording length (all have the same length).
pub(crate) fn build_playbacks(
    instruments: &Instruments<'_>,
    sweep: &[f64],
    protocol: &ExcitationProtocol,
    deconv: &DeconvConfig,
    calibration: Option<&Calibration>,
) -> Result<Playbacks, RecipeError> {
    let actuators = instruments.rig.wiring.actuator_channels.len();
    let fir_len = calibration.map_or(0, |c| c.filters.iter().map(|f| f.taps.len()).max().unwrap_or(0));
    // The tail holds the last response (ir_len) and the filter's own length.
    let tail = deconv.ir_len + fir_len;
    let fs = instruments.daq_rate_hz();
    let mut at_audio = Vec::with_capacity(actuators);
    let mut first = None;
    for a in 0..actuators {
        let filter = calibration.map(|c| &c.filters[a]);
        let playback = DrivePlayback::new(sweep, protocol.repetitions, tail, filter)?;
        at_audio.push(playback.at_audio_rate(&instruments.rig.wiring, a, fs)?);
        first.get_or_insert(playback);
    }
    let first = first.ok_or_else(|| RecipeError::Config("no actuator is wired".into()))?;
    Ok((first, at_audio))
}

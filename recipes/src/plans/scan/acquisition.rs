//! The scan's recording of a point (the engine has aimed): every pending actuator recorded (one at a time, or every
//! shot of a simultaneous protocol, round after round for an adaptive one), each through the engine's `acquire`
//! with the scan's retry policy.

use std::collections::HashMap;

use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::error::DspError;
use metaplate_dsp::excitation::{Adaptive, AdaptiveTarget, Decoder, ExcitationProtocol};
use metaplate_dsp::pipeline::ChannelResult;

use crate::drive::{AudioPlayback, DrivePlayback};
use crate::engine::acquire::record_samples;
use crate::engine::aim::Aimed;
use crate::engine::plan::Lab;
use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::plans::calibrate::Calibration;
use crate::plans::scan::ScanPlan;
use crate::plans::scan::gates::{gated, in_units};
use crate::plans::scan::points::{Outcome, Problem};
use crate::plans::scan::processing::{Channel, Job, ScanProcessor, Work};
use crate::plans::scan::simultaneous::{Averager, Simultaneous};

impl ScanPlan<'_> {
    /// Records every actuator still to measure at `point` (`pending`; the beam already at `aimed`); `None` if
    /// abandoned on request.
    pub(super) fn record_point(
        &mut self,
        point: usize,
        pending: &[usize],
        aimed: Aimed,
        processor: &ScanProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<Job>, RecipeError> {
        if let Some(sim) = &processor.simultaneous {
            let work = match self.record_simultaneous(point, pending, sim, processor, lab)? {
                Some(work) => work,
                None => return Ok(None),
            };
            return Ok(Some(Job { point, aimed, work }));
        }
        if let Some(adaptive) = self.cfg.protocol.adaptive {
            let mut outcomes = Vec::with_capacity(pending.len());
            for &actuator in pending {
                match self.record_rounds(point, actuator, adaptive, processor, lab)? {
                    Some(outcome) => outcomes.push(outcome),
                    None => return Ok(None),
                }
            }
            return Ok(Some(Job { point, aimed, work: Work::Done(outcomes) }));
        }
        let mut channels = Vec::with_capacity(pending.len());
        for &actuator in pending {
            let buffers = self.playbacks[actuator].buffers();
            let Some(acquired) = lab.acquire(&buffers, self.record, point)? else {
                return Ok(None);
            };
            self.book.count_acquisitions(point, actuator, acquired.attempts);
            let problem = acquired.problem.map(Problem::from);
            channels.push(Channel { actuator, acquisition: acquired.acquisition, problem });
        }
        Ok(Some(Job { point, aimed, work: Work::Channels(channels) }))
    }

    /// Plays `actuator` alone at `point` (the beam already there), shot after shot, decoding each at once and
    /// averaging them weighted by their periods, until the protocol's adaptive target is reached or its periods
    /// (`max_rounds` times the protocol's) are spent (a sequential adaptive protocol); `None` if abandoned on
    /// request. The first shot plays the protocol's periods; each next one as many as the estimate so far says are
    /// missing ([`next_shot_periods`]). A shot with an acquisition problem ends the rounds: the row is settled on
    /// that shot alone, with its problem (so it is deferred and measured again).
    fn record_rounds(
        &mut self,
        point: usize,
        actuator: usize,
        adaptive: Adaptive,
        processor: &ScanProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<Outcome>, RecipeError> {
        let (gates, fs) = (&processor.gates, processor.decoder.sample_rate_hz());
        let first = self.cfg.protocol.repetitions;
        let budget = adaptive.max_rounds * first;
        let mut rounds = Averager::new(1);
        let (mut periods, mut played) = (first, 0);
        loop {
            let (buffers, record) = if periods == first {
                (self.playbacks[actuator].buffers(), self.record)
            } else {
                let extra = self.extra.as_mut().ok_or_else(|| RecipeError::Internal("no extra shots".into()))?;
                extra.shot(lab.instruments, self.calibration, actuator, periods)?
            };
            let Some(acquired) = lab.acquire(&buffers, record, point)? else {
                return Ok(None);
            };
            // Extra rounds are the protocol's, not retries: only the first round counts as the row's acquisition.
            self.book.count_acquisitions(point, actuator, acquired.attempts - 1 + u32::from(rounds.count == 0));
            let acq = &acquired.acquisition;
            let (velocity, loopback) = (&acq.recording.velocity_v, &acq.recording.loopback_v);
            let decoded = match &mut self.extra {
                Some(extra) if periods != first => extra.decode(&self.cfg.protocol, periods, velocity, loopback),
                _ => processor.decoder.decode_shot(velocity, loopback),
            };
            let r = match decoded {
                Ok(r) => in_units(r, acq.scale.m_s_per_v * gates.volts_per_fs),
                Err(e) => return Ok(Some((actuator, None, Some(Problem::Processing(e.to_string()))))),
            };
            if let Some(problem) = acquired.problem.map(Problem::from) {
                return Ok(Some(gated(actuator, r, Some(problem), gates, fs)));
            }
            rounds.add_weighted(std::slice::from_ref(&r), periods as f64);
            played += periods;
            let (snr, error) = (rounds.snr_db(&[0])[0], rounds.error_db(&[0], fs)[0]);
            let reached = adaptive.target.reached(snr, error);
            let left = budget.saturating_sub(played);
            if reached || left < MIN_SHOT_PERIODS {
                let Some(Some(mean)) = rounds.averaged().into_iter().next() else {
                    return Err(RecipeError::Internal("no averaged response".into()));
                };
                let mut outcome = gated(actuator, mean, None, gates, fs);
                if outcome.2.is_none() && !reached {
                    let value_db = match adaptive.target {
                        AdaptiveTarget::SnrDb(_) => snr,
                        AdaptiveTarget::ErrorDb(_) => error,
                    };
                    outcome.2 = Some(Problem::Unreached { target: adaptive.target, value_db, rounds: rounds.count });
                }
                return Ok(Some(outcome));
            }
            periods = next_shot_periods(adaptive.target.shortfall_db(snr, error), played, first, left);
        }
    }

    /// Plays every shot of a simultaneous protocol at `point` (the beam already there), round after round for an
    /// adaptive one; `None` if abandoned on request.
    fn record_simultaneous(
        &mut self,
        point: usize,
        pending: &[usize],
        sim: &Simultaneous,
        processor: &ScanProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<Work>, RecipeError> {
        let gates = &processor.gates;
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
                let Some(acquired) = lab.acquire(&buffers, self.record, point)? else {
                    return Ok(None);
                };
                retries += acquired.attempts - 1;
                worst = worst.or(acquired.problem.map(Problem::from));
                acquisitions.push(acquired.acquisition);
            }
            for &a in pending {
                self.book.count_acquisitions(point, a, retries + u32::from(rounds.count == 0));
            }
            retries = 0;
            let Some(adaptive) = sim.adaptive else {
                return Ok(Some(Work::Shots { pending: pending.to_vec(), acquisitions, problem: worst }));
            };
            // Adaptive: decode this round now, to decide whether another is needed.
            if worst.is_some() {
                let decoded = Err(Problem::Processing("an acquisition of the round failed".into()));
                return Ok(Some(Work::Done(sim.outcomes(pending, decoded, worst, gates))));
            }
            match sim.decode(&processor.decoder, &acquisitions, gates) {
                Ok(results) => rounds.add(&results),
                Err(problem) => return Ok(Some(Work::Done(sim.outcomes(pending, Err(problem), None, gates)))),
            }
            let snrs = rounds.snr_db(pending);
            let errors = rounds.error_db(pending, sim.sample_rate_hz);
            let target = adaptive.target;
            let reached = snrs.iter().zip(&errors).all(|(&s, &e)| target.reached(s, e));
            if reached || rounds.count >= max_rounds {
                let averaged = rounds.averaged();
                let mut outcomes = sim.outcomes(pending, Ok(averaged), None, gates);
                for ((outcome, snr), error) in outcomes.iter_mut().zip(snrs).zip(errors) {
                    if outcome.2.is_none() && !target.reached(snr, error) {
                        let value_db = match target {
                            AdaptiveTarget::SnrDb(_) => snr,
                            AdaptiveTarget::ErrorDb(_) => error,
                        };
                        outcome.2 = Some(Problem::Unreached { target, value_db, rounds: rounds.count });
                    }
                }
                return Ok(Some(Work::Done(outcomes)));
            }
        }
    }
}

/// Fewest periods a sequential adaptive shot plays: its noise estimate is the spread of its periods.
const MIN_SHOT_PERIODS: usize = 2;
/// How much longer than predicted the next shot of a sequential adaptive row plays: the estimate it is predicted from
/// scatters by about 10 % (its noise over the band's bins), and a shot that falls just short costs another shot's
/// ring-out.
const SHOT_MARGIN: f64 = 1.1;

/// Periods of the next shot of a sequential adaptive row that has had `played` periods and is `shortfall_db` short
/// of its target: its noise falls as 1 / periods, so `played (10^(shortfall / 10) - 1)` more, times
/// [`SHOT_MARGIN`]; at least [`MIN_SHOT_PERIODS`] and at most `left`; `first` (the protocol's periods) when the
/// estimate is unknown.
fn next_shot_periods(shortfall_db: Option<f64>, played: usize, first: usize, left: usize) -> usize {
    let wanted = match shortfall_db {
        Some(db) if db.is_finite() => {
            let more = played as f64 * (10f64.powf(db.max(0.0) / 10.0) - 1.0) * SHOT_MARGIN;
            more.ceil().min(left as f64) as usize
        }
        _ => first,
    };
    wanted.max(MIN_SHOT_PERIODS).min(left)
}

/// The shots of sequential adaptive rows beyond their first: `periods` periods of the sweep for one actuator, built
/// when first asked for (their number comes from the estimate so far), and the decoder of each length.
pub(crate) struct ExtraShots {
    /// One period of the excitation at the DAQ rate, and the deconvolution at that rate.
    sweep: Vec<f64>,
    deconv: DeconvConfig,
    /// Samples of silence after the last period: the response and the inverse filter ring out.
    tail: usize,
    playbacks: HashMap<(usize, usize), (AudioPlayback, usize)>,
    decoders: HashMap<usize, Decoder>,
}

/// Playbacks kept at most (each up to a few MB at the audio rate); beyond, the cache starts again.
const MAX_EXTRA_PLAYBACKS: usize = 32;

impl ExtraShots {
    pub(crate) fn new(sweep: Vec<f64>, deconv: DeconvConfig, calibration: Option<&Calibration>) -> Self {
        let fir_len = calibration.map_or(0, |c| c.filters.iter().map(|f| f.taps.len()).max().unwrap_or(0));
        let tail = deconv.ir_len + fir_len;
        Self { sweep, deconv, tail, playbacks: HashMap::new(), decoders: HashMap::new() }
    }

    /// The audio buffers of `periods` periods for `actuator`, and the samples to record.
    fn shot(
        &mut self,
        instruments: &Instruments<'_>,
        calibration: Option<&Calibration>,
        actuator: usize,
        periods: usize,
    ) -> Result<(Vec<Vec<f64>>, usize), RecipeError> {
        if !self.playbacks.contains_key(&(actuator, periods)) {
            if self.playbacks.len() >= MAX_EXTRA_PLAYBACKS {
                self.playbacks.clear();
            }
            let fs = instruments.daq_rate_hz();
            let filter = calibration.and_then(|c| c.filters.get(actuator));
            let playback = DrivePlayback::new(&self.sweep, periods, self.tail, filter)?;
            let record = record_samples(&playback, fs);
            let audio = playback.at_audio_rate(&instruments.rig.wiring, actuator, fs)?;
            self.playbacks.insert((actuator, periods), (audio, record));
        }
        let (playback, record) = &self.playbacks[&(actuator, periods)];
        Ok((playback.buffers(), *record))
    }

    /// One shot of `periods` periods of `protocol`, decoded.
    fn decode(
        &mut self,
        protocol: &ExcitationProtocol,
        periods: usize,
        velocity: &[f64],
        loopback: &[f64],
    ) -> Result<ChannelResult, DspError> {
        if !self.decoders.contains_key(&periods) {
            let shots = ExcitationProtocol { repetitions: periods, adaptive: None, ..protocol.clone() };
            self.decoders.insert(periods, shots.decoder(1, &self.deconv)?);
        }
        self.decoders[&periods].decode_shot(velocity, loopback)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_next_shot_plays_what_the_estimate_says_is_missing() {
        // 3 dB short after 4 periods: the noise must halve, 4 more periods, 10 % over: 5.
        assert_eq!(next_shot_periods(Some(3.0103), 4, 4, 100), 5);
        // 10 dB short after 4: 36 more, 40 with the margin; capped by what the budget leaves.
        assert_eq!(next_shot_periods(Some(10.0), 4, 4, 100), 40);
        assert_eq!(next_shot_periods(Some(10.0), 4, 4, 28), 28);
        // Just short: at least the 2 periods a noise estimate needs.
        assert_eq!(next_shot_periods(Some(0.01), 8, 4, 100), 2);
        assert_eq!(next_shot_periods(Some(-1.0), 8, 4, 100), 2);
        // Unknown (no estimate yet, or not finite): the protocol's own periods.
        assert_eq!(next_shot_periods(None, 4, 4, 100), 4);
        assert_eq!(next_shot_periods(Some(f64::NAN), 4, 3, 100), 3);
        assert_eq!(next_shot_periods(Some(f64::INFINITY), 4, 3, 100), 3);
    }
}

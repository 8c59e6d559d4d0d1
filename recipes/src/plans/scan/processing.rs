//! The scan's processing of a point's recordings, on the worker thread: deconvolution (or a simultaneous
//! protocol's decode) and the quality gates, into outcomes the plan settles.

use metaplate_dsp::excitation::Decoder;

use crate::engine::aim::Aimed;
use crate::engine::plan::Processor;
use crate::engine::session::Acquisition;
use crate::plans::scan::gates::{Gates, gated, in_units};
use crate::plans::scan::points::{Outcome, Problem};
use crate::plans::scan::simultaneous::Simultaneous;

/// One acquisition sent for processing.
pub(crate) struct Channel {
    pub actuator: usize,
    pub acquisition: Acquisition,
    /// What the retry policy left wrong with it.
    pub problem: Option<Problem>,
}

/// A point's recordings, sent to the worker thread.
pub(crate) struct Job {
    pub point: usize,
    pub aimed: Aimed,
    pub work: Work,
}

/// What a job carries to the worker.
pub(crate) enum Work {
    /// Sequential: one acquisition per pending actuator.
    Channels(Vec<Channel>),
    /// Simultaneous: one acquisition per shot, for the pending actuators; the worst acquisition problem.
    Shots { pending: Vec<usize>, acquisitions: Vec<Acquisition>, problem: Option<Problem> },
    /// Already processed (adaptive protocols decide between rounds, so they decode as they acquire).
    Done(Vec<Outcome>),
}

/// A job processed: what the plan settles.
pub(crate) struct Processed {
    pub point: usize,
    pub aimed: Aimed,
    /// Per channel: actuator, the response when processing succeeded, problem if any.
    pub outcomes: Vec<Outcome>,
}

/// The scan's processing, shared with the engine's worker thread: the protocol's decoder at the DAQ rate (adaptive
/// rounds are also decoded while recording, to decide on the next), the simultaneous protocol if the scan plays one,
/// and the gates.
pub(crate) struct ScanProcessor {
    pub decoder: Decoder,
    pub simultaneous: Option<Simultaneous>,
    pub gates: Gates,
}

impl Processor for ScanProcessor {
    type Recorded = Job;
    type Processed = Processed;

    fn process(&self, job: Job) -> Processed {
        process(job, &self.decoder, self.simultaneous.as_ref(), &self.gates)
    }
}

/// Deconvolves and gates every channel of a job (on the worker thread).
fn process(job: Job, decoder: &Decoder, simultaneous: Option<&Simultaneous>, gates: &Gates) -> Processed {
    let outcomes = match (job.work, simultaneous) {
        (Work::Channels(channels), _) => process_channels(channels, decoder, gates),
        (Work::Shots { pending, acquisitions, problem }, Some(sim)) => {
            let decoded =
                sim.decode(decoder, &acquisitions, gates).map(|results| results.into_iter().map(Some).collect());
            sim.outcomes(&pending, decoded, problem, gates)
        }
        (Work::Shots { pending, .. }, None) => {
            let problem = Problem::Processing("shots without a simultaneous protocol".into());
            pending.into_iter().map(|a| (a, None, Some(problem.clone()))).collect()
        }
        (Work::Done(outcomes), _) => outcomes,
    };
    Processed { point: job.point, aimed: job.aimed, outcomes }
}

/// Deconvolves and gates the channels of a sequential job.
fn process_channels(channels: Vec<Channel>, decoder: &Decoder, gates: &Gates) -> Vec<Outcome> {
    channels
        .into_iter()
        .map(|ch| {
            let acq = &ch.acquisition;
            match decoder.decode_shot(&acq.recording.velocity_v, &acq.recording.loopback_v) {
                Err(e) => (ch.actuator, None, ch.problem.or(Some(Problem::Processing(e.to_string())))),
                Ok(r) => {
                    let r = in_units(r, acq.scale.m_s_per_v * gates.volts_per_fs);
                    gated(ch.actuator, r, ch.problem, gates, decoder.sample_rate_hz())
                }
            }
        })
        .collect()
}

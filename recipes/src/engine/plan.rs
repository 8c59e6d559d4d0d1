//! What the engine asks of a plan: the [`Plan`] trait, the [`Step`]s a plan hands out, and the [`Verdict`] it
//! gives on each processed step.
//!
//! The split follows Bluesky's plans and RunEngine, in typed Rust: a plan decides (what to measure next, what a
//! result means: settle and commit, defer, measure again); the engine does (aims, acquires with the retry policy,
//! recovers devices, re-measures the reference after a recovery, processes on a worker thread while the next step
//! is acquired, commits, reports). A plan's state is plain data, so its decisions are tested without a lab.

use std::collections::BTreeSet;

use metaplate_core::rig::Wiring;
use metaplate_store::{DatasetMeta, IrRecord, Status};

use crate::engine::acquire::{Acquired, RetryPolicy, acquire};
use crate::engine::aim::Aimed;
use crate::engine::reference::ReferenceSpec;
use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::events::{Event, Observer, Phase, RunControl};
use crate::output::Output;

/// One thing for the engine to do: aim (optionally), then let the plan record its playbacks.
#[derive(Debug, Clone, PartialEq)]
pub struct Step<D> {
    /// The unit (grid point, actuator) the step measures: what retries, events and the aim's nudges are keyed by.
    pub unit: usize,
    /// Where to aim first, and the visit that keys the nudges; `None` leaves the beam where it is.
    pub aim: Option<AimAt>,
    /// What else the plan needs to record the step (which actuators, which phase).
    pub detail: D,
}

/// A position to aim at, m, on visit `visit` of the step's unit (nudges are keyed by seed, unit and visit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AimAt {
    /// Beam position, m.
    pub position_m: (f64, f64),
    /// The visit (0 for the first): a re-measure nudges elsewhere than the first measurement.
    pub visit: u32,
}

/// What a plan wants next.
#[derive(Debug, Clone, PartialEq)]
pub enum Next<D> {
    /// Measure this.
    Step(Step<D>),
    /// Nothing can be chosen until the step in flight is settled (its result decides the next).
    Wait,
    /// Every unit is settled.
    Done,
}

/// What a processed step means for its unit.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// The unit is settled: commit its rows, with its worst status and median SNR (for the event).
    Commit {
        /// The unit committed.
        unit: usize,
        /// Its rows.
        records: Vec<IrRecord>,
        /// The worst status of its rows.
        status: Status,
        /// Median SNR of its rows, dB, where known.
        snr_db: Option<f64>,
    },
    /// The unit goes on (another phase, another visit later); `retry` is reported when it is a repeat: (unit,
    /// attempt, reason).
    Continue {
        /// A repeat to report as a retry event.
        retry: Option<(usize, u32, String)>,
    },
}

/// The engine's settings for one run, which the plan's configuration gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Velocity range asked of the vibrometer first, m/s (a resume starts from the committed state instead).
    pub max_velocity_m_s: f64,
    /// How often an unusable acquisition is repeated.
    pub retry: RetryPolicy,
    /// Aiming and its nudges.
    pub aim: crate::engine::aim::AimPolicy,
    /// Seed of the nudges.
    pub seed: u64,
    /// Waiting for devices.
    pub recovery: crate::engine::session::RecoveryPolicy,
}

/// The processing half of a plan: pure, shared with the worker thread.
pub trait Processor: Sync {
    /// What a step's recording hands to processing.
    type Recorded: Send;
    /// What processing makes of it.
    type Processed: Send;

    /// Processes one recorded step (on the worker thread, while the engine acquires the next).
    fn process(&self, recorded: Self::Recorded) -> Self::Processed;
}

/// A recipe's decisions. The engine calls, in order: [`Plan::meta`], [`Plan::start`] (what is committed already),
/// [`Plan::setup`] (the instruments' rates known), then [`Plan::next`], [`Plan::record`] and [`Plan::settle`] until
/// the plan is done or a stop is requested.
pub trait Plan {
    /// What a step carries besides its unit and aim.
    type Detail;
    /// The pure processing, shared with the worker thread.
    type Processor: Processor;

    /// The dataset's description (recipe, configuration, grid, seed; the scene and software version of `out`); a
    /// resume refuses a different one.
    fn meta(&self, out: &Output) -> DatasetMeta;

    /// Learns what the dataset already holds (`(row, actuator)` keys; empty for a fresh run); returns the units in
    /// the plan and how many of them are committed.
    fn start(&mut self, committed: &BTreeSet<(u32, u16)>) -> (usize, usize);

    /// Prepares what the rig's configuration decides (rates, playbacks, decoders).
    ///
    /// # Errors
    /// [`RecipeError::Config`] for a configuration the rig cannot play.
    fn setup(&mut self, instruments: &Instruments<'_>) -> Result<Self::Processor, RecipeError>;

    /// Every position the plan may aim at before nudges, m, so the engine can ask the aimer whether each is within
    /// reach before the run starts (empty: nothing to check).
    fn aim_points(&self) -> Vec<(f64, f64)> {
        Vec::new()
    }

    /// The reference check after a device recovery, if the plan wants one.
    fn reference(&self) -> Option<ReferenceSpec> {
        None
    }

    /// What to measure next; `in_flight` says whether a step is still being processed.
    fn next(&mut self, in_flight: bool) -> Next<Self::Detail>;

    /// Whether a unit is partly measured and must be finished before a stop is honoured (a stop otherwise takes
    /// effect before the next step).
    fn mid_unit(&self) -> bool {
        false
    }

    /// Records `step` (the beam already at `aimed` when the step asked to aim); `None` when abandoned on request.
    ///
    /// # Errors
    /// Device faults recovery cannot fix, as [`RecipeError`] says.
    fn record(
        &mut self,
        step: &Step<Self::Detail>,
        aimed: Option<Aimed>,
        processor: &Self::Processor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<<Self::Processor as Processor>::Recorded>, RecipeError>;

    /// What a processed step means for its unit.
    ///
    /// # Errors
    /// [`RecipeError`] when the result cannot be used at all (an internal inconsistency, a processing error the
    /// plan treats as fatal).
    fn settle(&mut self, processed: <Self::Processor as Processor>::Processed) -> Result<Verdict, RecipeError>;
}

/// The lab as a plan's [`Plan::record`] sees it: acquisitions with the run's retry policy, and the wiring.
pub struct Lab<'a, 'r> {
    pub(crate) instruments: &'a mut Instruments<'r>,
    pub(crate) retry: RetryPolicy,
    pub(crate) control: &'a RunControl,
    pub(crate) observer: &'a mut dyn Observer,
}

impl Lab<'_, '_> {
    /// Plays `buffers` (one per audio channel, at the audio rate) and records `record_samples` per DAQ channel,
    /// with the run's retry policy; `unit` names the retries. `None` when abandoned on request.
    ///
    /// # Errors
    /// Device faults recovery cannot fix.
    pub fn acquire(
        &mut self,
        buffers: &[Vec<f64>],
        record_samples: usize,
        unit: usize,
    ) -> Result<Option<Acquired>, RecipeError> {
        // The actuators driven: those whose audio channel carries a non-silent buffer.
        let actuators = (self.instruments.rig.wiring.actuator_channels.iter().enumerate())
            .filter(|(_, channel)| buffers.get(**channel as usize).is_some_and(|b| b.iter().any(|v| *v != 0.0)))
            .map(|(actuator, _)| actuator)
            .collect();
        self.observer.event(&Event::Phase { unit, phase: Phase::Playing, actuators });
        acquire(self.instruments, buffers, record_samples, self.retry, unit, self.control, self.observer)
    }

    /// The DAQ sample rate, Hz.
    pub fn daq_rate_hz(&self) -> f64 {
        self.instruments.daq_rate_hz()
    }

    /// The rig's wiring.
    pub fn wiring(&self) -> &Wiring {
        &self.instruments.rig.wiring
    }
}

//! The engine's loop, [`run`], and the run skeleton under it: the dataset opened fresh or resumed, `Started`, a
//! plan's steps aimed, acquired and processed (the next step acquired while the last is processed, when the plan
//! can choose it), one commit (and manifest checkpoint) per settled unit with its `Committed` event and the stop
//! hook, then `Finished` or `Stopped`.

use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;
use std::sync::mpsc;

use metaplate_core::clock::Clock;
use metaplate_core::rig::Rig;
use metaplate_store::{DatasetMeta, IrRecord};

use crate::engine::aim::aim;
use crate::engine::plan::{Lab, Next, Plan, Processor, Settings, Verdict};
use crate::engine::reference::ReferenceCheck;
use crate::engine::rig_record::rig_config;
use crate::engine::session::{Instruments, SessionState};
use crate::error::RecipeError;
use crate::events::{Event, Observer, Phase, RunControl, UnitPosition};
use crate::output::{self, Output};

/// What a run did, for the recipe's summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunReport {
    /// Units committed by this run.
    pub committed_now: usize,
    /// Units committed in all (with earlier runs).
    pub committed: usize,
    /// Units in the plan.
    pub total: usize,
    /// Rig clock seconds this run took (simulated in the mock lab).
    pub clock_s: f64,
    /// Wall-clock seconds this run spent in commits (batch file, fsyncs, journal line).
    pub commit_s: f64,
}

/// Runs `plan` on `rig` into `out` until every unit is committed or a stop is requested.
///
/// Steps are acquired on this thread and processed on a worker thread: while step k is processed, step k + 1 is
/// acquired if the plan can choose it without k's result ([`Next::Wait`] otherwise), so the instruments set the
/// pace. Results are settled in the order the steps were taken, so commits are in a deterministic order. Each unit
/// commits the session state after its last acquisition (what the next unit starts from, restored on resume).
///
/// # Errors
/// [`RecipeError::Aim`] before anything starts when a point of the plan is out of the aimer's reach;
/// [`RecipeError::Interrupted`] when stopped on request (everything committed stays); device, store and
/// configuration errors as [`RecipeError`] says.
pub fn run<P: Plan>(
    plan: &mut P,
    settings: Settings,
    rig: &mut Rig,
    out: &Output,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<RunReport, RecipeError> {
    // Every point within the aimer's reach, or nothing starts (nudges, a fraction of a millimetre, are not checked).
    for (x_m, y_m) in plan.aim_points() {
        rig.aim.check_reachable(x_m, y_m)?;
    }
    let mut meta = plan.meta(out);
    let rig_record = rig_config(rig)?;
    if let Some(report) = &out.preflight {
        let record = crate::output::manifest_record(report, &rig_record);
        meta.config.insert(crate::output::PREFLIGHT_KEY.into(), record);
    }
    meta.config.insert("rig".into(), rig_record);
    let mut run = Run::open(out, meta, rig.clock.clone(), control)?;
    let (total, done_before) = plan.start(&run.committed_keys);
    run.start(total, done_before, observer);
    let state = run.session_state(SessionState { velocity_range_m_s: settings.max_velocity_m_s });
    let mut instruments = Instruments::new(rig, state, settings.recovery, control, observer)?;
    let processor = plan.setup(&instruments)?;
    let mut reference = plan.reference().map(|spec| ReferenceCheck::new(spec, &out.dir));
    let mut report = RunReport { total, committed: done_before, ..RunReport::default() };
    std::thread::scope(|scope| -> Result<(), RecipeError> {
        let (job_tx, job_rx) = mpsc::channel::<<P::Processor as Processor>::Recorded>();
        let (done_tx, done_rx) = mpsc::channel::<<P::Processor as Processor>::Processed>();
        let processor = &processor;
        scope.spawn(move || {
            for job in job_rx {
                if done_tx.send(processor.process(job)).is_err() {
                    break;
                }
            }
        });
        let mut in_flight = false;
        // The unit whose recording the worker is processing (meaningful while `in_flight`).
        let mut in_flight_unit = 0;
        let mut abandoned = false;
        // Per unit, the session state after its last acquisition: what it commits (the next unit may have been
        // acquired, and widened the range, before it commits).
        let mut state_after: HashMap<usize, SessionState> = HashMap::new();
        loop {
            let stopping = abandoned || (control.stop_requested() && !plan.mid_unit());
            let next = if stopping { Next::Done } else { plan.next(in_flight) };
            match next {
                Next::Done if !in_flight => break,
                // A plan waiting with nothing in flight would wait forever.
                Next::Wait if !in_flight => {
                    return Err(RecipeError::Internal("the plan waits for a result while none is in flight".into()));
                }
                _ => {}
            }
            let mut recorded = None;
            let mut recorded_unit = 0;
            if let Next::Step(step) = next {
                recorded_unit = step.unit;
                if let Some(reference) = reference.as_mut() {
                    reference.after_recovery(&mut instruments, control, observer)?;
                }
                let aimed = match step.aim {
                    Some(at) => Some({
                        observer.event(&Event::Phase { unit: step.unit, phase: Phase::Moving, actuators: Vec::new() });
                        aim(
                            &mut instruments,
                            at.position_m,
                            (settings.seed, step.unit as u64, at.visit),
                            &settings.aim,
                            control,
                            observer,
                        )?
                    }),
                    None => None,
                };
                let mut lab = Lab { instruments: &mut instruments, retry: settings.retry, control, observer };
                recorded = plan.record(&step, aimed, processor, &mut lab)?;
                match recorded {
                    Some(_) => {
                        state_after.insert(step.unit, instruments.state());
                    }
                    None => abandoned = true,
                }
            }
            if in_flight {
                observer.event(&Event::Phase { unit: in_flight_unit, phase: Phase::Processing, actuators: Vec::new() });
                let processed = done_rx
                    .recv()
                    .map_err(|_| RecipeError::Internal("the processing thread stopped unexpectedly".into()))?;
                in_flight = false;
                match plan.settle(processed)? {
                    Verdict::Commit { unit, records, status, snr_db } => {
                        let state = state_after.remove(&unit).unwrap_or_else(|| instruments.state());
                        tracing::info!(unit, status = status.as_str(), snr_db, "unit committed");
                        report.commit_s +=
                            run.commit(&records, state, unit, snr_db, status.as_str(), control, observer)?;
                        report.committed_now += 1;
                        report.committed = run.done();
                    }
                    Verdict::Continue { retry } => {
                        if let Some((unit, attempt, reason)) = retry {
                            observer.event(&Event::Retry { unit, attempt, reason });
                        }
                    }
                }
            }
            if let Some(job) = recorded {
                job_tx.send(job).map_err(|_| RecipeError::Internal("the processing thread stopped".into()))?;
                in_flight = true;
                in_flight_unit = recorded_unit;
            }
        }
        Ok(())
    })?;
    report.clock_s = run.elapsed_s();
    run.finish(observer)?;
    Ok(report)
}

/// A run in progress: the open dataset and the counts the events report.
struct Run {
    writer: metaplate_store::DatasetWriter,
    /// The (row, actuator) keys committed before this run (a resume), as the store found them.
    committed_keys: BTreeSet<(u32, u16)>,
    /// The session state committed with the last unit before this run (a resume), if any.
    restored: Option<SessionState>,
    total: usize,
    /// Units committed in the dataset, this run's and earlier ones'.
    done: usize,
    /// Units committed by this run.
    commits: usize,
    clock: Arc<dyn Clock>,
    t0_s: f64,
    /// Whether an earlier run was continued.
    resumed: bool,
}

impl Run {
    /// Opens (or with `out.resume`, resumes) the dataset of `meta` in `out`; the clock starts now.
    ///
    /// # Errors
    /// As [`output::open`]; [`RecipeError::Config`] if the committed session state does not read.
    fn open(out: &Output, meta: DatasetMeta, clock: Arc<dyn Clock>, control: &RunControl) -> Result<Self, RecipeError> {
        let opened = output::open(out, meta, control)?;
        let restored =
            opened.report.as_ref().and_then(|r| r.state.as_ref()).map(SessionState::from_json).transpose()?;
        let t0_s = clock.now_s();
        let resumed = opened.report.is_some();
        Ok(Self {
            resumed,
            writer: opened.writer,
            committed_keys: opened.committed,
            restored,
            total: 0,
            done: 0,
            commits: 0,
            clock,
            t0_s,
        })
    }

    /// The session state to start from: the one committed with the last unit of an earlier run (a resume), else
    /// `configured`.
    fn session_state(&self, configured: SessionState) -> SessionState {
        match self.restored {
            Some(state) => {
                tracing::info!(
                    velocity_range_m_s = state.velocity_range_m_s,
                    configured_m_s = configured.velocity_range_m_s,
                    "resuming with the session state of the last committed unit"
                );
                state
            }
            None => configured,
        }
    }

    /// Reports the start: `total` units in the plan, `done` of them already committed.
    fn start(&mut self, total: usize, done: usize, observer: &mut dyn Observer) {
        self.total = total;
        self.done = done;
        observer.event(&Event::Started {
            total,
            done,
            dataset: self.writer.dir().to_path_buf(),
            config_hash: self.writer.manifest().config_hash.clone(),
            resumed: self.resumed,
        });
    }

    /// Seconds on the rig's clock since the run opened.
    fn elapsed_s(&self) -> f64 {
        self.clock.now_s() - self.t0_s
    }

    /// Units committed in the dataset (earlier runs' included).
    fn done(&self) -> usize {
        self.done
    }

    /// Commits `records` as one unit with `state`, the session state after its measurement (what the next unit
    /// starts from, restored by a resume), checkpoints the manifest (so a resume reads it without replaying the
    /// journal), reports it, and raises the stop level if the test hook asks. Returns the seconds the commit took.
    ///
    /// # Errors
    /// [`RecipeError::Store`] if the store refuses the batch or the checkpoint.
    #[allow(clippy::too_many_arguments)] // The unit (rows, state, index, SNR, status), the control and the observer.
    fn commit(
        &mut self,
        records: &[IrRecord],
        state: SessionState,
        unit: usize,
        snr_db: Option<f64>,
        status: &str,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<f64, RecipeError> {
        observer.event(&Event::Phase { unit, phase: Phase::Committing, actuators: Vec::new() });
        let started = std::time::Instant::now();
        self.writer.commit_batch_with_state(records, Some(state.to_json()))?;
        self.writer.checkpoint()?;
        let commit_s = started.elapsed().as_secs_f64();
        self.commits += 1;
        self.done += 1;
        observer.event(&Event::Committed {
            unit,
            done: self.done,
            total: self.total,
            snr_db,
            status: status.to_string(),
            clock_s: self.elapsed_s(),
            position: records.first().map(|r| UnitPosition {
                ix: r.meta.ix,
                iy: r.meta.iy,
                x_m: r.meta.x_m,
                y_m: r.meta.y_m,
            }),
        });
        control.committed(self.commits);
        Ok(commit_s)
    }

    /// Ends the run: `Finished` when every unit is committed, else `Stopped` and [`RecipeError::Interrupted`].
    ///
    /// # Errors
    /// [`RecipeError::Interrupted`] when units remain (a stop was requested).
    fn finish(self, observer: &mut dyn Observer) -> Result<usize, RecipeError> {
        if self.done < self.total {
            observer.event(&Event::Stopped { done: self.done });
            return Err(RecipeError::Interrupted { committed: self.done });
        }
        observer.event(&Event::Finished { done: self.done });
        Ok(self.done)
    }
}

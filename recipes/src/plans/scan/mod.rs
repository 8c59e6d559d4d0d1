//! The grid scan plan: every unmasked point, every actuator, the compensated excitation, deconvolution, quality
//! gates, bounded retries, a deferred re-measure queue, and one commit per point.
//!
//! Acquisition (the instruments, on this thread) and processing (deconvolution, on a worker thread) overlap: point
//! k is processed while point k + 1 is acquired, so the instruments set the pace. Results come back in the order
//! the points were sent, so commits are in a deterministic order.
//!
//! Per point and actuator, each acquisition goes through the engine's `acquire` (gaps, underruns, clipping:
//! repeated up to `max_attempts` times, clipping widening the velocity range), then is processed and gated (SNR,
//! clock drift). A point with an actuator that fails a gate is deferred to the end of the run and re-measured there
//! (only the failing actuators, the beam nudged), up to `deferred_visits` times; then it is committed with a status
//! saying what went wrong. No point is dropped.
//!
//! Sub-modules: [`points`] (the plan's state: what a result means for a point), `acquisition` (recording a point),
//! `processing` (the worker thread's deconvolution and gates), `simultaneous` (Hadamard, interleaved, adaptive).

mod acquisition;
pub(crate) mod points;
mod processing;
mod simultaneous;

use std::collections::{BTreeMap, VecDeque};
use std::sync::mpsc;

use metaplate_core::grid::GridSpec;
use metaplate_core::rig::Rig;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use metaplate_store::{DatasetDescription, DatasetMeta, Status};
use serde_json::{Map, Value, json};

use crate::drive::excitation;
use crate::engine::acquire::{RetryPolicy, record_samples, record_samples_for};
use crate::engine::aim::AimPolicy;
use crate::engine::now_unix_us;
use crate::engine::reference::{ReferenceCheck, ReferenceSpec};
use crate::engine::run::Run;
use crate::engine::session::{Instruments, RecoveryPolicy, SessionState};
use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};
use crate::output::Output;
use crate::plans::calibrate::Calibration;
use acquisition::{PointAcquisition, build_playbacks};
use metaplate_dsp::stats::median;
use points::{PointBook, Settled, point_records, severity};
use processing::{Gates, Job, Processed, process};
use simultaneous::Simultaneous;

/// Recipe name in the manifest.
pub const RECIPE: &str = "scan";

/// What a scan does, besides where.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanConfig {
    /// Excitation and processing.
    pub protocol: ExcitationProtocol,
    /// Lowest acceptable SNR of a response, dB.
    pub min_snr_db: f64,
    /// Largest acceptable clock drift between the audio interface and the DAQ, ppm.
    pub max_drift_ppm: f64,
    /// Acquisitions per actuator and visit before the point is deferred (or flagged).
    pub max_attempts: u32,
    /// Extra visits of a deferred point at the end of the run.
    pub deferred_visits: u32,
    /// Velocity range asked of the vibrometer, m/s.
    pub max_velocity_m_s: f64,
    /// Aiming.
    pub aim: AimPolicy,
    /// Waiting for devices.
    pub recovery: RecoveryPolicy,
    /// Seed of every random choice (beam nudges).
    pub seed: u64,
}

impl Default for ScanConfig {
    /// The paper's protocol; SNR at least 20 dB, drift within 200 ppm, 3 attempts, 2 deferred visits, 0.1 m/s.
    fn default() -> Self {
        Self {
            protocol: ExcitationProtocol::paper(),
            min_snr_db: 20.0,
            max_drift_ppm: 200.0,
            max_attempts: 3,
            deferred_visits: 2,
            max_velocity_m_s: 0.1,
            aim: AimPolicy::default(),
            recovery: RecoveryPolicy::default(),
            seed: 0,
        }
    }
}

/// Where a scan goes: the grid and the points to visit, in path order.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPlan {
    /// The grid (point indices refer to it).
    pub grid: GridSpec,
    /// Flat indices to measure, in the order visited (serpentine).
    pub points: Vec<usize>,
}

impl ScanPlan {
    /// The measurable points of `grid` (`mask[i]` true), or of its evenly spread `subset` (nx, ny), in serpentine
    /// order.
    ///
    /// # Errors
    /// [`RecipeError::Config`] for a mask of the wrong length, a subset that does not fit, or no point left.
    pub fn new(grid: GridSpec, mask: &[bool], subset: Option<(usize, usize)>) -> Result<Self, RecipeError> {
        if mask.len() != grid.len() {
            return Err(RecipeError::Config(format!("a mask of {} for a grid of {} points", mask.len(), grid.len())));
        }
        let candidates: Vec<usize> = match subset {
            Some((nx, ny)) => grid.subset(nx, ny).map_err(|e| RecipeError::Config(e.to_string()))?,
            None => (0..grid.len()).collect(),
        };
        let measurable: Vec<usize> = candidates.into_iter().filter(|&i| mask[i]).collect();
        if measurable.is_empty() {
            return Err(RecipeError::Config("no measurable point in the grid (all masked)".into()));
        }
        Ok(Self { grid, points: grid.serpentine_order(&measurable) })
    }
}

impl ScanConfig {
    /// The configuration as stored in the manifest: everything that changes the result, with the plan and the
    /// calibration's hash, so that a resume refuses a changed one.
    pub fn to_json(&self, plan: &ScanPlan, calibration_hash: Option<&str>) -> Map<String, Value> {
        let p = &self.protocol;
        let s = &p.sweep;
        let d = &p.deconv;
        let value = json!({
            "protocol": { "name": p.name, "repetitions": p.repetitions,
                "excitation": match p.scheme {
                    Scheme::Sequential => json!({ "kind": "sequential" }),
                    Scheme::Hadamard => json!({ "kind": "hadamard" }),
                    Scheme::Interleaved { slot_s } => json!({ "kind": "interleaved", "slot_s": slot_s }),
                },
                "adaptive": p.adaptive.map(|a| json!({ "target_snr_db": a.target_snr_db, "max_rounds": a.max_rounds })),
                "sweep": { "f1_hz": s.f1_hz, "f2_hz": s.f2_hz, "duration_s": s.duration_s, "amplitude": s.amplitude,
                           "fade_in_s": s.fade_in_s, "fade_out_s": s.fade_out_s, "kind": format!("{:?}", s.kind) },
                "deconv": { "ir_len": d.ir_len, "pre_samples": d.pre_samples, "regularisation": d.regularisation,
                            "band": d.band.map(|b| [b.lo_hz, b.hi_hz, b.lo_transition_hz, b.hi_transition_hz]) } },
            "gates": { "min_snr_db": self.min_snr_db, "max_drift_ppm": self.max_drift_ppm,
                       "max_attempts": self.max_attempts, "deferred_visits": self.deferred_visits },
            "max_velocity_m_s": self.max_velocity_m_s,
            "aim": { "min_signal_level": self.aim.min_signal_level, "nudge_m": self.aim.nudge_m,
                     "max_nudges": self.aim.max_nudges },
            "points": plan.points,
            "calibration": calibration_hash,
        });
        match value {
            Value::Object(map) => map,
            _ => Map::new(),
        }
    }
}

/// What a finished (or stopped) scan did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ScanSummary {
    /// Points committed by this run.
    pub committed_now: usize,
    /// Points committed in all (with earlier runs).
    pub committed: usize,
    /// Points in the plan.
    pub total: usize,
    /// Rows committed by this run, by status.
    pub statuses: BTreeMap<&'static str, usize>,
    /// Points deferred to the end at least once by this run.
    pub deferred: usize,
    /// Rig clock seconds this run took (simulated in the mock lab).
    pub clock_s: f64,
    /// Wall-clock seconds this run spent in commits (batch file, fsyncs, journal line).
    pub commit_s: f64,
}

/// Runs the scan of `plan` with the inverse filters of `calibration` (raw drive when `None`), into `out`.
///
/// # Errors
/// [`RecipeError::Interrupted`] when stopped on request (everything committed stays); device, store and
/// configuration errors as [`RecipeError`] says.
pub fn scan(
    rig: &mut Rig,
    plan: &ScanPlan,
    calibration: Option<&Calibration>,
    cfg: &ScanConfig,
    out: &Output,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<ScanSummary, RecipeError> {
    let actuators = rig.wiring.actuator_channels.len();
    if let Some(c) = calibration
        && c.filters.len() != actuators
    {
        return Err(RecipeError::Config(format!(
            "the calibration has {} filters for {actuators} wired actuators",
            c.filters.len()
        )));
    }
    let meta = DatasetMeta::new(
        RECIPE,
        cfg.to_json(plan, calibration.map(|c| c.content_hash.as_str())),
        out.scene.clone(),
        out.software_version.clone(),
        cfg.seed,
        plan.grid,
    )
    .with_description(DatasetDescription {
        ir_unit: match calibration {
            Some(_) => "m/s per full-scale drive, through the calibration's inverse filters".into(),
            None => "m/s per full-scale drive".into(),
        },
        pre_samples: u32::try_from(cfg.protocol.deconv.pre_samples).unwrap_or(u32::MAX),
    });
    let mut run = Run::open(out, meta, rig.clock.clone(), control)?;
    let is_committed = |p: usize| (0..actuators).all(|a| run.committed_keys.contains(&(p as u32, a as u16)));
    let todo: VecDeque<usize> = plan.points.iter().copied().filter(|&p| !is_committed(p)).collect();
    let total = plan.points.len();
    let done_before = total - todo.len();
    run.start(total, done_before, observer);

    let state = run.session_state(SessionState { velocity_range_m_s: cfg.max_velocity_m_s });
    let mut instruments = Instruments::new(rig, state, cfg.recovery, control, observer)?;
    let fs = instruments.daq_rate_hz();
    let volts_per_fs = instruments.rig.wiring.loopback_volts_per_full_scale;
    let protocol = &cfg.protocol;
    let sweep = excitation(&protocol.sweep, fs)?;
    let deconv = DeconvConfig { sample_rate_hz: fs, ..protocol.deconv };
    // One decoder for the run: the sequential path decodes each actuator's acquisition with it as it comes.
    let decoder = protocol.decoder(actuators, &deconv)?;
    let (playbacks, simultaneous, record) = if protocol.is_simultaneous() {
        let sim = Simultaneous::new(&instruments, protocol, &deconv, calibration)?;
        let record = record_samples_for(sim.playback.daq_len, fs);
        (Vec::new(), Some(sim), record)
    } else {
        let playbacks = build_playbacks(&instruments, &sweep, protocol, &deconv, calibration)?;
        let record = record_samples(&playbacks.0, fs);
        (playbacks.1, None, record)
    };
    let gates = Gates { min_snr_db: cfg.min_snr_db, max_drift_ppm: cfg.max_drift_ppm, volts_per_fs };

    let acquisition = PointAcquisition {
        plan,
        cfg,
        playbacks: &playbacks,
        simultaneous: simultaneous.as_ref(),
        decoder: &decoder,
        gates: &gates,
        actuators,
        record,
        retry: RetryPolicy { max_attempts: cfg.max_attempts },
    };
    let mut book = PointBook::new(actuators, cfg.deferred_visits);
    let mut summary = ScanSummary { total, committed: done_before, ..ScanSummary::default() };
    let ir_len = deconv.ir_len;
    let result = std::thread::scope(|scope| -> Result<(), RecipeError> {
        let (job_tx, job_rx) = mpsc::channel::<Job>();
        let (done_tx, done_rx) = mpsc::channel::<Processed>();
        let decoder = &decoder;
        let gates = &gates;
        let simultaneous = simultaneous.as_ref();
        scope.spawn(move || {
            for job in job_rx {
                if done_tx.send(process(job, decoder, simultaneous, gates)).is_err() {
                    break;
                }
            }
        });
        let mut reference = ReferenceCheck::new(ReferenceSpec {
            dir: &out.dir,
            points: &plan.points,
            protocol: &cfg.protocol,
            filters: calibration.map(|c| c.filters.as_slice()),
            limit_db: cfg.recovery.reference_limit_db,
            min_snr_db: cfg.min_snr_db,
            retry: acquisition.retry,
        });
        let mut main = todo;
        let mut in_flight = false;
        // Per point, the session state after its last acquisition: what it commits (the next point may have been
        // acquired, and widened the range, before it commits).
        let mut state_after = std::collections::HashMap::new();
        loop {
            let next = if control.stop_requested() {
                None
            } else if let Some(p) = main.pop_front() {
                Some(p)
            } else if !in_flight {
                book.deferred.pop_front()
            } else {
                None
            };
            let job = match next {
                Some(point) => {
                    reference.after_recovery(&mut instruments, control, observer)?;
                    let job = acquisition.acquire_point(&mut book, &mut instruments, point, control, observer)?;
                    state_after.insert(point, instruments.state());
                    job
                }
                None => None,
            };
            if in_flight {
                let processed = done_rx
                    .recv()
                    .map_err(|_| RecipeError::Internal("the processing thread stopped unexpectedly".into()))?;
                in_flight = false;
                let Processed { point, aimed, outcomes } = processed;
                match book.settle(point, aimed, outcomes)? {
                    Settled::Commit(rows) => {
                        let records = point_records(&plan.grid, point, rows, ir_len, fs, now_unix_us())?;
                        let state = state_after.get(&point).copied().unwrap_or_else(|| instruments.state());
                        commit_point(&mut run, &mut summary, (point, records, state), control, observer)?;
                    }
                    Settled::Deferred { visit, reasons } => {
                        let reasons = reasons.join("; ");
                        tracing::info!(point, visit, %reasons, "point deferred");
                        let reason = format!("deferred: {reasons}");
                        observer.event(&Event::Retry { unit: point, attempt: visit, reason });
                    }
                }
            }
            if let Some(job) = job {
                job_tx.send(job).map_err(|_| RecipeError::Internal("the processing thread stopped".into()))?;
                in_flight = true;
            }
            if !in_flight && (control.stop_requested() || (main.is_empty() && book.deferred.is_empty())) {
                break;
            }
        }
        Ok(())
    });
    result?;
    summary.clock_s = run.elapsed_s();
    summary.deferred = book.deferred_points;
    run.finish(observer)?;
    Ok(summary)
}

/// Commits a settled point's records through the run, counting their statuses in `summary`.
fn commit_point(
    run: &mut Run,
    summary: &mut ScanSummary,
    (point, records, state): (usize, Vec<(metaplate_store::IrRecord, Status)>, SessionState),
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<(), RecipeError> {
    let mut worst = Status::Valid;
    let mut snrs = Vec::new();
    for (record, status) in &records {
        snrs.extend(record.meta.snr_db);
        if severity(*status) > severity(worst) {
            worst = *status;
        }
        *summary.statuses.entry(status.as_str()).or_default() += 1;
    }
    let records: Vec<_> = records.into_iter().map(|(r, _)| r).collect();
    let snr_db = median(&mut snrs);
    tracing::info!(point, status = worst.as_str(), snr_db, "point committed");
    summary.commit_s += run.commit(&records, state, point, snr_db, worst.as_str(), control, observer)?;
    summary.committed_now += 1;
    summary.committed = run.done();
    Ok(())
}

//! The grid scan plan: every unmasked point, every actuator, the compensated excitation, deconvolution, quality
//! gates, bounded retries, a deferred re-measure queue, and one commit per point.
//!
//! The scan is a [`crate::engine::plan::Plan`]: a step is a visit of a point; the engine aims, records it and
//! processes it on its worker thread while the next point is acquired (the path's next point is known without the
//! last one's result; deferred points wait until nothing is in flight).
//!
//! Per point and actuator, each acquisition goes through the engine's `acquire` (gaps, underruns, clipping:
//! repeated up to `max_attempts` times, clipping widening the velocity range), then is processed and gated (SNR,
//! clock drift). A point with an actuator that fails a gate is deferred to the end of the run and re-measured there
//! (only the failing actuators, the beam nudged), up to `deferred_visits` times; then it is committed with a status
//! saying what went wrong. No point is dropped.
//!
//! Sub-modules: [`points`] (the plan's state: what a result means for a point), `acquisition` (recording a point),
//! `processing` (the worker thread's deconvolution), `gates` (SNR and drift), `simultaneous` (Hadamard, interleaved, adaptive).

mod acquisition;
mod gates;
pub(crate) mod points;
mod processing;
mod simultaneous;

use std::collections::{BTreeMap, BTreeSet, VecDeque};

use metaplate_core::grid::{GridSpec, GridSubset};
use metaplate_core::rig::Rig;
use metaplate_core::scene::Scene;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{AdaptiveTarget, ExcitationProtocol, Scheme};
use metaplate_dsp::stats::median;
use metaplate_store::{DatasetDescription, DatasetMeta, Status};
use serde_json::{Map, Value, json};

use crate::drive::{AudioPlayback, excitation};
use crate::engine::acquire::{RetryPolicy, record_samples, record_samples_for};
use crate::engine::aim::{AimPolicy, Aimed};
use crate::engine::now_unix_us;
use crate::engine::plan::{AimAt, Lab, Next, Plan, Settings, Step, Verdict};
use crate::engine::reference::ReferenceSpec;
use crate::engine::run::run;
use crate::engine::session::{Instruments, RecoveryPolicy};
use crate::error::RecipeError;
use crate::events::{Observer, RunControl};
use crate::output::Output;
use crate::plans::calibrate::Calibration;
use acquisition::{ExtraShots, build_playbacks};
use gates::Gates;
use points::{PointBook, Settled, point_records, severity};
use processing::{Job, Processed, ScanProcessor};
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

/// On the mock lab, a plan of at most this many points is prepared whole ([`ScanPoints::prepared_whole`]; 64 points
/// of 8 responses of 0.5 s take 100 MB).
pub const PREPARE_WHOLE_PLAN_POINTS: usize = 64;

/// Where a scan goes: the grid and the points to visit, in path order (what [`scan`] measures; the plan that
/// measures them, like the calibration's, is internal).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPoints {
    /// The grid (point indices refer to it).
    pub grid: GridSpec,
    /// Flat indices to measure, in the order visited (serpentine).
    pub points: Vec<usize>,
}

impl ScanPoints {
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

    /// The measurable points of `scene` (its grid and mask), or of its evenly spread `subset` (`--grid NXxNY`).
    ///
    /// # Errors
    /// As [`ScanPoints::new`].
    pub fn of_scene(scene: &Scene, subset: Option<GridSubset>) -> Result<Self, RecipeError> {
        Self::new(scene.grid, &scene.grid_mask(), subset.map(Into::into))
    }

    /// The points a mock lab prepares for this plan on `scene` when it is small (at most
    /// [`PREPARE_WHOLE_PLAN_POINTS`]): its points and the driving points, so a `check` and a scan of the same plan
    /// share one Green's-function cache entry. `None` for a larger plan, whose caller prepares only what it visits.
    pub fn prepared_whole(&self, scene: &Scene) -> Option<Vec<usize>> {
        (self.points.len() <= PREPARE_WHOLE_PLAN_POINTS).then(|| self.with_driving_points(scene))
    }

    /// The plan's points and, after them, `scene`'s driving points ([`Scene::driving_points`]): what a mock lab
    /// prepares to measure this plan and calibrate.
    pub fn with_driving_points(&self, scene: &Scene) -> Vec<usize> {
        [self.points.clone(), scene.driving_points()].concat()
    }

    /// `n` points spread along the path (at 1/(n+1), 2/(n+1), ... of it), without repeats.
    pub fn spread(&self, n: usize) -> Vec<usize> {
        let len = self.points.len();
        let mut points: Vec<usize> =
            (1..=n).filter_map(|k| self.points.get((k * len / (n + 1)).min(len.saturating_sub(1))).copied()).collect();
        points.dedup();
        points
    }
}

impl ScanConfig {
    /// The configuration as stored in the manifest: everything that changes the result, with the plan and the
    /// calibration's hash, so that a resume refuses a changed one.
    pub fn to_json(&self, plan: &ScanPoints, calibration_hash: Option<&str>) -> Map<String, Value> {
        let p = &self.protocol;
        let s = &p.sweep;
        let d = &p.deconv;
        let value = json!({
            "protocol": { "name": p.name, "repetitions": p.repetitions,
                "excitation": match p.scheme {
                    Scheme::Sequential => json!({ "kind": "sequential" }),
                    Scheme::Hadamard => json!({ "kind": "hadamard" }),
                    Scheme::Staggered => json!({ "kind": "staggered" }),
                    Scheme::Interleaved { slot_s } => json!({ "kind": "interleaved", "slot_s": slot_s }),
                },
                // An SNR target keeps the key it always had, so existing datasets' configurations are unchanged.
                "adaptive": p.adaptive.map(|a| match a.target {
                    AdaptiveTarget::SnrDb(db) => json!({ "target_snr_db": db, "max_rounds": a.max_rounds }),
                    AdaptiveTarget::ErrorDb(db) => json!({ "target_error_db": db, "max_rounds": a.max_rounds }),
                }),
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

/// What a finished scan did.
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

impl ScanSummary {
    /// Rows committed by this run that need a look: failed, dropout or overrange.
    pub fn flagged_rows(&self) -> usize {
        self.statuses.iter().filter(|(s, _)| ["failed", "dropout", "overrange"].contains(s)).map(|(_, n)| n).sum()
    }
}

impl std::fmt::Display for ScanSummary {
    /// One line: `6 of 6 points committed (6 now: rows 48 valid; 0 deferred), 0.05 h on the rig's clock`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let statuses: Vec<String> = self.statuses.iter().map(|(s, n)| format!("{n} {s}")).collect();
        write!(
            f,
            "{} of {} points committed ({} now: rows {}; {} deferred), {:.2} h on the rig's clock",
            self.committed,
            self.total,
            self.committed_now,
            if statuses.is_empty() { "none".to_string() } else { statuses.join(", ") },
            self.deferred,
            self.clock_s / 3600.0
        )
    }
}

/// Runs the scan of `plan` with the inverse filters of `calibration` (raw drive when `None`), into `out`.
///
/// # Errors
/// [`RecipeError::Interrupted`] when stopped on request (everything committed stays); device, store and
/// configuration errors as [`RecipeError`] says.
pub fn scan(
    rig: &mut Rig,
    plan: &ScanPoints,
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
    let settings = Settings {
        max_velocity_m_s: cfg.max_velocity_m_s,
        retry: RetryPolicy { max_attempts: cfg.max_attempts },
        aim: cfg.aim,
        seed: cfg.seed,
        recovery: cfg.recovery,
    };
    let mut scan_plan = ScanPlan::new(plan, calibration, cfg, actuators);
    let report = run(&mut scan_plan, settings, rig, out, control, observer)?;
    Ok(ScanSummary {
        committed_now: report.committed_now,
        committed: report.committed,
        total: report.total,
        statuses: scan_plan.statuses,
        deferred: scan_plan.book.deferred_points,
        clock_s: report.clock_s,
        commit_s: report.commit_s,
    })
}

/// The scan as a plan: the points still to visit, the book of what each point needs, and what the rig's
/// configuration decided (playbacks, recording length).
struct ScanPlan<'a> {
    /// The points, in path order.
    path: &'a ScanPoints,
    calibration: Option<&'a Calibration>,
    cfg: &'a ScanConfig,
    actuators: usize,
    /// Points not yet visited, in path order.
    main: VecDeque<usize>,
    book: PointBook,
    /// Each actuator's playback at the audio rate (sequential protocols; set up with the rig).
    playbacks: Vec<AudioPlayback>,
    /// Samples per DAQ channel to record per acquisition.
    record: usize,
    /// A sequential adaptive protocol's shots beyond a row's first (their lengths vary).
    extra: Option<ExtraShots>,
    ir_len: usize,
    fs: f64,
    /// Rows committed by this run, by status.
    statuses: BTreeMap<&'static str, usize>,
}

impl<'a> ScanPlan<'a> {
    fn new(path: &'a ScanPoints, calibration: Option<&'a Calibration>, cfg: &'a ScanConfig, actuators: usize) -> Self {
        Self {
            path,
            calibration,
            cfg,
            actuators,
            main: VecDeque::new(),
            book: PointBook::new(actuators, cfg.deferred_visits),
            playbacks: Vec::new(),
            record: 0,
            extra: None,
            ir_len: cfg.protocol.deconv.ir_len,
            fs: 0.0,
            statuses: BTreeMap::new(),
        }
    }

    /// A visit of `point`: the beam on it (nudged elsewhere on a re-visit), its actuators still to measure.
    fn visit(&mut self, point: usize) -> Step<Vec<usize>> {
        let (visit, pending) = self.book.visit(point);
        Step { unit: point, aim: Some(AimAt { position_m: self.path.grid.position_m(point), visit }), detail: pending }
    }
}

impl Plan for ScanPlan<'_> {
    type Detail = Vec<usize>;
    type Processor = ScanProcessor;

    fn meta(&self, out: &Output) -> DatasetMeta {
        DatasetMeta::new(
            RECIPE,
            self.cfg.to_json(self.path, self.calibration.map(|c| c.content_hash.as_str())),
            out.scene.clone(),
            out.software_version.clone(),
            self.cfg.seed,
            self.path.grid,
        )
        .with_description(DatasetDescription {
            ir_unit: match self.calibration {
                Some(_) => "m/s per full-scale drive, through the calibration's inverse filters".into(),
                None => "m/s per full-scale drive".into(),
            },
            pre_samples: u32::try_from(self.cfg.protocol.deconv.pre_samples).unwrap_or(u32::MAX),
        })
    }

    fn aim_points(&self) -> Vec<(f64, f64)> {
        self.path.points.iter().map(|&p| self.path.grid.position_m(p)).collect()
    }

    fn start(&mut self, committed: &BTreeSet<(u32, u16)>) -> (usize, usize) {
        let actuators = self.actuators;
        let is_committed = |p: usize| (0..actuators).all(|a| committed.contains(&(p as u32, a as u16)));
        self.main = self.path.points.iter().copied().filter(|&p| !is_committed(p)).collect();
        let total = self.path.points.len();
        (total, total - self.main.len())
    }

    fn setup(&mut self, instruments: &Instruments<'_>) -> Result<ScanProcessor, RecipeError> {
        let fs = instruments.daq_rate_hz();
        let protocol = &self.cfg.protocol;
        let sweep = excitation(&protocol.sweep, fs)?;
        let deconv = DeconvConfig { sample_rate_hz: fs, ..protocol.deconv };
        // One decoder for the run: the sequential path decodes each actuator's acquisition with it as it comes.
        let decoder = protocol.decoder(self.actuators, &deconv)?;
        let simultaneous = if protocol.is_simultaneous() {
            let sim = Simultaneous::new(instruments, protocol, &deconv, self.calibration)?;
            self.record = record_samples_for(sim.playback.daq_len, fs);
            Some(sim)
        } else {
            let (first, playbacks) = build_playbacks(instruments, &sweep, protocol, &deconv, self.calibration)?;
            self.record = record_samples(&first, fs);
            self.playbacks = playbacks;
            if protocol.adaptive.is_some() {
                self.extra = Some(ExtraShots::new(sweep, deconv, self.calibration));
            }
            None
        };
        self.fs = fs;
        self.ir_len = deconv.ir_len;
        let volts_per_fs = instruments.rig.wiring.loopback_volts_per_full_scale;
        let gates = Gates { min_snr_db: self.cfg.min_snr_db, max_drift_ppm: self.cfg.max_drift_ppm, volts_per_fs };
        Ok(ScanProcessor { decoder, simultaneous, gates })
    }

    fn reference(&self) -> Option<ReferenceSpec> {
        Some(ReferenceSpec {
            points: self.path.points.clone(),
            protocol: self.cfg.protocol.clone(),
            filters: self.calibration.map(|c| c.filters.clone()),
            limit_db: self.cfg.recovery.reference_limit_db,
            min_snr_db: self.cfg.min_snr_db,
            retry: RetryPolicy { max_attempts: self.cfg.max_attempts },
        })
    }

    /// The path's points first; deferred points once the path is done and nothing is in flight (a point in flight
    /// may yet be deferred, and re-visits follow the order of deferral).
    fn next(&mut self, in_flight: bool) -> Next<Vec<usize>> {
        if let Some(point) = self.main.pop_front() {
            return Next::Step(self.visit(point));
        }
        if in_flight {
            return Next::Wait;
        }
        match self.book.deferred.pop_front() {
            Some(point) => Next::Step(self.visit(point)),
            None => Next::Done,
        }
    }

    fn record(
        &mut self,
        step: &Step<Vec<usize>>,
        aimed: Option<Aimed>,
        processor: &ScanProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<Job>, RecipeError> {
        let aimed = aimed.ok_or_else(|| RecipeError::Internal("a scan step without aiming".into()))?;
        self.record_point(step.unit, &step.detail, aimed, processor, lab)
    }

    fn settle(&mut self, processed: Processed) -> Result<Verdict, RecipeError> {
        let Processed { point, aimed, outcomes } = processed;
        match self.book.settle(point, aimed, outcomes)? {
            Settled::Commit(rows) => {
                let records = point_records(&self.path.grid, point, rows, self.ir_len, self.fs, now_unix_us())?;
                let mut worst = Status::Valid;
                let mut snrs = Vec::new();
                for (record, status) in &records {
                    snrs.extend(record.meta.snr_db);
                    if severity(*status) > severity(worst) {
                        worst = *status;
                    }
                    *self.statuses.entry(status.as_str()).or_default() += 1;
                }
                let records = records.into_iter().map(|(r, _)| r).collect();
                Ok(Verdict::Commit { unit: point, records, status: worst, snr_db: median(&mut snrs) })
            }
            Settled::Deferred { visit, reasons } => {
                let reasons = reasons.join("; ");
                tracing::info!(point, visit, %reasons, "point deferred");
                Ok(Verdict::Continue { retry: Some((point, visit, format!("deferred: {reasons}"))) })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plans::scan::points::Problem;
    use crate::plans::scan::points::tests::measured;

    const HERE: Aimed = Aimed { x_m: 0.0, y_m: 0.0, level: 1.0 };

    fn step_unit(next: Next<Vec<usize>>) -> (usize, u32, Vec<usize>) {
        let Next::Step(step) = next else { panic!("a step, got {next:?}") };
        (step.unit, step.aim.map_or(u32::MAX, |a| a.visit), step.detail)
    }

    #[test]
    fn the_path_runs_ahead_of_results_and_deferred_points_wait_until_nothing_is_in_flight() {
        let grid = GridSpec { nx: 3, ny: 1, spacing_m: 0.01, origin_x_m: 0.0, origin_y_m: 0.0 };
        let plan = ScanPoints { grid, points: vec![0, 1, 2] };
        let cfg = ScanConfig::default();
        let mut scan = ScanPlan::new(&plan, None, &cfg, 2);
        // What `setup` sets from the rig.
        scan.fs = 24_000.0;
        // Point 0 committed by an earlier run (both actuators); point 1 half committed is measured again whole.
        assert_eq!(scan.start(&BTreeSet::from([(0, 0), (0, 1), (1, 0)])), (3, 1));
        assert_eq!(step_unit(scan.next(false)), (1, 0, vec![0, 1]));
        // The next path point needs no result: it is handed out while point 1 is in flight.
        assert_eq!(step_unit(scan.next(true)), (2, 0, vec![0, 1]));
        let low = |a| (a, Some(measured(0.1, 5.0)), Some(Problem::LowSnr(5.0)));
        let good = |a| (a, Some(measured(1.0, 40.0)), None);
        let verdict = scan.settle(Processed { point: 1, aimed: HERE, outcomes: vec![good(0), low(1)] }).unwrap();
        assert!(matches!(verdict, Verdict::Continue { retry: Some((1, 1, _)) }), "{verdict:?}");
        // Deferred point 1 waits while point 2 is in flight (2 may be deferred too, and re-visits keep order).
        assert_eq!(scan.next(true), Next::Wait);
        let Verdict::Commit { unit, status, .. } =
            scan.settle(Processed { point: 2, aimed: HERE, outcomes: vec![good(0), good(1)] }).unwrap()
        else {
            panic!("point 2 commits")
        };
        assert_eq!((unit, status), (2, Status::Valid));
        // The re-visit: only the failing actuator, on visit 1 (nudged).
        assert_eq!(step_unit(scan.next(false)), (1, 1, vec![1]));
        assert_eq!(scan.next(true), Next::Wait);
        let Verdict::Commit { status, records, .. } =
            scan.settle(Processed { point: 1, aimed: HERE, outcomes: vec![good(1)] }).unwrap()
        else {
            panic!("point 1 commits")
        };
        assert_eq!((status, records.len()), (Status::Valid, 2));
        assert_eq!(scan.next(false), Next::Done);
        assert_eq!(scan.statuses.get("valid"), Some(&4));
    }
}

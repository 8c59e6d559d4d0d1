//! The engine with a plan of its own (not calibrate, not scan): the order of the engine's calls (the next step
//! recorded while the last is processed, results settled in order), commits and resume through `Plan::start`, a
//! stop honoured only between units, and a plan that waits with nothing in flight.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};

use common::{lab_and_plan, metamaterial, output};
use metaplate_dsp::sweep::SweepSpec;
use metaplate_recipes::drive::{DrivePlayback, excitation};
use metaplate_recipes::engine::aim::{AimPolicy, Aimed};
use metaplate_recipes::engine::plan::{AimAt, Lab, Next, Plan, Processor, Settings, Step, Verdict};
use metaplate_recipes::engine::run::run;
use metaplate_recipes::engine::session::{Instruments, RecoveryPolicy};
use metaplate_recipes::{RecipeError, RetryPolicy, RunControl, Silent};
use metaplate_store::{Dataset, DatasetMeta, GridSpec, IrMeta, IrRecord, Status};

/// Every call the engine made, in order.
type Log = Arc<Mutex<Vec<String>>>;

/// A plan of units at `points` (grid indices, the units' numbers); each unit is `steps` steps (a stop must wait for its last), each
/// step one short sweep on actuator 0; a unit commits one row holding the RMS velocity of its steps.
struct Rms {
    grid: GridSpec,
    points: Vec<usize>,
    steps: u32,
    todo: std::collections::VecDeque<usize>,
    /// The unit whose steps are being handed out, and how many were.
    current: Option<(usize, u32)>,
    /// Per unit, the RMS of its settled steps.
    values: std::collections::BTreeMap<usize, Vec<f64>>,
    sweep: Vec<f64>,
    /// Wait for the result of each step before taking the next (as a calibration does).
    serial: bool,
    /// Press "Ctrl-C" (stop level 1) while recording the first step.
    stop_in_first_step: Option<RunControl>,
    log: Log,
}

struct RmsProcessor {
    log: Log,
}

impl Processor for RmsProcessor {
    type Recorded = (usize, Vec<f64>);
    type Processed = (usize, f64);

    fn process(&self, (unit, velocity_v): (usize, Vec<f64>)) -> (usize, f64) {
        self.log.lock().unwrap().push(format!("process {unit}"));
        let rms = (velocity_v.iter().map(|v| v * v).sum::<f64>() / velocity_v.len() as f64).sqrt();
        (unit, rms)
    }
}

impl Plan for Rms {
    type Detail = u32;
    type Processor = RmsProcessor;

    fn meta(&self, out: &metaplate_recipes::Output) -> DatasetMeta {
        DatasetMeta::new("rms", serde_json::Map::new(), out.scene.clone(), "test", 0, self.grid)
    }

    fn start(&mut self, committed: &BTreeSet<(u32, u16)>) -> (usize, usize) {
        self.todo = self.points.iter().copied().filter(|u| !committed.contains(&(*u as u32, 0))).collect();
        (self.points.len(), self.points.len() - self.todo.len())
    }

    fn setup(&mut self, instruments: &Instruments<'_>) -> Result<RmsProcessor, RecipeError> {
        let sweep = SweepSpec { f1_hz: 100.0, f2_hz: 400.0, duration_s: 0.05, ..SweepSpec::default() };
        self.sweep = excitation(&sweep, instruments.daq_rate_hz())?;
        Ok(RmsProcessor { log: self.log.clone() })
    }

    fn next(&mut self, in_flight: bool) -> Next<u32> {
        if self.serial && in_flight {
            return Next::Wait;
        }
        let (unit, step) = match &mut self.current {
            Some((unit, taken)) if *taken < self.steps => {
                *taken += 1;
                (*unit, *taken - 1)
            }
            _ => match self.todo.pop_front() {
                Some(unit) => {
                    self.current = Some((unit, 1));
                    (unit, 0)
                }
                None if in_flight => return Next::Wait,
                None => return Next::Done,
            },
        };
        let aim = (step == 0).then(|| AimAt { position_m: self.grid.position_m(unit), visit: 0 });
        Next::Step(Step { unit, aim, detail: step })
    }

    fn mid_unit(&self) -> bool {
        self.current.is_some_and(|(unit, _)| self.values.get(&unit).is_none_or(|v| v.len() < self.steps as usize))
    }

    fn record(
        &mut self,
        step: &Step<u32>,
        aimed: Option<Aimed>,
        _processor: &RmsProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<(usize, Vec<f64>)>, RecipeError> {
        assert_eq!(aimed.is_some(), step.detail == 0, "the engine aims exactly when asked");
        self.log.lock().unwrap().push(format!("record {} step {}", step.unit, step.detail));
        if let Some(control) = self.stop_in_first_step.take() {
            control.request_stop();
        }
        let fs = lab.daq_rate_hz();
        let playback = DrivePlayback::new(&self.sweep, 1, 240, None)?;
        let buffers = playback.audio_buffers(lab.wiring(), 0, fs)?;
        let Some(acquired) = lab.acquire(&buffers, playback.drive.len(), step.unit)? else { return Ok(None) };
        Ok(Some((step.unit, acquired.acquisition.recording.velocity_v)))
    }

    fn settle(&mut self, (unit, rms): (usize, f64)) -> Result<Verdict, RecipeError> {
        self.log.lock().unwrap().push(format!("settle {unit}"));
        let values = self.values.entry(unit).or_default();
        values.push(rms);
        if values.len() < self.steps as usize {
            return Ok(Verdict::Continue { retry: None });
        }
        let (ix, iy) = self.grid.indices(unit);
        let meta =
            IrMeta { status: Some(Status::Valid), ..IrMeta::at_grid(&self.grid, ix as u32, iy as u32, 0, 24_000.0)? };
        let ir = values.iter().map(|v| *v as f32).collect();
        Ok(Verdict::Commit { unit, records: vec![IrRecord { meta, ir }], status: Status::Valid, snr_db: None })
    }
}

/// A fresh mock lab of the built-in metamaterial scene (a restarted program) and its 7 x 5 scan plan (the lab
/// shares the other recipe tests' cached Green's functions).
fn lab() -> (metaplate_lab::MockLab, metaplate_recipes::ScanPoints) {
    lab_and_plan(&metamaterial(), 7, 5)
}

fn settings() -> Settings {
    Settings {
        max_velocity_m_s: 0.1,
        retry: RetryPolicy { max_attempts: 3 },
        aim: AimPolicy::default(),
        seed: 1,
        recovery: RecoveryPolicy::default(),
    }
}

/// A plan of the first `units` points of the 7 x 5 scan plan of [`lab`]'s scene, and its call log.
fn rms(units: usize, steps: u32, serial: bool) -> (Rms, Log) {
    let (_, scan_plan) = lab();
    let log = Log::default();
    let plan = Rms {
        grid: scan_plan.grid,
        points: scan_plan.points[..units].to_vec(),
        steps,
        todo: Default::default(),
        current: None,
        values: Default::default(),
        sweep: Vec::new(),
        serial,
        stop_in_first_step: None,
        log: log.clone(),
    };
    (plan, log)
}

#[test]
fn the_next_step_is_recorded_while_the_last_is_processed_and_results_settle_in_order() {
    let scene = metamaterial();
    let mut rig = lab().0.rig().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (mut plan, log) = rms(3, 1, false);
    let points = plan.points.clone();
    let report =
        run(&mut plan, settings(), &mut rig, &output(dir.path(), &scene, false), &RunControl::new(), &mut Silent)
            .unwrap();
    assert_eq!((report.committed_now, report.committed, report.total), (3, 3, 3));
    let log = log.lock().unwrap().clone();
    let at = |entry: String| log.iter().position(|e| *e == entry).unwrap_or_else(|| panic!("{entry} in {log:?}"));
    // The second point is recorded before the first one's result is settled (the overlap), and settles follow the
    // steps' order.
    let [p0, p1, p2] = [points[0], points[1], points[2]];
    assert!(at(format!("record {p1} step 0")) < at(format!("settle {p0}")), "{log:?}");
    assert!(at(format!("settle {p0}")) < at(format!("settle {p1}")), "{log:?}");
    assert!(at(format!("settle {p1}")) < at(format!("settle {p2}")), "{log:?}");
    let dataset = Dataset::open(dir.path()).unwrap();
    assert_eq!(dataset.len(), 3);
    // The plate moves under every point: a positive RMS velocity committed at each.
    assert!(points.iter().all(|&p| dataset.ir(p as u32, 0).is_some_and(|ir| ir.len() == 1 && ir[0] > 0.0)));
}

#[test]
fn a_stop_waits_for_the_unit_in_progress_and_a_resume_starts_after_it() {
    let scene = metamaterial();
    let dir = tempfile::tempdir().unwrap();
    // Three steps per unit, each waiting for the last; a stop requested during the first step is honoured at the
    // unit's end: its three steps are recorded and committed, the next unit is never started.
    let control = RunControl::new();
    let (mut plan, log) = rms(3, 3, true);
    plan.stop_in_first_step = Some(control.clone());
    let points = plan.points.clone();
    let mut rig = lab().0.rig().unwrap();
    let err =
        run(&mut plan, settings(), &mut rig, &output(dir.path(), &scene, false), &control, &mut Silent).unwrap_err();
    assert!(matches!(err, RecipeError::Interrupted { committed: 1 }), "{err}");
    let log = log.lock().unwrap().clone();
    assert_eq!(log.iter().filter(|e| e.starts_with("record")).count(), 3, "{log:?}");
    assert!(!log.iter().any(|e| e.starts_with(&format!("record {} ", points[1]))), "{log:?}");
    // The resume measures the two units left.
    let (mut plan, _) = rms(3, 3, true);
    let mut rig = lab().0.rig().unwrap();
    let report =
        run(&mut plan, settings(), &mut rig, &output(dir.path(), &scene, true), &RunControl::new(), &mut Silent)
            .unwrap();
    assert_eq!((report.committed_now, report.committed), (2, 3));
    let dataset = Dataset::open(dir.path()).unwrap();
    assert!(points.iter().all(|&p| dataset.ir(p as u32, 0).is_some_and(|ir| ir.len() == 3)));
}

/// A plan that asks to wait when nothing is in flight.
struct Stuck;

impl Plan for Stuck {
    type Detail = ();
    type Processor = RmsProcessor;

    fn meta(&self, out: &metaplate_recipes::Output) -> DatasetMeta {
        let grid = GridSpec { nx: 1, ny: 1, ..metamaterial().grid };
        DatasetMeta::new("stuck", serde_json::Map::new(), out.scene.clone(), "test", 0, grid)
    }
    fn start(&mut self, _: &BTreeSet<(u32, u16)>) -> (usize, usize) {
        (1, 0)
    }
    fn setup(&mut self, _: &Instruments<'_>) -> Result<RmsProcessor, RecipeError> {
        Ok(RmsProcessor { log: Log::default() })
    }
    fn next(&mut self, _: bool) -> Next<()> {
        Next::Wait
    }
    fn record(
        &mut self,
        _: &Step<()>,
        _: Option<Aimed>,
        _: &RmsProcessor,
        _: &mut Lab<'_, '_>,
    ) -> Result<Option<(usize, Vec<f64>)>, RecipeError> {
        unreachable!("never asked to record")
    }
    fn settle(&mut self, _: (usize, f64)) -> Result<Verdict, RecipeError> {
        unreachable!("nothing is ever in flight")
    }
}

#[test]
fn a_plan_waiting_with_nothing_in_flight_is_an_internal_error_not_a_hang() {
    let scene = metamaterial();
    let mut rig = lab().0.rig().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let err =
        run(&mut Stuck, settings(), &mut rig, &output(dir.path(), &scene, false), &RunControl::new(), &mut Silent)
            .unwrap_err();
    assert!(matches!(err, RecipeError::Internal(_)), "{err}");
}

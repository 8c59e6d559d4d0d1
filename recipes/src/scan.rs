//! The grid scan: every unmasked point, every actuator, the compensated excitation, deconvolution, quality gates,
//! bounded retries, a deferred re-measure queue, and one commit per point.
//!
//! Acquisition (the instruments, on this thread) and processing (deconvolution, on a worker thread) overlap: point
//! k is processed while point k + 1 is acquired, so the instruments set the pace. Results come back in the order
//! the points were sent, so commits are in a deterministic order.
//!
//! Per point and actuator, each acquisition is checked at once (gaps, underruns, clipping: repeated up to
//! `max_attempts` times), then processed and gated (SNR, clock drift). A point with an actuator that fails a gate is
//! deferred to the end of the run and re-measured there (only the failing actuators, the beam nudged), up to
//! `deferred_visits` times; then it is committed with a status saying what went wrong. No point is dropped.

use std::collections::{BTreeMap, VecDeque};
use std::sync::mpsc;

use metaplate_core::grid::GridSpec;
use metaplate_core::rig::Rig;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::pipeline::{ChannelResult, PreparedLayout, RepetitionLayout};
use metaplate_dsp::protocol::Protocol;
use metaplate_dsp::sweep::SweepSpec;
use metaplate_store::{DatasetMeta, IrMeta, IrRecord, Status};
use serde_json::{Map, Value, json};

use crate::aim::{AimPolicy, Aimed, aim};
use crate::calibrate::{Calibration, now_unix_us, record_samples};
use crate::control::{Event, Observer, RunControl};
use crate::dataset::{self, Output};
use crate::error::RecipeError;
use crate::instruments::{Acquisition, Instruments, RecoveryPolicy};
use crate::protocol::{Adaptive, Excitation};
use crate::quality::median;
use crate::signals::{AudioPlayback, Playback, SimultaneousPlayback, excitation};

/// Recipe name in the manifest.
pub const RECIPE: &str = "scan";

/// The excitation and its processing.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanProtocol {
    /// Name recorded in the manifest (`paper`, `quick`).
    pub name: String,
    /// One period of the excitation (its `sample_rate_hz` is replaced by the DAQ's).
    pub sweep: SweepSpec,
    /// Periods played back to back.
    pub repetitions: usize,
    /// Deconvolution (its `sample_rate_hz` is replaced by the DAQ's).
    pub deconv: DeconvConfig,
    /// How the actuators are played (one at a time, or all at once).
    pub excitation: Excitation,
    /// Averaging until a target SNR (simultaneous protocols only); `None`: one round.
    pub adaptive: Option<Adaptive>,
}

impl ScanProtocol {
    /// The paper's: a 3 s linear sweep 62..625 Hz, 5 repetitions, [`DeconvConfig::paper`] (0.5 s responses).
    pub fn paper() -> Self {
        Self {
            name: "paper".into(),
            sweep: SweepSpec::default(),
            repetitions: 5,
            deconv: DeconvConfig::paper(),
            excitation: Excitation::Sequential,
            adaptive: None,
        }
    }

    /// For tests and quick looks: a 1 s sweep 62..625 Hz, 2 repetitions, the paper's deconvolution (0.5 s
    /// responses fit the 1 s period). 7.5 times less playing than the paper's; the SNR drops by about 10 dB (the
    /// sweep energy per period falls 3 times and 2 periods are averaged instead of 5).
    pub fn quick() -> Self {
        Self {
            name: "quick".into(),
            sweep: SweepSpec { duration_s: 1.0, ..SweepSpec::default() },
            repetitions: 2,
            deconv: DeconvConfig::paper(),
            excitation: Excitation::Sequential,
            adaptive: None,
        }
    }

    /// A protocol by name: `paper`, `quick`, or one with settings such as `hadamard:1x2` (the syntax and every
    /// protocol's assumptions: [`crate::protocol`]).
    ///
    /// # Errors
    /// [`RecipeError::Config`] for an unknown name or bad settings.
    pub fn by_name(name: &str) -> Result<Self, RecipeError> {
        crate::protocol::parse(name)
    }

    /// Seconds of playback per actuator and point (repetitions and tail), at nominal rates.
    pub fn seconds_per_actuator(&self) -> f64 {
        self.repetitions as f64 * self.sweep.duration_s + self.deconv.ir_len as f64 / self.deconv.sample_rate_hz
    }
}

/// What a scan does, besides where.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanConfig {
    /// Excitation and processing.
    pub protocol: ScanProtocol,
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
            protocol: ScanProtocol::paper(),
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
                "excitation": match p.excitation {
                    Excitation::Sequential => json!({ "kind": "sequential" }),
                    Excitation::Hadamard => json!({ "kind": "hadamard" }),
                    Excitation::Interleaved { slot_s } => json!({ "kind": "interleaved", "slot_s": slot_s }),
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

/// Why a row is not (yet) good.
#[derive(Debug, Clone, PartialEq)]
enum Problem {
    Clipped,
    Gap,
    Processing(String),
    LowSnr(f64),
    Drift(f64),
    /// An adaptive protocol's target SNR, not reached within its rounds (final: not deferred).
    Unreached {
        snr_db: Option<f64>,
        target_db: f64,
        rounds: usize,
    },
}

impl Problem {
    /// The status a row ends with when this is its last problem.
    fn status(&self) -> Status {
        match self {
            Problem::Clipped => Status::Overrange,
            Problem::Gap | Problem::Processing(_) => Status::Dropout,
            Problem::LowSnr(_) | Problem::Drift(_) | Problem::Unreached { .. } => Status::Failed,
        }
    }

    /// Whether a re-measure is pointless (the problem already is the outcome of a bounded effort).
    fn is_final(&self) -> bool {
        matches!(self, Problem::Unreached { .. })
    }

    fn describe(&self) -> String {
        match self {
            Problem::Clipped => "clipped".into(),
            Problem::Gap => "gap or underrun in the recording".into(),
            Problem::Processing(e) => format!("processing failed: {e}"),
            Problem::LowSnr(snr) => format!("SNR {snr:.1} dB below the limit"),
            Problem::Drift(ppm) => format!("clock drift {ppm:.0} ppm beyond the limit"),
            Problem::Unreached { snr_db, target_db, rounds } => format!(
                "SNR {} below the adaptive target {target_db:.1} dB after {rounds} rounds",
                snr_db.map_or("unknown".to_string(), |s| format!("{s:.1} dB"))
            ),
        }
    }
}

/// One actuator's row at a point, across visits.
#[derive(Debug, Clone)]
struct Row {
    acquisitions: u32,
    /// Best result so far: IR (m/s per full scale), SNR, where.
    result: Option<(Vec<f64>, Option<f64>, Aimed)>,
    problem: Option<Problem>,
    done: bool,
}

/// A point being measured.
#[derive(Debug, Clone)]
struct PointState {
    visit: u32,
    rows: Vec<Row>,
}

/// One acquisition sent for processing.
struct Channel {
    actuator: usize,
    acquisition: Acquisition,
    problem: Option<Problem>,
}

struct Job {
    point: usize,
    aimed: Aimed,
    work: Work,
}

/// What a job carries to the worker.
enum Work {
    /// Sequential: one acquisition per pending actuator.
    Channels(Vec<Channel>),
    /// Simultaneous: one acquisition per shot, for the pending actuators; the worst acquisition problem.
    Shots { pending: Vec<usize>, acquisitions: Vec<Acquisition>, problem: Option<Problem> },
    /// Already processed (adaptive protocols decide between rounds, so they decode as they acquire).
    Done(Vec<Outcome>),
}

/// One processed channel: actuator, response (m/s per full scale) and SNR when processing succeeded, problem.
type Outcome = (usize, Option<(Vec<f64>, Option<f64>)>, Option<Problem>);

struct Processed {
    point: usize,
    aimed: Aimed,
    /// Per channel: actuator, response (m/s per full scale) and SNR when processing succeeded, problem if any.
    outcomes: Vec<Outcome>,
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
    );
    let mut opened = dataset::open(out, meta, control)?;
    let is_committed = |p: usize| (0..actuators).all(|a| opened.committed.contains(&(p as u32, a as u16)));
    let todo: VecDeque<usize> = plan.points.iter().copied().filter(|&p| !is_committed(p)).collect();
    let total = plan.points.len();
    let done_before = total - todo.len();
    observer.event(&Event::Started { total, done: done_before });

    let clock = rig.clock.clone();
    let t0 = clock.now_s();
    let mut instruments = Instruments::new(rig, cfg.max_velocity_m_s, cfg.recovery, control, observer)?;
    let fs = instruments.daq_rate_hz();
    let volts_per_fs = instruments.rig.wiring.loopback_volts_per_full_scale;
    let protocol = &cfg.protocol;
    let sweep = excitation(&protocol.sweep, fs)?;
    let deconv = DeconvConfig { sample_rate_hz: fs, ..protocol.deconv };
    let layout = RepetitionLayout { excitation: sweep.clone(), repetitions: protocol.repetitions };
    let prepared = PreparedLayout::new(&layout, &deconv)?;
    let (playbacks, simultaneous, record) = if protocol.is_simultaneous() {
        let sim = Simultaneous::new(&instruments, protocol, &deconv, calibration)?;
        // As `record_samples`: all of the playback plus 0.1 s for the audio interface's output latency.
        let record = sim.playback.daq_len + (0.1 * fs).ceil() as usize;
        (Vec::new(), Some(sim), record)
    } else {
        let playbacks = build_playbacks(&instruments, &sweep, protocol, &deconv, calibration)?;
        let record = record_samples(&playbacks.0, fs);
        (playbacks.1, None, record)
    };
    let gates = Gates { min_snr_db: cfg.min_snr_db, max_drift_ppm: cfg.max_drift_ppm, volts_per_fs };

    let mut ctx = Context {
        plan,
        cfg,
        playbacks: &playbacks,
        simultaneous: simultaneous.as_ref(),
        gates: &gates,
        actuators,
        record,
        states: BTreeMap::new(),
        deferred: VecDeque::new(),
        summary: ScanSummary { total, committed: done_before, ..ScanSummary::default() },
        commits: 0,
        ir_len: deconv.ir_len,
        fs,
        t0,
    };
    let result = std::thread::scope(|scope| -> Result<(), RecipeError> {
        let (job_tx, job_rx) = mpsc::channel::<Job>();
        let (done_tx, done_rx) = mpsc::channel::<Processed>();
        let prepared = &prepared;
        let gates = &gates;
        let simultaneous = simultaneous.as_ref();
        scope.spawn(move || {
            for job in job_rx {
                if done_tx.send(process(job, prepared, simultaneous, gates)).is_err() {
                    break;
                }
            }
        });
        let mut reference = crate::instruments::ReferenceCheck::new(out, plan, cfg, calibration);
        let mut main = todo;
        let mut in_flight = false;
        loop {
            let next = if control.stop_requested() {
                None
            } else if let Some(p) = main.pop_front() {
                Some(p)
            } else if !in_flight {
                ctx.deferred.pop_front()
            } else {
                None
            };
            let job = match next {
                Some(point) => {
                    reference.after_recovery(&mut instruments, control, observer)?;
                    ctx.acquire_point(&mut instruments, point, control, observer)?
                }
                None => None,
            };
            if in_flight {
                let processed = done_rx
                    .recv()
                    .map_err(|_| RecipeError::Config("the processing thread stopped unexpectedly".into()))?;
                in_flight = false;
                ctx.settle(processed, &mut opened.writer, control, observer, &clock)?;
            }
            if let Some(job) = job {
                job_tx.send(job).map_err(|_| RecipeError::Config("the processing thread stopped".into()))?;
                in_flight = true;
            }
            if !in_flight && (control.stop_requested() || (main.is_empty() && ctx.deferred.is_empty())) {
                break;
            }
        }
        Ok(())
    });
    result?;
    ctx.summary.clock_s = clock.now_s() - t0;
    let summary = ctx.summary;
    if summary.committed < total {
        observer.event(&Event::Stopped { done: summary.committed });
        return Err(RecipeError::Interrupted { committed: summary.committed });
    }
    observer.event(&Event::Finished { done: summary.committed });
    Ok(summary)
}

type Playbacks = (Playback, Vec<AudioPlayback>);

/// Each actuator's playback at the audio rate (built once for the whole scan), and one at the DAQ rate for the
/// recording length (all have the same length).
fn build_playbacks(
    instruments: &Instruments<'_>,
    sweep: &[f64],
    protocol: &ScanProtocol,
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
        let playback = Playback::new(sweep, protocol.repetitions, tail, filter)?;
        at_audio.push(playback.at_audio_rate(&instruments.rig.wiring, a, fs)?);
        first.get_or_insert(playback);
    }
    let first = first.ok_or_else(|| RecipeError::Config("no actuator is wired".into()))?;
    Ok((first, at_audio))
}

struct Gates {
    min_snr_db: f64,
    max_drift_ppm: f64,
    volts_per_fs: f64,
}

/// Deconvolves and gates every channel of a job (on the worker thread).
fn process(job: Job, prepared: &PreparedLayout, simultaneous: Option<&Simultaneous>, gates: &Gates) -> Processed {
    let outcomes = match (job.work, simultaneous) {
        (Work::Channels(channels), _) => process_channels(channels, prepared, gates),
        (Work::Shots { pending, acquisitions, problem }, Some(sim)) => {
            let decoded = sim.decode(&acquisitions, gates).map(|results| results.into_iter().map(Some).collect());
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
fn process_channels(channels: Vec<Channel>, prepared: &PreparedLayout, gates: &Gates) -> Vec<Outcome> {
    channels
        .into_iter()
        .map(|ch| {
            let acq = &ch.acquisition;
            // The response is kept even when a gate fails: it is committed if no later visit does better.
            let (result, gate) = match prepared.process_channel(&acq.velocity_v, &acq.loopback_v) {
                Err(e) => (None, Some(Problem::Processing(e.to_string()))),
                Ok(r) => {
                    let to_units = acq.scale.m_s_per_v * gates.volts_per_fs;
                    let ir: Vec<f64> = r.ir.iter().map(|v| v * to_units).collect();
                    let gate = if r.drift_ppm.abs() > gates.max_drift_ppm {
                        Some(Problem::Drift(r.drift_ppm))
                    } else {
                        r.snr_db.filter(|s| *s < gates.min_snr_db).map(Problem::LowSnr)
                    };
                    (Some((ir, r.snr_db)), gate)
                }
            };
            // An acquisition problem (clipping, a gap) explains a gate failure better than the gate itself.
            let problem = ch.problem.or(gate);
            (ch.actuator, result, problem)
        })
        .collect()
}

/// Whether an acquisition is usable: whole (no gap or underrun) and unclipped.
fn acquisition_problem(acq: &Acquisition) -> Option<Problem> {
    if !acq.is_whole() {
        Some(Problem::Gap)
    } else if acq.clipped {
        Some(Problem::Clipped)
    } else {
        None
    }
}

/// A simultaneous protocol ready to play and decode.
struct Simultaneous {
    /// The DSP protocol (decoding at the DAQ rate).
    protocol: Protocol,
    /// Deconvolution at the DAQ rate.
    deconv: DeconvConfig,
    playback: SimultaneousPlayback,
    adaptive: Option<Adaptive>,
}

impl Simultaneous {
    fn new(
        instruments: &Instruments<'_>,
        protocol: &ScanProtocol,
        deconv: &DeconvConfig,
        calibration: Option<&Calibration>,
    ) -> Result<Self, RecipeError> {
        let wiring = &instruments.rig.wiring;
        let fs = instruments.daq_rate_hz();
        let dsp = protocol.dsp();
        dsp.validate(wiring.actuator_channels.len(), deconv.ir_len as f64 / fs)?;
        let fir_len = calibration.map_or(0, |c| c.filters.iter().map(|f| f.taps.len()).max().unwrap_or(0));
        // The tail holds the last response (ir_len) and the filter's own length, as in the sequential playback.
        let filters = calibration.map(|c| c.filters.as_slice());
        let playback = SimultaneousPlayback::new(&dsp, wiring, fs, deconv.ir_len + fir_len, filters)?;
        Ok(Self { protocol: dsp, deconv: *deconv, playback, adaptive: protocol.adaptive })
    }

    /// Every actuator's response (m/s per full scale of its compensated drive) and SNR from one round of shots.
    fn decode(&self, acquisitions: &[Acquisition], gates: &Gates) -> Result<Vec<ChannelResult>, Problem> {
        // Velocity in m/s per loopback full scale, so that the responses come out in m/s per full scale.
        let velocities: Vec<Vec<f64>> = acquisitions
            .iter()
            .map(|a| a.velocity_v.iter().map(|v| v * a.scale.m_s_per_v * gates.volts_per_fs).collect())
            .collect();
        let pairs: Vec<(&[f64], &[f64])> =
            velocities.iter().zip(acquisitions).map(|(v, a)| (v.as_slice(), a.loopback_v.as_slice())).collect();
        let mut results = self
            .protocol
            .decode(self.playback.response_gain.len(), &pairs, &self.deconv)
            .map_err(|e| Problem::Processing(e.to_string()))?;
        for (r, gain) in results.iter_mut().zip(&self.playback.response_gain) {
            r.ir.iter_mut().for_each(|v| *v *= gain);
        }
        Ok(results)
    }

    /// Outcomes of the pending actuators from decoded results (or why there are none), gated like sequential ones;
    /// an acquisition problem explains a gate failure better than the gate itself.
    fn outcomes(
        &self,
        pending: &[usize],
        decoded: Result<Vec<Option<ChannelResult>>, Problem>,
        problem: Option<Problem>,
        gates: &Gates,
    ) -> Vec<Outcome> {
        pending
            .iter()
            .map(|&a| match &decoded {
                Err(e) => (a, None, problem.clone().or_else(|| Some(e.clone()))),
                Ok(results) => match results.get(a).cloned().flatten() {
                    None => (a, None, problem.clone().or(Some(Problem::Processing(format!("no response {a}"))))),
                    Some(r) => {
                        let gate = if r.drift_ppm.abs() > gates.max_drift_ppm {
                            Some(Problem::Drift(r.drift_ppm))
                        } else {
                            r.snr_db.filter(|s| *s < gates.min_snr_db).map(Problem::LowSnr)
                        };
                        (a, Some((r.ir, r.snr_db)), problem.clone().or(gate))
                    }
                },
            })
            .collect()
    }
}

/// Coherent average of adaptive rounds, with the noise of the average from each round's SNR.
struct Averager {
    count: usize,
    /// Per actuator: sum of the responses, and sum of the rounds' noise energies (`None` once a round had none).
    sums: Vec<(Vec<f64>, Option<f64>)>,
    drift_ppm: f64,
}

impl Averager {
    fn new(actuators: usize) -> Self {
        Self { count: 0, sums: vec![(Vec::new(), Some(0.0)); actuators], drift_ppm: 0.0 }
    }

    fn add(&mut self, results: &[ChannelResult]) {
        self.count += 1;
        for ((sum, noise), r) in self.sums.iter_mut().zip(results) {
            sum.resize(r.ir.len(), 0.0);
            sum.iter_mut().zip(&r.ir).for_each(|(s, v)| *s += v);
            // A round's noise energy from its SNR: energy / 10^(snr/10).
            *noise = noise.zip(r.snr_db).map(|(n, snr)| n + energy(&r.ir) / 10f64.powf(snr / 10.0));
        }
        self.drift_ppm = self.drift_ppm.max(results.iter().fold(0.0f64, |m, r| m.max(r.drift_ppm.abs())));
    }

    /// The averaged responses, with the average's SNR: its energy over the mean noise energy divided by the count
    /// (independent noise averages down by the number of rounds).
    fn averaged(&self) -> Vec<Option<ChannelResult>> {
        let n = self.count.max(1) as f64;
        (0..self.sums.len())
            .map(|a| {
                let (sum, _) = &self.sums[a];
                let ir: Vec<f64> = sum.iter().map(|v| v / n).collect();
                let snr_db = self.snr_db(&[a]).into_iter().next().flatten();
                Some(ChannelResult { ir, snr_db, drift_ppm: self.drift_ppm, latency_samples: 0.0 })
            })
            .collect()
    }

    /// SNR of the average for each of `actuators`, dB; `None` where unknown.
    fn snr_db(&self, actuators: &[usize]) -> Vec<Option<f64>> {
        let n = self.count.max(1) as f64;
        actuators
            .iter()
            .map(|&a| {
                let (sum, noise) = self.sums.get(a)?;
                let signal = energy(sum) / (n * n);
                let noise = (*noise)? / n / n;
                (noise > 0.0 && signal > 0.0).then(|| 10.0 * (signal / noise).log10())
            })
            .collect()
    }
}

fn energy(signal: &[f64]) -> f64 {
    signal.iter().map(|x| x * x).sum()
}

struct Context<'p> {
    plan: &'p ScanPlan,
    cfg: &'p ScanConfig,
    playbacks: &'p [AudioPlayback],
    simultaneous: Option<&'p Simultaneous>,
    gates: &'p Gates,
    actuators: usize,
    record: usize,
    states: BTreeMap<usize, PointState>,
    deferred: VecDeque<usize>,
    summary: ScanSummary,
    commits: usize,
    ir_len: usize,
    fs: f64,
    t0: f64,
}

impl Context<'_> {
    /// Aims at `point` and records every actuator still to measure there; `None` if abandoned on request.
    fn acquire_point(
        &mut self,
        instruments: &mut Instruments<'_>,
        point: usize,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Option<Job>, RecipeError> {
        let actuators = self.actuators;
        let state = self.states.entry(point).or_insert_with(|| PointState {
            visit: 0,
            rows: vec![Row { acquisitions: 0, result: None, problem: None, done: false }; actuators],
        });
        let visit = state.visit;
        let pending: Vec<usize> = (0..actuators).filter(|&a| !state.rows[a].done).collect();
        let position = self.plan.grid.position_m(point);
        let aimed = aim(instruments, position, (self.cfg.seed, point as u64, visit), &self.cfg.aim, control, observer)?;
        if let Some(sim) = self.simultaneous {
            let work = match self.acquire_simultaneous(instruments, point, &pending, sim, control, observer)? {
                Some(work) => work,
                None => return Ok(None),
            };
            return Ok(Some(Job { point, aimed, work }));
        }
        let mut channels = Vec::with_capacity(pending.len());
        for actuator in pending {
            let buffers = self.playbacks[actuator].buffers();
            let mut attempt = 0;
            let (acquisition, problem) = loop {
                if control.abandon_requested() {
                    return Ok(None);
                }
                let acq = instruments.with_recovery(control, observer, |i| i.acquire(&buffers, self.record))?;
                attempt += 1;
                let problem = acquisition_problem(&acq);
                match problem {
                    Some(p) if attempt < self.cfg.max_attempts => {
                        observer.event(&Event::Retry { unit: point, attempt, reason: p.describe() });
                    }
                    other => break (acq, other),
                }
            };
            if let Some(s) = self.states.get_mut(&point) {
                s.rows[actuator].acquisitions += attempt;
            }
            channels.push(Channel { actuator, acquisition, problem });
        }
        Ok(Some(Job { point, aimed, work: Work::Channels(channels) }))
    }

    /// Plays every shot of a simultaneous protocol at `point` (the beam already there), round after round for an
    /// adaptive one; `None` if abandoned on request.
    fn acquire_simultaneous(
        &mut self,
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
                    .ok_or_else(|| RecipeError::Config(format!("shot {shot} has no buffers")))?;
                let mut attempt = 0;
                let (acquisition, problem) = loop {
                    if control.abandon_requested() {
                        return Ok(None);
                    }
                    let acq = instruments.with_recovery(control, observer, |i| i.acquire(&buffers, self.record))?;
                    attempt += 1;
                    let problem = acquisition_problem(&acq);
                    match problem {
                        Some(p) if attempt < self.cfg.max_attempts => {
                            observer.event(&Event::Retry { unit: point, attempt, reason: p.describe() });
                            // Every actuator at once can move the plate up to `actuators` times faster than one:
                            // a clipped shot asks the vibrometer for a wider range (kept for the rest of the run;
                            // each shot is converted with its own scale, so a round may mix ranges).
                            if p == Problem::Clipped {
                                let grew = instruments.with_recovery(control, observer, |i| i.widen_range())?;
                                tracing::info!(point, grew, "clipped shot: velocity range widened");
                            }
                        }
                        other => break (acq, other),
                    }
                };
                retries += attempt - 1;
                worst = worst.or(problem);
                acquisitions.push(acquisition);
            }
            if let Some(s) = self.states.get_mut(&point) {
                for &a in pending {
                    s.rows[a].acquisitions += retries + u32::from(rounds.count == 0);
                }
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
            match sim.decode(&acquisitions, self.gates) {
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

    /// Merges processed results into the point's rows; commits the point when every row is settled, else defers it.
    fn settle(
        &mut self,
        processed: Processed,
        writer: &mut metaplate_store::DatasetWriter,
        control: &RunControl,
        observer: &mut dyn Observer,
        clock: &std::sync::Arc<dyn metaplate_core::clock::Clock>,
    ) -> Result<(), RecipeError> {
        let point = processed.point;
        let Some(state) = self.states.get_mut(&point) else {
            return Err(RecipeError::Config(format!("point {point} was processed but never acquired")));
        };
        let last_visit = state.visit >= self.cfg.deferred_visits;
        for (actuator, result, problem) in processed.outcomes {
            let row = &mut state.rows[actuator];
            if let Some((ir, snr)) = result {
                row.result = Some((ir, snr, processed.aimed));
            }
            row.done = problem.as_ref().is_none_or(Problem::is_final);
            row.problem = problem;
            if last_visit {
                row.done = true;
            }
        }
        if state.rows.iter().all(|r| r.done) {
            let state = self.states.remove(&point).unwrap_or_else(|| PointState { visit: 0, rows: Vec::new() });
            return self.commit(point, state, writer, control, observer, clock);
        }
        let reasons: Vec<String> =
            state.rows.iter().filter_map(|r| r.problem.as_ref().map(Problem::describe)).collect();
        state.visit += 1;
        if state.visit == 1 {
            self.summary.deferred += 1;
        }
        tracing::info!(point, visit = state.visit, reasons = %reasons.join("; "), "point deferred");
        observer.event(&Event::Retry {
            unit: point,
            attempt: state.visit,
            reason: format!("deferred: {}", reasons.join("; ")),
        });
        self.deferred.push_back(point);
        Ok(())
    }

    fn commit(
        &mut self,
        point: usize,
        state: PointState,
        writer: &mut metaplate_store::DatasetWriter,
        control: &RunControl,
        observer: &mut dyn Observer,
        clock: &std::sync::Arc<dyn metaplate_core::clock::Clock>,
    ) -> Result<(), RecipeError> {
        let (ix, iy) = self.plan.grid.indices(point);
        let measured_at = now_unix_us();
        let mut records = Vec::with_capacity(state.rows.len());
        let mut snrs = Vec::new();
        let mut worst = Status::Valid;
        for (actuator, row) in state.rows.into_iter().enumerate() {
            let status = match &row.problem {
                Some(p) => p.status(),
                None if row.acquisitions > 1 => Status::ReMeasured,
                None => Status::Valid,
            };
            let (ir, snr_db, x_m, y_m) = match row.result {
                Some((ir, snr, aimed)) => (ir, snr, aimed.x_m, aimed.y_m),
                None => {
                    let (x, y) = self.plan.grid.position_m(point);
                    (vec![0.0; self.ir_len], None, x, y)
                }
            };
            if let Some(s) = snr_db {
                snrs.push(s);
            }
            if severity(status) > severity(worst) {
                worst = status;
            }
            *self.summary.statuses.entry(status.as_str()).or_default() += 1;
            let meta = IrMeta {
                x_m,
                y_m,
                snr_db,
                status: Some(status),
                retries: Some(row.acquisitions.saturating_sub(1)),
                measured_at_unix_us: Some(measured_at),
                ..IrMeta::at_grid(&self.plan.grid, ix as u32, iy as u32, actuator as u16, self.fs)?
            };
            records.push(IrRecord { meta, ir: ir.iter().map(|v| *v as f32).collect() });
        }
        let commit_started = std::time::Instant::now();
        writer.commit_batch(&records)?;
        self.summary.commit_s += commit_started.elapsed().as_secs_f64();
        self.commits += 1;
        self.summary.committed_now += 1;
        self.summary.committed += 1;
        let snr_db = median(&mut snrs);
        tracing::info!(point, status = worst.as_str(), snr_db, "point committed");
        observer.event(&Event::Committed {
            unit: point,
            done: self.summary.committed,
            total: self.summary.total,
            snr_db,
            status: worst.as_str().to_string(),
            clock_s: clock.now_s() - self.t0,
        });
        control.committed(self.commits);
        Ok(())
    }
}

/// Order of badness of a status, for the worst row of a point.
fn severity(status: Status) -> u8 {
    match status {
        Status::Valid | Status::GroundTruth => 0,
        Status::ReMeasured => 1,
        Status::Overrange => 2,
        Status::Dropout => 3,
        Status::Failed => 4,
    }
}

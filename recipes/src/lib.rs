//! Recipes: actuator calibration and the grid scan, as plans run by one engine over capability traits and the
//! store.
//!
//! A *plan* ([`plans`]) is what a recipe decides: what to measure next and what a result means for it (settle,
//! defer, re-measure, the row's status); its state is plain data, testable without a lab. The *engine*
//! ([`engine`]) owns the rest: the rig session and its recovery, acquisition with the one retry policy, aiming,
//! the reference check after a recovery, and the run skeleton (the dataset opened or resumed, commits, manifest
//! checkpoints, events, stop requests), for any [`engine::plan::Plan`] (Bluesky's plans and RunEngine, as a typed
//! trait). A recipe sees a [`metaplate_core::rig::Rig`] and writes only through `metaplate-store`. Every step that
//! changes the dataset is a commit; a resumed run continues after the last one. Beside the two recipes: the
//! pre-flight check ([`preflight`]), a rendered pattern played on the rig ([`play`]), and what a caller keeps and
//! says of a run's events ([`progress`], [`notify`], [`remaining`], [`cells`]).
//!
//! # Modules
//!
//! ```text
//! engine/         the lab and the dataset for any plan; never names a plan
//!   session.rs    the rig configured for recipes (`Instruments`); recovery: reconnect, reopen, drain, re-apply
//!                 settings, poll, pause after `RecoveryPolicy::pause_after_s`; `SessionState` (the velocity range
//!                 in force), committed with every unit and restored on resume
//!   acquire.rs    `acquire` with the one `RetryPolicy`: gaps, underruns and clipping retried; clipping widens the
//!                 velocity range tenfold (calibration, sequential and simultaneous scans, the reference check);
//!                 every retry counted in the row's `retries` and sent as an event
//!   aim.rs        the beam on a point, with nudges keyed by (seed, unit, visit, nudge)
//!   reference.rs  after a recovery, a committed point re-measured and compared (`ReferenceSpec`)
//!   plan.rs       what the engine asks of a plan: the `Plan` trait (meta, start, setup, reference, next -> Step |
//!                 Wait | Done, mid_unit, record, settle -> Commit | Continue), its `Processor` (pure, on the
//!                 worker thread), `Step`, `Lab` (a plan's view of the instruments)
//!   run.rs        `run(plan, settings, rig, out, control, observer)`: open or resume the dataset (its
//!                 configuration with the rig's record and, when given a pre-flight report, its record: verdict,
//!                 when, failed checks, `same_rig`; a resume keeps the first run's), `Started`, per step the
//!                 reference check after a recovery, aiming, the plan's recording, processing on a worker thread
//!                 while the next step is recorded (each step a `Phase` event: moving, playing, processing,
//!                 committing), the verdict: commit and manifest checkpoint with the unit's session state,
//!                 `Committed`, the stop hook; `Finished` or `Stopped`
//!   rig_record.rs the configuration's `rig` (`rig_config`): each instrument's identity and the wiring, so a resume
//!                 on another rig or cabling is refused as a changed configuration; `recorded_wiring` reads it back
//! plans/
//!   calibrate/    mod (configuration, `calibrate`, `calibration_row`), plan (per actuator, attempts of two steps:
//!                 the response aimed at the magnet, then the verification through the filter designed from it),
//!                 processing (deconvolution, the design by `dsp::equalise`, flatness), load (`Calibration::load`)
//!   scan/         mod (configuration, `scan`, `ScanPoints`, the scan plan: path points first, deferred ones when
//!                 nothing is in flight), points (`PointBook`: the plan's state as plain data, unit-tested without a
//!                 lab: visit, settle, defer, flag, commit), acquisition (recording a point; a sequential adaptive
//!                 row's shots, each as long as its estimate says is still missing: `ExtraShots`), processing (the
//!                 worker's decode and gates), gates (SNR and drift), simultaneous (Hadamard, staggered,
//!                 interleaved; adaptive rounds averaged with weights: `Averager`)
//! preflight/      the pre-flight (`metaplate check`): not a plan (it commits nothing), checks run straight on the
//!                 Rig, each device failure an outcome rather than an error. mod (`preflight`, `PreflightConfig`,
//!                 `CheckOutcome`, `PreflightReport`, the disk and duration checks), bench (the instruments, the
//!                 loopback level, latency and drift), chirps (each actuator's chirp at the beam: the actuators'
//!                 wiring, the LDV's level, range and SNR at a few points), reciprocity (which channel drives which
//!                 magnet: the pairs' responses reciprocal as wired, or only as swapped), keypad, signals
//! drive.rs        what is played: `DrivePlayback`, `SimultaneousPlayback`, `AudioPlayback`
//! play.rs         a rendered pattern on the rig: `PatternPlayback` (drives at a level, refused with
//!                 `RecipeError::Clipping` when they would clip, checked at the audio rate before any device is
//!                 touched), a sweep marker on the loopback located by `dsp::drift::locate_repetitions`: scheduled
//!                 and measured onset, latency
//!   prepare.rs    a pattern rendered from a scan through its calibration, checked and ready to play: what
//!                 `metaplate play` plays and an experiment's stimuli are (`prepare`, `render_through`,
//!                 `check_playable`)
//! events.rs       `RunControl` (stop levels, test hooks), `Event` (with `Phase`, `UnitPosition`), `Observer`
//! progress.rs     `RunProgress`, `EventLine` (the `--json` lines), `RunSummary` (a notification's summary)
//! notify.rs       `--notify-command`, run once per event, and the watch that notices a stall
//! remaining.rs    `RemainingTime`: median and conservative p90 of the time left, from the units' durations
//! cells.rs        a scan's planned points and the per-point status and SNR for the maps (`SNR_SCALE_DB`)
//! output.rs       `Output`: the dataset directory, opened fresh or resumed; the pre-flight's manifest record
//! quality.rs      the calibration's flatness measures (the project's smoothing and pyfar's standard one)
//! error.rs        `RecipeError` (`Config` is only the user's configuration; `Device`, `Internal` apart)
//! ```
//!
//! Dependencies point one way: plans -> engine -> `core`, `dsp`, `store`. A plan decides what to measure next and
//! what a result means (settle, defer, re-measure, status); the engine does everything with the instruments and the
//! dataset. A plan's decisions are unit-tested without a lab (`plans/calibrate/plan.rs`, `plans/scan/points.rs`);
//! the engine is tested with a plan of its own (the test module `engine`: overlap, order, stop between units,
//! resume). A stop (first Ctrl-C, [`RunControl`]) takes effect before the next step, except inside a unit the plan
//! says is partly measured (`mid_unit`: a calibration's actuator between its response and its verification), which
//! finishes first; a second one abandons the unit in flight.
//!
//! # The recipes
//!
//! - [`calibrate()`]: per actuator, the beam on its magnet; a 3 s sweep over 50 to 710 Hz (past the scan band by
//!   more than the standard smoothing's half window); the response deconvolved two-sided; its power smoothed over
//!   a third of an octave (the plate's driving-point modes at the magnet are the plate's, not the actuator's, and
//!   inverting their notches would spend tens of dB of headroom) and given minimum phase; the Kirkeby inverse,
//!   refined by `dsp::equalise` until the verification is predicted flat on both smoothings; a verification with
//!   the filter applied, judged on the project's smoothing and on pyfar's standard one, each about its median
//!   (+/-1 dB over 62 to 625 Hz, both: `CalibrationConfig::standard_smoothing`); one commit per actuator (filter,
//!   response, verification as three rows of a 3 x 1 calibration grid).
//! - [`scan()`]: the plan's points in serpentine order; per point, the protocol's shots (simultaneous protocols play
//!   every actuator's own compensated drive at once and decode on the worker thread), gates per acquisition
//!   (`acquire`) and per response (SNR, drift), a deferred queue re-visited at the end with the beam nudged, then a
//!   status (valid, re-measured, overrange, dropout, failed). Acquisition of point k + 1 overlaps processing of
//!   point k; commits are in plan order.
//!
//! # Resume
//!
//! The store's journal says what is committed; a changed configuration (the manifest holds the recipe's whole
//! configuration, the calibration's hash, the plan and the rig) is refused unless forced; corrupt files are
//! quarantined and their points measured again. The session state that changes later measurements (the velocity
//! range a clipping widened) is committed with each unit in the journal and restored on resume (for the scan, the
//! state right after that point's own recording, since point k + 1 is recorded before point k commits).
//! Randomness (beam nudges) is keyed by (seed, unit, visit, nudge), never drawn from a running generator, and what a
//! unit measures on the mock lab depends only on (scene, seed, unit, attempt), so a resumed run equals an
//! uninterrupted one bit for bit, also when killed inside a unit (the test module `resume`; the end-to-end
//! `tests/crash.rs`: kill -9 at seeded instants inside units and inside commits of `scan` and `calibrate`).

pub mod cells;
pub mod drive;
pub mod engine;
pub mod error;
pub mod events;
pub mod notify;
pub mod output;
pub mod plans;
pub mod play;
pub mod preflight;
pub mod progress;
pub mod quality;
pub mod remaining;

pub use engine::acquire::RetryPolicy;
pub use engine::aim::AimPolicy;
pub use engine::rig_record::{recorded_wiring, rig_config};
pub use engine::session::RecoveryPolicy;
pub use error::RecipeError;
pub use events::{Event, Observer, Phase, RunControl, Silent, UnitPosition};
pub use output::Output;
pub use plans::calibrate::{self, Calibration, CalibrationConfig, calibrate};
pub use plans::scan::{self, PREPARE_WHOLE_PLAN_POINTS, ScanConfig, ScanPoints, ScanSummary, scan};
pub use progress::{EventLine, RunProgress, RunSummary, resume_command};
pub use remaining::RemainingTime;

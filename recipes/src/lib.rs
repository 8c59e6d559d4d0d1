//! Recipes: actuator calibration and the grid scan, as plans run by one engine over capability traits and the
//! store.
//!
//! A *plan* ([`plans`]) is what a recipe decides: what to measure next and what a result means for it (settle,
//! defer, re-measure, the row's status); its state is plain data, testable without a lab. The *engine*
//! ([`engine`]) owns the rest: the rig session and its recovery, acquisition with the one retry policy, aiming,
//! the reference check after a recovery, and the run skeleton (the dataset opened or resumed, commits, manifest
//! checkpoints, events, stop requests). A recipe sees a [`metaplate_core::rig::Rig`] and writes only through
//! `metaplate-store`. Every step that changes the dataset is a commit; a resumed run continues after the last one.
//! Randomness (beam nudges) is keyed by (seed, unit, visit, nudge), never drawn from a running generator, so a
//! resumed run makes the same choices as an uninterrupted one.

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
pub use plans::scan::{self, ScanConfig, ScanPoints, ScanSummary, scan};
pub use progress::{EventLine, RunProgress, RunSummary};
pub use remaining::RemainingTime;

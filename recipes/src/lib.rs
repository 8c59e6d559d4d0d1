//! Recipes: actuator calibration and the grid scan, as resumable state machines over capability traits and the store.
//!
//! A recipe sees a [`metaplate_core::rig::Rig`] (the instruments behind their capability traits, their wiring and a
//! clock) and writes only through `metaplate-store`. Every step that changes the dataset is a commit; a resumed run
//! continues after the last one. Randomness (beam nudges) is keyed by (seed, unit, visit, nudge), never drawn from
//! a running generator, so a resumed run makes the same choices as an uninterrupted one.

pub mod aim;
pub mod calibrate;
pub mod control;
pub mod dataset;
pub mod error;
pub mod instruments;
pub mod protocol;
pub mod quality;
pub mod scan;
pub mod signals;

pub use calibrate::{Calibration, CalibrationConfig, calibrate};
pub use control::{Event, Observer, RunControl, Silent};
pub use dataset::Output;
pub use error::RecipeError;
pub use scan::{ScanConfig, ScanPlan, ScanProtocol, ScanSummary, scan};

//! The suite judged on the simulated lab: what a measurement made on the mock lab is worth against the simulated
//! truth (the Green's functions' error), the error budget, the speed/accuracy trade of the scan protocols and its
//! statistics, and the end-to-end demo with its report.
//!
//! [`truth`]: a dataset against the mock lab's ground truth. [`budget`]: the error budget per imperfection.
//! [`tradeoff`]: the speed/accuracy trade and its statistics ([`tradeoff::fit`]). [`simulated`]: the plate model's
//! own dispersion and ground-truth dataset. [`report`]: the self-contained HTML page on scan datasets. [`demo`]:
//! the main job on the built-in plates, as a typed [`demo::DemoSummary`]. Every result derives `Serialize` with its
//! fields in alphabetical order, the key order of the JSON the binary prints. Long runs tell a [`Progress`].

pub mod budget;
pub mod demo;
pub mod error;
pub mod progress;
pub mod report;
mod scratch;
pub mod simulated;
pub mod tradeoff;
pub mod truth;

pub use error::EvaluationError;
pub use progress::{Progress, Quiet};

//! The suite judged on the simulated lab: what a measurement made on the mock lab is worth against the simulated
//! truth (the Green's functions' error), the error budget, the speed/accuracy trade of the scan protocols and its
//! statistics, and the end-to-end demo with its report. The binary's `demo`, `tradeoff`, `budget`, `report` and
//! `simulate` commands are thin calls of this crate.
//!
//! - [`truth`]: a dataset against the mock lab's ground truth, the error of each measured Green's function, as the
//!   demo, `tradeoff` and `report` state it.
//! - [`budget`]: the error budget per imperfection: each variant of the scene (`metaplate_lab::budget`: every
//!   imperfection off, each alone, all on) scanned, and each row compared with the full and the windowed truth
//!   (the protocol's band, the dataset's window, and the sweep's period for two periods or more); the lab's
//!   `budget` module does the arithmetic.
//! - [`tradeoff`]: each protocol scanned once per seed on the mock lab (the scan's SNR gate off unless
//!   `min_snr_db`: its estimates differ by scheme), reported as seed means with Student-t 95 % intervals;
//!   [`tradeoff::fit`] holds its arithmetic (a series' error slope per doubling of excitation time, the time ratio
//!   to the paper protocol at its median error).
//! - [`simulated`]: the plate model's own dispersion and its ground truth written as a dataset.
//! - [`report`]: the self-contained HTML page on scan datasets (`metaplate report`, and the demo's), with the
//!   paper-against-suite table of `metaplate_analysis::paper_table`.
//! - [`demo`]: the main job on the built-in plates, as a typed [`demo::DemoSummary`].
//!
//! Every result derives `Serialize` with its fields in alphabetical order, the key order of the JSON the binary
//! prints. Long runs tell a [`Progress`]. Nothing here links tokio or a real device backend (`.ci/run` checks both
//! with `cargo tree`).

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

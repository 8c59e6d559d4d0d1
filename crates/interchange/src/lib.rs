//! Datasets to and from other tools' files: a dataset exported as universal files (UFF 58/58b with 164 units and
//! 2411 nodes) for modal-analysis tools ([`export()`]), and universal files written by other tools (or by
//! [`export()`]) imported as a dataset through the store's writer ([`import()`]). The codec is `metaplate-uff`;
//! the binary's `metaplate export` and `metaplate import` are thin calls of this crate.
//!
//! Both stream: an export reads one batch file at a time and an import holds one batch of rows, so a dataset of
//! any size passes in bounded memory. Both report their progress to a callback ([`Progress`]), so that the caller
//! draws it as it likes (the binary: a progress bar on stderr).
//!
//! - [`export`](mod@export): what the file holds, in order (units, nodes, then one response per committed
//!   (point, actuator), and with [`ExportOptions`] its frequency response too).
//! - [`import`](mod@import): what is read and what skipped, how the grid and keys, the actuators, the sample rate
//!   (`metaplate_uff::sample_rate_from_step`), the function and the units are found, and what is refused.
//! - `survey::choose`: of several responses of one (point, actuator) and kind, the one imported (the estimator, the
//!   direction along the plate's normal), the others listed as skipped.
//! - [`lattice`]: 3-D node positions placed on the regular lattice of their plane, or in their plane alone
//!   (scattered points, `metaplate_store::ScatteredPoints`).
//! - `header`: the dataset 151 an export begins with: the dataset's `ir` unit in full and the calibration a scan went
//!   through, which an import restores (so that a scan exported and imported again still plays).
//! - [`IdLines`]: the ID lines of an exported record, the one format export and import share: they carry what an
//!   import needs to rebuild the dataset's rows exactly (key, grid, scene, row quality, source); a file without them
//!   (another tool's) is placed by its nodes (`metaplate_core::grid::snap_to_grid`).
//!
//! Every error is an [`InterchangeError`] saying what and where. The crate's tests round-trip a dataset through a
//! universal file in every format, from FRFs alone and placed by the nodes alone (on a tilted, rotated mesh too),
//! import files with records that are no responses and responses of acceleration and displacement, check each
//! refusal, and read the corpus of other writers' files in `tests/corpus/` as pyuff reads them.

mod convert;
mod error;
pub mod export;
mod header;
mod id_lines;
pub mod import;
pub mod lattice;
mod quantity;
mod survey;

pub use error::InterchangeError;
pub use export::{ExportOptions, ExportSummary, actuator_sites, default_out, export};
pub use id_lines::IdLines;
pub use import::{ImportOptions, ImportSummary, import, skipped_summary};
pub use survey::{ActuatorRef, ESTIMATORS, MAX_AXIS_ANGLE_DEG, ONE_POINT_SPACING_M, SkippedRecord, read_nodes_csv};

/// How far an export or import is: `done` of `total` responses (a response: one (point, actuator) pair).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress {
    /// Responses written (export) or committed (import) so far.
    pub done: u64,
    /// Responses in all.
    pub total: u64,
}

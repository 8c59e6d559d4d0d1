//! Datasets on disk: the format a scan produces and analysis reads.
//!
//! A dataset is a directory that pandas, polars or pyarrow read without our code:
//! - `batches/batch-NNNNNN.parquet`: one Parquet file per committed batch, one row per (grid point, actuator), in
//!   the columns of [`schema`]; `batches/` holds nothing else, so `pyarrow.parquet.read_table("RUN/batches")`,
//!   `pandas.read_parquet("RUN/batches")` and `polars.read_parquet("RUN/batches")` read the whole dataset;
//! - `manifest.json` ([`Manifest`]): what the dataset is (recipe and resolved configuration, scene, software version,
//!   seed, grid), the batch files with their sizes and SHA-256 checksums, and a hash of the configuration.
//!
//! Every file is written durably (temporary name, fsync, atomic rename, directory fsync), so a crash leaves either the previous state or the new one, never a half-written file under a real name.
//! [`DatasetWriter`] writes, [`Dataset`] reads back, verifying every checksum first.
//!
//! Still to come (later issues): the append-only commit journal and resume, quarantine, compaction, exports (WAV,
//! UFF 58) and a polars reader.

mod checksum;
mod codec;
mod durable;
pub mod error;
mod index;
pub mod manifest;
mod reader;
pub mod record;
pub mod schema;
mod writer;

pub use checksum::sha256;
pub use error::StoreError;
pub use manifest::{BATCH_DIR, BatchInfo, DatasetMeta, GridSpec, MANIFEST_FILE, Manifest, SCHEMA_VERSION, SceneId};
pub use reader::Dataset;
pub use record::{IrMeta, IrRecord};
pub use schema::Status;
pub use writer::{DatasetWriter, IfExists};

//! Datasets on disk: the format a scan produces and analysis reads.
//!
//! A dataset is a directory that pandas, polars or pyarrow read without our code:
//! - `manifest.json` ([`Manifest`]): what the dataset is (recipe and resolved configuration, scene, software version,
//!   seed, grid) and `config_hash`; written at creation, its batch list refreshed at checkpoint and finish;
//! - `journal.jsonl` ([`journal`]): one fsync'd line per commit, each with its own CRC-32. **The journal is
//!   authoritative** for which files hold the dataset; the manifest's batch list is a snapshot for tools that read only
//!   the manifest;
//! - `batches/batch-NNNNNN.parquet` (and `compacted-NNNNNN.parquet` after [`compact`]): one row per (grid point,
//!   actuator), in the columns of [`schema`]. Read the files the journal lists: after a crash or a compaction,
//!   `batches/` may briefly hold files that are not part of the dataset (resume tidies them);
//! - `quarantine/`: files resume could not trust, with `notes.jsonl` saying why.
//!
//! Every file is written durably (temporary name, fsync, atomic rename, directory fsync) before its journal line, so
//! a crash leaves either the previous state or the new one. [`DatasetWriter`] writes ([`DatasetWriter::create`],
//! [`DatasetWriter::commit_batch`]) and continues after any stop ([`DatasetWriter::resume`]: verifies every committed
//! file, quarantines what fails, never commits a key twice); [`Dataset`] reads back, verifying every checksum first;
//! [`export_wav`] and [`write_wav_f32`] write 32-bit float WAV files, [`read_wav`] reads any WAV file; with the cargo feature `polars`,
//! `Dataset::lazy` gives a polars `LazyFrame` over the committed files.

mod checksum;
mod codec;
mod compact;
mod durable;
pub mod error;
mod index;
pub mod journal;
#[cfg(feature = "polars")]
mod lazy;
pub mod lock;
pub mod manifest;
mod reader;
pub mod record;
mod resume;
pub mod schema;
mod space;
pub mod test_hook;
pub mod wav;
mod writer;

pub use checksum::sha256;
pub use compact::{CompactReport, compact};
pub use durable::{sync_dir, write_bytes};
pub use error::StoreError;
pub use journal::{JOURNAL_FILE, JournalCommit, JournalIssue, JournalView};
pub use lock::{LockHolder, try_lock_exclusive};
pub use manifest::{
    BATCH_DIR, BatchInfo, DatasetDescription, DatasetMeta, GridSpec, IR_UNIT_M_S_PER_N, MANIFEST_FILE, Manifest,
    SCHEMA_VERSION, SceneId,
};
pub use reader::{BatchRows, Dataset, ReadOptions};
pub use record::{IrMeta, IrRecord};
pub use resume::{Quarantined, ResumeReport};
pub use schema::{RowKind, Status};
pub use space::free_bytes;
pub use wav::{export_wav, read_wav, write_wav_f32};
pub use writer::{DatasetWriter, IfExists, QUARANTINE_DIR};

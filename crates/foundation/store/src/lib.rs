//! Datasets on disk: the format a scan produces and analysis reads.
//!
//! A dataset is a directory of Parquet batch files, a manifest and a commit journal, written durably and read back
//! verified, that pandas, polars or pyarrow read without our code. This crate writes it ([`DatasetWriter`]), resumes
//! it after any stop, compacts it, reads it whole or one committed file at a time ([`Dataset`]), and follows it while
//! another process writes it ([`journal::view`]). It also holds WAV files ([`wav`]), small durable writes outside a
//! dataset ([`write_bytes`]) and the free space of a run's disk ([`free_bytes`]).
//!
//! # Layout
//!
//! ```text
//! RUN/manifest.json            schema version, recipe, resolved configuration, scene {name, hash}, seed, grid,
//!                              description, batches [{file, rows, size_bytes, checksum "sha256:..."}], config_hash
//! RUN/journal.jsonl            one fsync'd line per commit, each with its own CRC-32: the source of truth
//! RUN/batches/batch-NNNNNN.parquet   one row per (point, actuator): point_index, ix, iy, x_m, y_m, actuator,
//!                              sample_rate_hz, ir, snr_db, status, retries, measured_at (UTC us), kind,
//!                              estimated_error_db
//! RUN/batches/compacted-NNNNNN.parquet   after `compact`: one file superseding the batches
//! RUN/quarantine/              files resume could not trust, with notes.jsonl saying why
//! ```
//!
//! - [`manifest`]: [`Manifest`], what the dataset is ([`DatasetMeta`]: recipe and resolved configuration, scene,
//!   software version, seed, grid, and [`DatasetDescription`], what `ir` holds: its unit and `pre_samples`, the
//!   samples before time 0; and, for points on no lattice, [`ScatteredPoints`]: their positions, the grid then
//!   only their index) and `config_hash`; written at creation, its batch list refreshed at checkpoint and
//!   finish. The batch files live in `batches/` ([`BATCH_DIR`]) so that `pl.read_parquet("RUN/batches")` and
//!   `pq.read_table("RUN/batches")` read the dataset without our code (a JSON file beside them makes both refuse
//!   the directory).
//! - [`schema`]: the columns. `ir` is a fixed-size list of the dataset's IR length
//!   ([`schema::arrow_schema`]`(ir_len)`; files written with a plain list still read); `kind` says which row of a
//!   calibration is which ([`RowKind`]: filter, response, verification); `estimated_error_db` and `kind` are
//!   optional when reading. [`schema::file_metadata`] is the one list of `metaplate.*` key-value metadata every
//!   batch file carries, so that one file read alone says what it holds.
//! - [`journal`]: `journal.jsonl`, one JSON line per batch, compaction, quarantine or forced resume, each with its
//!   own CRC-32, appended and fsync'd after the batch file's rename and directory fsync. **The journal is
//!   authoritative** for which files hold the dataset; the manifest's batch list is a snapshot for tools that read
//!   only the manifest. A torn or corrupt line is skipped and reported. [`journal::view`] reads it without the
//!   writer's lock (every commit with its time, the live files), for a follower of a dataset being written.
//! - [`DatasetWriter`]: [`DatasetWriter::create`] and [`DatasetWriter::commit_batch`], which refuses a key already
//!   committed (in this session or an earlier one), a second IR length or sample rate, or an invalid row.
//!   [`DatasetWriter::commit_batch_with_state`] commits the writer's session state (a JSON object the recipe
//!   defines) in the batch's journal line, atomically with its rows.
//! - [`DatasetWriter::resume`]: verifies every journaled file (size, SHA-256), quarantines what fails into
//!   `quarantine/` (its points are then measured again), moves unjournaled orphans there too, refuses a changed
//!   configuration unless forced (listing the differing keys, and journaling them when forced), and returns the
//!   committed keys and the state of the last committed batch that verified ([`ResumeReport::state`]).
//! - [`compact()`]: writes one file and journals it as superseding the batches, carrying the last state on.
//! - [`Dataset`]: [`Dataset::open`] reads the committed files on several threads (each file whole on one thread,
//!   decoded in record batches of about 1 MiB), verifying sizes and SHA-256 checksums before parsing, and refuses
//!   duplicates, mixed IR lengths or sample rates, and non-finite samples. [`Dataset::stream`] hands over one
//!   committed file at a time; [`Dataset::committed_keys`] reads the journal alone; [`Dataset::read_batch`] reads
//!   one committed file, verified against its journal entry (with [`journal::view`], how a follower reads a dataset
//!   as it grows). [`Dataset::committed_files`] lists the committed files for other readers; with the cargo
//!   feature `polars`, `Dataset::dataframe` turns a dataset, read and verified, into a polars `DataFrame`.
//! - [`wav`]: [`export_wav`] and [`write_wav_f32`] write 32-bit float multichannel WAV files (impulse responses,
//!   drive signals); [`read_wav`] reads any WAV file.
//! - [`write_bytes`]: a small file written durably outside a dataset (an experiment session's plan, for example).
//! - [`write_table`]: a small table outside a dataset (scored trials, band points) as one Parquet file, durably.
//! - [`free_bytes`]: the free space of the disk a run writes to (statvfs), for the monitor and the pre-flight.
//! - [`lock`]: the exclusive writer lock on a journal, released by the operating system when the process dies, and
//!   [`LockHolder`], who holds it.
//!
//! # Invariants
//!
//! - Every file is written durably (a temporary name, fsync, atomic rename, directory fsync; a batch file is
//!   staged in `RUN/` and renamed into `batches/`) before its journal line, so a crash leaves either the previous
//!   state or the new one; the manifest is replaced the same way.
//! - A (point, actuator) key is committed at most once; nothing the journal has not superseded is ever deleted
//!   (suspect files are moved to `quarantine/`, with a line in its `notes.jsonl` each).
//! - One writer at a time: the writer holds a lock on the journal; readers take none.

mod checksum;
mod codec;
mod committed;
mod compact;
#[cfg(feature = "polars")]
mod dataframe;
mod durable;
pub mod error;
mod index;
pub mod journal;
pub mod lock;
pub mod manifest;
mod reader;
pub mod record;
mod resume;
pub mod schema;
mod space;
mod table;
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
    SCHEMA_VERSION, ScatteredPoints, SceneId,
};
pub use reader::{BatchRows, Dataset, ReadOptions};
pub use record::{IrMeta, IrRecord};
pub use resume::{Quarantined, ResumeReport};
pub use schema::{RowKind, Status};
pub use space::free_bytes;
pub use table::write_table;
pub use wav::{export_wav, read_wav, write_wav_f32};
pub use writer::{DatasetWriter, IfExists, QUARANTINE_DIR};

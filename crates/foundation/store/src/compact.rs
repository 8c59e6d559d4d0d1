//! Compaction: one file instead of many small ones, without a moment at which the dataset is not whole.
//!
//! Steps, each crash-safe: (1) write `batches/compacted-NNNNNN.parquet` durably with every committed row, sorted by
//! (point, actuator) — a crash here leaves an unjournaled file that the batches make redundant (resume deletes it);
//! (2) append the `compaction` journal line listing the files it supersedes — from then on readers take the compacted
//! file and ignore the old ones; (3) delete the old files — a crash here leaves garbage that readers ignore and
//! resume deletes; (4) refresh the manifest.

use std::fs;
use std::path::Path;

use crate::codec;
use crate::durable::{self, WriteBudget};
use crate::error::StoreError;
use crate::journal::{self, BatchEntry, JOURNAL_FILE, JournalEntry, JournalWriter, Live};
use crate::manifest::{BATCH_DIR, Manifest};
use crate::reader::Dataset;
use crate::record::IrRecord;
use crate::schema;

/// Rows per row group of a compacted file: bounds the memory of writing it (1024 rows of 12000 samples: 49 MB).
const ROWS_PER_GROUP: usize = 1024;

/// What [`compact`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CompactReport {
    /// The compacted file, or `None` if the dataset already was a single file (nothing done).
    pub file: Option<String>,
    /// Rows in it.
    pub rows: u64,
    /// The files it replaced (deleted).
    pub superseded: Vec<String>,
}

/// Rewrites every committed row of the dataset in `dir` into one file, sorted by (point, actuator), journals it, and
/// deletes the files it replaces. Verifies every file first (as [`Dataset::open`]). Takes the writer lock: it cannot
/// run while a writer has the dataset open.
///
/// # Errors
/// [`StoreError::Journal`] if the dataset has no journal, or a damaged one (resume it first);
/// [`StoreError::Locked`]; any error of [`Dataset::open`]; [`StoreError::Io`] / [`StoreError::DiskFull`] (then
/// nothing has changed but a leftover compacted file, which resume deletes).
pub fn compact(dir: impl AsRef<Path>) -> Result<CompactReport, StoreError> {
    let dir = dir.as_ref();
    let mut manifest = Manifest::read(dir)?;
    let path = dir.join(JOURNAL_FILE);
    let read = journal::read(dir)?.ok_or_else(|| StoreError::Journal {
        path: path.clone(),
        reason: "missing: nothing to compact against".into(),
    })?;
    if !read.issues.is_empty() {
        let reason = format!("{} damaged line(s); resume the dataset before compacting it", read.issues.len());
        return Err(StoreError::Journal { path, reason });
    }
    let mut journal = JournalWriter::open(dir, read.next_seq())?;
    let live = Live::replay(&read.entries);
    if live.batches.len() <= 1 {
        let rows = live.batches.first().map_or(0, |b| b.rows);
        return Ok(CompactReport { file: None, rows, superseded: Vec::new() });
    }
    let dataset = Dataset::open(dir)?;
    let mut order: Vec<usize> = (0..dataset.len()).collect();
    order.sort_unstable_by_key(|&row| dataset.rows()[row].key());
    let file = format!("compacted-{:06}.parquet", journal.next_seq());
    let parts = order.chunks(ROWS_PER_GROUP).map(|rows| {
        rows.iter()
            .map(|&row| {
                let ir = dataset.row_ir(row).ok_or_else(|| StoreError::InvalidRecord {
                    location: format!("row {row}"),
                    reason: "missing from the dataset read for compaction".into(),
                })?;
                Ok(IrRecord { meta: dataset.rows()[row], ir: ir.to_vec() })
            })
            .collect::<Result<Vec<_>, StoreError>>()
    });
    let batch_dir = dir.join(BATCH_DIR);
    let budget = WriteBudget::default();
    let key_values = schema::file_metadata(&manifest.meta, dataset.sample_rate_hz());
    let written = durable::write_file_into(dir, &batch_dir, &file, &budget, |sink| {
        codec::write_parquet_parts(sink, parts, key_values, &file)
    })?;
    let superseded: Vec<String> = live.batches.iter().map(|b| b.file.clone()).collect();
    let entry = BatchEntry {
        file: file.clone(),
        rows: dataset.len() as u64,
        size_bytes: written.size_bytes,
        checksum: written.checksum,
        ir_len: dataset.ir_len() as u64,
        sample_rate_hz: dataset.sample_rate_hz(),
        keys: order.iter().map(|&row| dataset.rows()[row].key()).collect(),
        supersedes: superseded.clone(),
        // The state after the last batch it replaces: a resume after the compaction continues from it.
        state: live.batches.iter().rev().find_map(|b| b.state.clone()),
    };
    if let Err(e) = journal.append(&JournalEntry::Compaction(entry.clone()), &budget) {
        if journal.broken().is_none() {
            // Surely not journaled: the batches stay authoritative; the copy goes (best effort, resume deletes it).
            let _ = fs::remove_file(batch_dir.join(&file));
        }
        return Err(e);
    }
    for old in &superseded {
        let old_path = batch_dir.join(old);
        match fs::remove_file(&old_path) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(StoreError::from_io("remove", old_path, e)),
        }
    }
    durable::sync_dir(&batch_dir)?;
    manifest.batches = vec![entry.info()];
    manifest.write(dir)?;
    Ok(CompactReport { file: Some(file), rows: entry.rows, superseded })
}

//! Writing a dataset: `manifest.json` at creation, then per committed batch one durable Parquet file and one fsync'd
//! journal line.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

use chrono::{SecondsFormat, Utc};

use crate::codec;
use crate::durable::{self, TEMP_SUFFIX, WriteBudget};
use crate::error::StoreError;
use crate::index::RowIndex;
use crate::journal::{BatchEntry, JOURNAL_FILE, JournalEntry, JournalWriter};
use crate::manifest::{BATCH_DIR, BatchInfo, DatasetMeta, MANIFEST_FILE, Manifest};
use crate::record::IrRecord;
use crate::schema;

/// Subdirectory of a dataset directory where `DatasetWriter::resume` moves files it cannot trust, with a note each
/// in `notes.jsonl`.
pub const QUARANTINE_DIR: &str = "quarantine";

/// What [`DatasetWriter::create`] does with a directory that already holds files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IfExists {
    /// Refuse with [`StoreError::NotEmpty`]: the safe default, nothing is ever overwritten.
    Refuse,
    /// Delete a previous dataset in it (its manifest, journal, batch files, quarantine and temporary files) and
    /// start afresh. Any other file makes it refuse with [`StoreError::NotEmpty`], and then nothing has been deleted.
    Replace,
}

/// Writes one dataset directory; holds the dataset's writer lock (on `journal.jsonl`) while it lives.
///
/// [`create`](Self::create) writes `manifest.json` (what the dataset is) and an empty `journal.jsonl`. Each
/// [`commit_batch`](Self::commit_batch) makes one Parquet file durable, then appends and fsyncs its journal line:
/// when it returns `Ok`, the batch survives a crash or a power cut, and [`crate::Dataset::open`] reads it. The
/// journal is authoritative; the manifest's batch list is a snapshot refreshed by [`checkpoint`](Self::checkpoint)
/// and [`finish`](Self::finish) for tools that read only the manifest.
#[derive(Debug)]
pub struct DatasetWriter {
    dir: PathBuf,
    manifest: Manifest,
    index: RowIndex,
    journal: JournalWriter,
    budget: WriteBudget,
}

/// File name of the batch journaled with sequence number `seq`; zero-padded so that names sort in commit order.
pub(crate) fn batch_file_name(seq: u64) -> String {
    format!("batch-{seq:06}.parquet")
}

/// Whether `name` is a data file name this crate gives (`batch-` or `compacted-`, digits, `.parquet`).
pub(crate) fn is_own_batch_file(name: &str) -> bool {
    ["batch-", "compacted-"].iter().any(|prefix| {
        name.strip_prefix(prefix)
            .and_then(|n| n.strip_suffix(".parquet"))
            .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
    })
}

/// Whether `name`, in the dataset directory itself, is a file a writer of this crate creates: the manifest, the
/// journal, or a temporary of one of them or of a batch file.
pub(crate) fn is_own_root_file(name: &str) -> bool {
    let target = name.strip_prefix('.').and_then(|n| n.strip_suffix(TEMP_SUFFIX));
    let own = |n: &str| n == MANIFEST_FILE || n == JOURNAL_FILE;
    own(name) || target.is_some_and(|t| own(t) || is_own_batch_file(t))
}

impl DatasetWriter {
    /// Starts a dataset in `dir` (created if missing, with its parents) described by `meta`: creates the empty
    /// [`BATCH_DIR`] and journal, then writes `manifest.json` (whose presence marks a complete creation).
    ///
    /// # Errors
    /// [`StoreError::UnsupportedSchemaVersion`] or [`StoreError::InvalidMeta`] for bad metadata;
    /// [`StoreError::NotEmpty`] if `dir` holds files and `if_exists` does not allow replacing them;
    /// [`StoreError::Io`] / [`StoreError::DiskFull`] if `dir` is not a writable directory.
    pub fn create(dir: impl AsRef<Path>, meta: DatasetMeta, if_exists: IfExists) -> Result<Self, StoreError> {
        meta.validate()?;
        let dir = dir.as_ref().to_path_buf();
        prepare_dir(&dir, if_exists)?;
        let batch_dir = dir.join(BATCH_DIR);
        fs::create_dir(&batch_dir).map_err(StoreError::io("create directory", &batch_dir))?;
        let journal = JournalWriter::create(&dir)?;
        let config_hash = meta.config_hash();
        let created_at = Utc::now().to_rfc3339_opts(SecondsFormat::Millis, true);
        let manifest = Manifest { meta, created_at, batches: Vec::new(), config_hash };
        manifest.write(&dir)?;
        Ok(Self { dir, manifest, index: RowIndex::default(), journal, budget: WriteBudget::default() })
    }

    /// A writer over state that [`DatasetWriter::resume`] has verified.
    pub(crate) fn from_parts(dir: PathBuf, manifest: Manifest, index: RowIndex, journal: JournalWriter) -> Self {
        Self { dir, manifest, index, journal, budget: WriteBudget::default() }
    }

    /// Testing aid: from now on this writer may write at most `bytes` more bytes (batch files, journal lines and
    /// manifest together); a write beyond fails as a full disk does ([`StoreError::DiskFull`]). It makes the
    /// full-disk behaviour testable without root or a small file system; production code never calls it.
    #[must_use]
    pub fn with_write_budget(mut self, bytes: u64) -> Self {
        self.budget = WriteBudget::limited(bytes);
        self
    }

    /// Writes `records` as the next batch file durably (temporary name, fsync, atomic rename, directory fsync), then
    /// appends its journal line (fsync'd). Only then is the batch committed.
    ///
    /// The batch is checked whole before anything is written: every record valid against the grid, each
    /// (point, actuator) pair once across the whole dataset (a pair committed before, in this session or an earlier
    /// one, is refused), one IR length and one sample rate. A refused or failed commit commits nothing and leaves the
    /// writer as it was; a batch file already renamed into place is taken back (or, if that fails, left as an orphan
    /// that resume quarantines).
    ///
    /// Cost: encoding, SHA-256 and three fsyncs (file, directory, journal); see the crate's ARCHITECTURE entry for
    /// measured figures.
    ///
    /// # Errors
    /// [`StoreError::EmptyBatch`], [`StoreError::InvalidRecord`], [`StoreError::Duplicate`],
    /// [`StoreError::Inconsistent`] (each naming the row); [`StoreError::DiskFull`] (nothing committed; free space,
    /// then resume or retry); [`StoreError::Io`] / [`StoreError::Parquet`]; [`StoreError::Poisoned`] after a failure
    /// that left the journal's state unknown (resume to continue).
    pub fn commit_batch(&mut self, records: &[IrRecord]) -> Result<BatchInfo, StoreError> {
        self.commit_batch_with_state(records, None)
    }

    /// [`commit_batch`](Self::commit_batch), with the writer's session `state` after this batch (a JSON object the
    /// caller defines) in the same journal line: the rows and the state are committed together or not at all, and
    /// [`DatasetWriter::resume`] hands back the state of the last committed batch
    /// ([`ResumeReport::state`](crate::ResumeReport::state)).
    ///
    /// # Errors
    /// As [`commit_batch`](Self::commit_batch).
    pub fn commit_batch_with_state(
        &mut self,
        records: &[IrRecord],
        state: Option<serde_json::Map<String, serde_json::Value>>,
    ) -> Result<BatchInfo, StoreError> {
        if let Some(reason) = self.journal.broken() {
            return Err(StoreError::Poisoned { dir: self.dir.clone(), reason: reason.to_string() });
        }
        let file = batch_file_name(self.journal.next_seq());
        let rows = records.iter().map(|r| (&r.meta, r.ir.as_slice()));
        let checked = self.index.check(&file, &self.manifest.meta.grid, rows)?;
        let batch_dir = self.dir.join(BATCH_DIR);
        let key_values = schema::file_metadata(&self.manifest.meta, checked.sample_rate_hz());
        // Staged in the dataset directory, so that `batches/` only ever holds finished files.
        let written = durable::write_file_into(&self.dir, &batch_dir, &file, &self.budget, |sink| {
            codec::write_parquet(sink, records, key_values, &file)
        })?;
        let entry = BatchEntry {
            file,
            rows: records.len() as u64,
            size_bytes: written.size_bytes,
            checksum: written.checksum,
            ir_len: checked.ir_len() as u64,
            sample_rate_hz: checked.sample_rate_hz(),
            keys: checked.keys().to_vec(),
            supersedes: Vec::new(),
            state,
        };
        crate::test_hook::pause_from_env(TEST_COMMIT_PAUSE_ENV);
        if let Err(e) = self.journal.append(&JournalEntry::Batch(entry.clone()), &self.budget) {
            // Not committed. When the journal was cut back cleanly the file is surely uncommitted: take it back (best
            // effort; a leftover is an orphan that resume quarantines). When the journal's state is unknown, leave
            // the file: it may be committed after all, and resume decides.
            if self.journal.broken().is_none() {
                let _ = fs::remove_file(batch_dir.join(&entry.file));
            }
            return Err(e);
        }
        self.index.accept(checked);
        let info = entry.info();
        self.manifest.batches.push(info.clone());
        Ok(info)
    }

    /// Every `(point_index, actuator)` committed (by this writer and, after a resume, before it), as a sorted set.
    /// Costs one pass over the in-memory index (no file is read).
    pub fn committed_keys(&self) -> BTreeSet<(u32, u16)> {
        self.index.keys().collect()
    }

    /// Whether `(point_index, actuator)` is committed.
    pub fn is_committed(&self, point_index: u32, actuator: u16) -> bool {
        self.index.contains((point_index, actuator))
    }

    /// Writes `manifest.json` durably with the batch list as it stands, for tools that read only the manifest
    /// (commits do not need it: the journal makes each one durable and readable). May be called again after further
    /// commits: each call replaces the manifest atomically.
    ///
    /// # Errors
    /// [`StoreError::EmptyDataset`] before the first commit; [`StoreError::Io`] / [`StoreError::DiskFull`].
    pub fn checkpoint(&mut self) -> Result<&Manifest, StoreError> {
        if self.manifest.batches.is_empty() {
            return Err(StoreError::EmptyDataset { dir: self.dir.clone() });
        }
        self.manifest.write_with(&self.dir, &self.budget)?;
        Ok(&self.manifest)
    }

    /// [`checkpoint`](Self::checkpoint), then releases the writer lock and hands back the final manifest.
    ///
    /// # Errors
    /// As [`checkpoint`](Self::checkpoint).
    pub fn finish(mut self) -> Result<Manifest, StoreError> {
        self.checkpoint()?;
        Ok(self.manifest)
    }

    /// The manifest as it stands (batches committed so far).
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The dataset directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Rows committed so far.
    pub fn rows(&self) -> usize {
        self.index.len()
    }
}

/// Test hook, not an API: the environment variable a crash test sets to a number of milliseconds that every commit
/// then sleeps between making its batch file durable (renamed into `batches/`) and appending its journal line, so
/// that a kill can land inside a commit ([`crate::test_hook`]); unset (or not a number) means no pause.
#[doc(hidden)]
pub const TEST_COMMIT_PAUSE_ENV: &str = "METAPLATE_TEST_COMMIT_PAUSE_MS";

/// Makes `dir` an empty directory, or refuses.
fn prepare_dir(dir: &Path, if_exists: IfExists) -> Result<(), StoreError> {
    if !dir.exists() {
        fs::create_dir_all(dir).map_err(StoreError::io("create directory", dir))?;
        if let Some(parent) = dir.parent().filter(|p| !p.as_os_str().is_empty()) {
            durable::sync_dir(parent)?;
        }
        return Ok(());
    }
    let names = durable::entry_names(dir)?;
    let refuse = |entry: &str| Err(StoreError::NotEmpty { dir: dir.to_path_buf(), entry: entry.to_string() });
    match (if_exists, names.first()) {
        (_, None) => return Ok(()),
        (IfExists::Refuse, Some(first)) => return refuse(first),
        (IfExists::Replace, _) => {}
    }
    // Look at every entry before deleting any, so that a refusal deletes nothing.
    let batch_dir = dir.join(BATCH_DIR);
    let batch_files = if batch_dir.is_dir() { durable::entry_names(&batch_dir)? } else { Vec::new() };
    let quarantine_dir = dir.join(QUARANTINE_DIR);
    let own_dir = |n: &str| (n == BATCH_DIR || n == QUARANTINE_DIR) && dir.join(n).is_dir();
    if let Some(foreign) = names.iter().find(|n| !(is_own_root_file(n) || own_dir(n))) {
        return refuse(foreign);
    }
    if let Some(foreign) = batch_files.iter().find(|n| !is_own_batch_file(n)) {
        return refuse(&format!("{BATCH_DIR}/{foreign}"));
    }
    // The manifest goes first: from that moment the directory is no longer a finished dataset, whatever happens next.
    let remove = |path: PathBuf| fs::remove_file(&path).map_err(StoreError::io("remove", &path));
    if names.iter().any(|n| n == MANIFEST_FILE) {
        remove(dir.join(MANIFEST_FILE))?;
        durable::sync_dir(dir)?;
    }
    for name in &batch_files {
        remove(batch_dir.join(name))?;
    }
    if batch_dir.is_dir() {
        fs::remove_dir(&batch_dir).map_err(StoreError::io("remove directory", &batch_dir))?;
    }
    if quarantine_dir.is_dir() {
        // Everything in it was moved there by resume: files of this dataset.
        fs::remove_dir_all(&quarantine_dir).map_err(StoreError::io("remove directory", &quarantine_dir))?;
    }
    for name in names.iter().filter(|n| !matches!(n.as_str(), MANIFEST_FILE | BATCH_DIR | QUARANTINE_DIR)) {
        remove(dir.join(name))?;
    }
    durable::sync_dir(dir)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn batch_names_sort_in_commit_order_and_are_recognised_as_own() {
        assert_eq!(batch_file_name(0), "batch-000000.parquet");
        assert!(batch_file_name(9) < batch_file_name(10));
        assert!(is_own_batch_file(&batch_file_name(123)));
        assert!(is_own_batch_file("compacted-000012.parquet"));
        for foreign in ["batch-.parquet", "batch-01a.parquet", ".batch-000001.parquet.tmp", "notes.parquet"] {
            assert!(!is_own_batch_file(foreign), "{foreign}");
        }
        for own in ["manifest.json", ".manifest.json.tmp", ".batch-000001.parquet.tmp", "journal.jsonl"] {
            assert!(is_own_root_file(own), "{own}");
        }
        for foreign in ["notes.txt", "batch-000001.parquet", "manifest.json.bak", ".manifest.json", "batches"] {
            assert!(!is_own_root_file(foreign), "{foreign}");
        }
    }
}

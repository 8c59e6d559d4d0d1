//! Writing a dataset: one durable Parquet file per committed batch, then the manifest.

use std::fs;
use std::path::{Path, PathBuf};

use chrono::{SecondsFormat, Utc};

use crate::codec;
use crate::durable::{self, TEMP_SUFFIX};
use crate::error::StoreError;
use crate::index::RowIndex;
use crate::manifest::{BATCH_DIR, BatchInfo, DatasetMeta, MANIFEST_FILE, Manifest};
use crate::record::IrRecord;

/// What [`DatasetWriter::create`] does with a directory that already holds files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IfExists {
    /// Refuse with [`StoreError::NotEmpty`]: the safe default, nothing is ever overwritten.
    Refuse,
    /// Delete a previous dataset in it (its manifest, batch files and temporary files) and start afresh. Any other
    /// file makes it refuse with [`StoreError::NotEmpty`], and then nothing has been deleted.
    Replace,
}

/// Writes one dataset directory.
///
/// Each [`commit_batch`](Self::commit_batch) makes one Parquet file durable before it returns; the manifest that
/// lists them is written by [`checkpoint`](Self::checkpoint) or [`finish`](Self::finish). Until then the directory
/// holds batch files but no manifest, and [`crate::Dataset::open`] reports it as unfinished.
#[derive(Debug)]
pub struct DatasetWriter {
    dir: PathBuf,
    manifest: Manifest,
    index: RowIndex,
}

/// File name of batch number `n` (0-based); zero-padded so that names sort in commit order.
fn batch_file_name(n: usize) -> String {
    format!("batch-{n:06}.parquet")
}

/// Whether `name` is a batch file name this writer gives (`batch-` digits `.parquet`).
fn is_own_batch_file(name: &str) -> bool {
    name.strip_prefix("batch-")
        .and_then(|n| n.strip_suffix(".parquet"))
        .is_some_and(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
}

/// Whether `name`, in the dataset directory itself, is a file a writer of this crate creates: the manifest, or a
/// temporary of the manifest or of a batch file.
fn is_own_root_file(name: &str) -> bool {
    let target = name.strip_prefix('.').and_then(|n| n.strip_suffix(TEMP_SUFFIX));
    name == MANIFEST_FILE || target.is_some_and(|t| t == MANIFEST_FILE || is_own_batch_file(t))
}

impl DatasetWriter {
    /// Starts a dataset in `dir` (created if missing, with its parents) described by `meta`, and creates its empty
    /// [`BATCH_DIR`].
    ///
    /// # Errors
    /// [`StoreError::UnsupportedSchemaVersion`] or [`StoreError::InvalidMeta`] for bad metadata;
    /// [`StoreError::NotEmpty`] if `dir` holds files and `if_exists` does not allow replacing them;
    /// [`StoreError::Io`] if `dir` is not a writable directory.
    pub fn create(dir: impl AsRef<Path>, meta: DatasetMeta, if_exists: IfExists) -> Result<Self, StoreError> {
        meta.validate()?;
        let dir = dir.as_ref().to_path_buf();
        prepare_dir(&dir, if_exists)?;
        let batch_dir = dir.join(BATCH_DIR);
        fs::create_dir(&batch_dir).map_err(StoreError::io("create directory", &batch_dir))?;
        durable::sync_dir(&dir)?;
        let config_hash = meta.config_hash();
        let created_at = Utc::now().to_rfc3339_opts(SecondsFormat::Millis, true);
        let manifest = Manifest { meta, created_at, batches: Vec::new(), config_hash };
        Ok(Self { dir, manifest, index: RowIndex::default() })
    }

    /// Writes `records` as the next batch file, durably (temporary name, fsync, atomic rename, directory fsync).
    ///
    /// The batch is checked whole before anything is written: every record valid against the grid, each
    /// (point, actuator) pair once across the whole dataset, one IR length and one sample rate. A refused or failed
    /// commit writes nothing and leaves the writer as it was.
    ///
    /// # Errors
    /// [`StoreError::EmptyBatch`], [`StoreError::InvalidRecord`], [`StoreError::Duplicate`],
    /// [`StoreError::Inconsistent`] (each naming the row), or [`StoreError::Io`] / [`StoreError::Parquet`].
    pub fn commit_batch(&mut self, records: &[IrRecord]) -> Result<BatchInfo, StoreError> {
        let file = batch_file_name(self.manifest.batches.len());
        let rows = records.iter().map(|r| (&r.meta, r.ir.as_slice()));
        let checked = self.index.check(&file, &self.manifest.meta.grid, rows)?;
        // Staged in the dataset directory, so that `batches/` only ever holds finished files.
        let written = durable::write_file_into(&self.dir, &self.dir.join(BATCH_DIR), &file, |sink| {
            codec::write_parquet(sink, records, &file)
        })?;
        self.index.accept(checked);
        let info =
            BatchInfo { file, rows: records.len() as u64, size_bytes: written.size_bytes, checksum: written.checksum };
        self.manifest.batches.push(info.clone());
        Ok(info)
    }

    /// Writes `manifest.json` durably, listing every batch committed so far; the dataset can then be opened. May be
    /// called again after further commits: each call replaces the manifest atomically.
    ///
    /// # Errors
    /// [`StoreError::EmptyDataset`] before the first commit; [`StoreError::Io`].
    pub fn checkpoint(&mut self) -> Result<&Manifest, StoreError> {
        if self.manifest.batches.is_empty() {
            return Err(StoreError::EmptyDataset { dir: self.dir.clone() });
        }
        self.manifest.write(&self.dir)?;
        Ok(&self.manifest)
    }

    /// [`checkpoint`](Self::checkpoint), then hands back the final manifest.
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

/// Sorted entry names of `dir`.
fn entries(dir: &Path) -> Result<Vec<String>, StoreError> {
    let mut names = Vec::new();
    for entry in fs::read_dir(dir).map_err(StoreError::io("list directory", dir))? {
        let entry = entry.map_err(StoreError::io("list directory", dir))?;
        names.push(entry.file_name().to_string_lossy().into_owned());
    }
    names.sort_unstable();
    Ok(names)
}

/// Makes `dir` an empty directory, or refuses.
fn prepare_dir(dir: &Path, if_exists: IfExists) -> Result<(), StoreError> {
    if !dir.exists() {
        fs::create_dir_all(dir).map_err(StoreError::io("create directory", dir))?;
        if let Some(parent) = dir.parent().filter(|p| !p.as_os_str().is_empty()) {
            durable::sync_dir(parent)?;
        }
        return Ok(());
    }
    let names = entries(dir)?;
    let refuse = |entry: &str| Err(StoreError::NotEmpty { dir: dir.to_path_buf(), entry: entry.to_string() });
    match (if_exists, names.first()) {
        (_, None) => return Ok(()),
        (IfExists::Refuse, Some(first)) => return refuse(first),
        (IfExists::Replace, _) => {}
    }
    // Look at every entry before deleting any, so that a refusal deletes nothing.
    let batch_dir = dir.join(BATCH_DIR);
    let batch_files = if batch_dir.is_dir() { entries(&batch_dir)? } else { Vec::new() };
    if let Some(foreign) = names.iter().find(|n| !(is_own_root_file(n) || (*n == BATCH_DIR && batch_dir.is_dir()))) {
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
    for name in names.iter().filter(|n| *n != MANIFEST_FILE && *n != BATCH_DIR) {
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
        for foreign in ["batch-.parquet", "batch-01a.parquet", ".batch-000001.parquet.tmp", "notes.parquet"] {
            assert!(!is_own_batch_file(foreign), "{foreign}");
        }
        for own in ["manifest.json", ".manifest.json.tmp", ".batch-000001.parquet.tmp"] {
            assert!(is_own_root_file(own), "{own}");
        }
        for foreign in ["notes.txt", "batch-000001.parquet", "manifest.json.bak", ".manifest.json", "batches"] {
            assert!(!is_own_root_file(foreign), "{foreign}");
        }
    }
}

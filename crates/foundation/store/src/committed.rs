//! The committed batch files, for readers other than [`Dataset`] (polars, pyarrow).

use std::path::{Path, PathBuf};

use crate::error::StoreError;
use crate::journal::{self, Live};
use crate::manifest::{BATCH_DIR, Manifest};
use crate::reader::Dataset;

impl Dataset {
    /// The Parquet files the journal commits (or, for a dataset written before the journal, the manifest lists), in
    /// commit order: what another reader should read. Orphans and superseded files in `batches/` are not listed.
    /// Nothing is verified here: use [`Dataset::open`] to verify.
    ///
    /// # Errors
    /// The manifest and journal errors of [`Dataset::open`]; [`StoreError::EmptyDataset`] if nothing is committed.
    pub fn committed_files(dir: impl AsRef<Path>) -> Result<Vec<PathBuf>, StoreError> {
        let dir = dir.as_ref();
        let manifest = Manifest::read(dir)?;
        let files: Vec<String> = match journal::read(dir)? {
            Some(read) => Live::replay(&read.entries).batches.into_iter().map(|b| b.file).collect(),
            None => manifest.batches.into_iter().map(|b| b.file).collect(),
        };
        if files.is_empty() {
            return Err(StoreError::EmptyDataset { dir: dir.to_path_buf() });
        }
        Ok(files.iter().map(|file| dir.join(BATCH_DIR).join(file)).collect())
    }
}

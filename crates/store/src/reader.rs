//! Reading a finished dataset into memory, every file verified against its checksum first.

use std::fs;
use std::path::Path;

use bytes::Bytes;

use crate::checksum;
use crate::codec;
use crate::error::StoreError;
use crate::index::RowIndex;
use crate::journal::{self, BatchEntry, JOURNAL_FILE, Live};
use crate::manifest::{BATCH_DIR, BatchInfo, Manifest};
use crate::record::IrMeta;

/// A dataset in memory, in columnar form: per-row metadata, and all impulse responses back to back in one `Vec<f32>`
/// (row `r` at `r * ir_len()..(r + 1) * ir_len()`), with a (point, actuator) lookup.
///
/// Rows are in file order (batches in commit order). Memory: about `4 * ir_len + 100` bytes per row; a full
/// 1225-point, 8-actuator dataset of 12000-sample responses takes about 470 MB.
#[derive(Debug)]
pub struct Dataset {
    manifest: Manifest,
    metas: Vec<IrMeta>,
    irs: Vec<f32>,
    ir_len: usize,
    sample_rate_hz: f64,
    index: RowIndex,
    points: Vec<u32>,
    actuators: Vec<u16>,
    notes: Vec<String>,
}

/// How [`Dataset::open_with`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadOptions {
    /// Verify each file's SHA-256 before parsing it (default `true`). Skipping it saves about 0.4 s per 470 MB (the
    /// full paper dataset) and is for interactive use on trusted copies: sizes, row counts and keys are still
    /// checked, and Parquet's own page checks still catch most damage, but a bit flip inside a sample goes unseen.
    pub verify_checksums: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self { verify_checksums: true }
    }
}

impl Dataset {
    /// Opens the dataset in `dir` with [`ReadOptions::default`] (every checksum verified); see
    /// [`Dataset::open_with`].
    ///
    /// # Errors
    /// As [`Dataset::open_with`].
    pub fn open(dir: impl AsRef<Path>) -> Result<Self, StoreError> {
        Self::open_with(dir, ReadOptions::default())
    }

    /// Opens the dataset in `dir`: reads and checks `manifest.json`; takes the list of committed files from
    /// `journal.jsonl` (authoritative: every commit is readable at once, before any checkpoint; a torn or damaged
    /// line is skipped and listed in [`Dataset::notes`]), or from the manifest for a dataset written before the
    /// journal existed; verifies each file's size and (unless `options` says otherwise) SHA-256 before parsing it;
    /// and reads every row, checking the same rules the writer enforces (rows valid against the grid, each
    /// (point, actuator) once, one IR length, one sample rate, and the keys the journal lists).
    ///
    /// Files in `batches/` that the journal does not list (orphans of a crash, batches superseded by a compaction)
    /// are not part of the dataset and are not read.
    ///
    /// # Errors
    /// - manifest: [`StoreError::ManifestMissing`] (not a dataset), [`StoreError::ManifestMalformed`],
    ///   [`StoreError::UnsupportedSchemaVersion`], [`StoreError::ConfigHashMismatch`] (edited after writing);
    ///   [`StoreError::EmptyDataset`] if nothing is committed;
    /// - a batch file: [`StoreError::BatchMissing`], [`StoreError::SizeMismatch`] (truncated),
    ///   [`StoreError::ChecksumMismatch`] (corrupt), [`StoreError::Parquet`], [`StoreError::SchemaMismatch`],
    ///   [`StoreError::RowCountMismatch`], [`StoreError::KeysMismatch`];
    /// - a row: [`StoreError::InvalidRecord`], [`StoreError::Duplicate`], [`StoreError::Inconsistent`];
    /// - [`StoreError::Io`] for any other failure to read.
    pub fn open_with(dir: impl AsRef<Path>, options: ReadOptions) -> Result<Self, StoreError> {
        let dir = dir.as_ref();
        let mut manifest = Manifest::read(dir)?;
        let mut notes = Vec::new();
        // Each file with the keys its journal entry lists (none for a manifest-only dataset).
        type Keys = Option<Vec<(u32, u16)>>;
        let batches: Vec<(BatchInfo, Keys)> = match journal::read(dir)? {
            Some(read) => {
                let live = Live::replay(&read.entries);
                for issue in read.issues.iter().chain(&live.issues) {
                    notes.push(format!("{JOURNAL_FILE} line {} ignored: {}", issue.line, issue.reason));
                }
                manifest.batches = live.batches.iter().map(BatchEntry::info).collect();
                live.batches.into_iter().map(|b| (b.info(), Some(b.keys))).collect()
            }
            None => manifest.batches.iter().map(|b| (b.clone(), None)).collect(),
        };
        if batches.is_empty() {
            return Err(StoreError::EmptyDataset { dir: dir.to_path_buf() });
        }
        let mut index = RowIndex::default();
        let mut metas = Vec::new();
        let mut irs = Vec::new();
        for (batch, keys) in &batches {
            let bytes = read_verified(dir, batch, options.verify_checksums)?;
            let decoded = codec::read_parquet(bytes, &batch.file)?;
            if decoded.metas.len() as u64 != batch.rows {
                return Err(StoreError::RowCountMismatch {
                    file: batch.file.clone(),
                    expected: batch.rows,
                    actual: decoded.metas.len() as u64,
                });
            }
            if let Some(keys) = keys
                && let Some(row) = decoded.metas.iter().zip(keys).position(|(m, k)| m.key() != *k)
            {
                let reason = format!("row {row} is {:?}, the journal says {:?}", decoded.metas[row].key(), keys[row]);
                return Err(StoreError::KeysMismatch { file: batch.file.clone(), reason });
            }
            let checked = index.check(&batch.file, &manifest.meta.grid, decoded.rows())?;
            index.accept(checked);
            metas.extend_from_slice(&decoded.metas);
            // Every row has the dataset's IR length (checked above), so the values append back to back.
            irs.extend_from_slice(&decoded.ir_values);
        }
        let (Some(ir_len), Some(sample_rate_hz)) = (index.ir_len(), index.sample_rate_hz()) else {
            return Err(StoreError::EmptyDataset { dir: dir.to_path_buf() });
        };
        let mut points: Vec<u32> = metas.iter().map(|m| m.point_index).collect();
        points.sort_unstable();
        points.dedup();
        let mut actuators: Vec<u16> = metas.iter().map(|m| m.actuator).collect();
        actuators.sort_unstable();
        actuators.dedup();
        Ok(Self { manifest, metas, irs, ir_len, sample_rate_hz, index, points, actuators, notes })
    }

    /// What the reader skipped and why (journal lines torn by a crash or damaged); empty for a clean dataset.
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The Green's functions of `points` x `actuators` as one array of shape
    /// `(points.len(), actuators.len(), ir_len())`, row-major: the response from `actuators[a]` at `points[p]` is
    /// `[(p * actuators.len() + a) * ir_len()..][..ir_len()]`. Samples are f32 as stored.
    ///
    /// # Errors
    /// [`StoreError::NotInDataset`] naming the first pair the dataset lacks.
    pub fn ir_matrix(&self, points: &[u32], actuators: &[u16]) -> Result<Vec<f32>, StoreError> {
        let mut out = Vec::with_capacity(points.len() * actuators.len() * self.ir_len);
        for &point_index in points {
            for &actuator in actuators {
                let ir = self.ir(point_index, actuator).ok_or(StoreError::NotInDataset { point_index, actuator })?;
                out.extend_from_slice(ir);
            }
        }
        Ok(out)
    }

    /// The manifest, its batch list as the journal has it.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// Number of rows (impulse responses); at least 1.
    pub fn len(&self) -> usize {
        self.metas.len()
    }

    /// Always false: an empty dataset does not open. Present for the `len`/`is_empty` convention.
    pub fn is_empty(&self) -> bool {
        self.metas.is_empty()
    }

    /// Length of every impulse response, samples (at least 1).
    pub fn ir_len(&self) -> usize {
        self.ir_len
    }

    /// Sample rate of every impulse response, Hz (finite, positive).
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// Grid point indices present, ascending, each once.
    pub fn points(&self) -> &[u32] {
        &self.points
    }

    /// Actuator numbers present, ascending, each once.
    pub fn actuators(&self) -> &[u16] {
        &self.actuators
    }

    /// Metadata of every row, in file order.
    pub fn rows(&self) -> &[IrMeta] {
        &self.metas
    }

    /// All impulse responses back to back, in row order (`len() * ir_len()` samples).
    pub fn irs(&self) -> &[f32] {
        &self.irs
    }

    /// The impulse response of row `row`, or `None` past the last row.
    pub fn row_ir(&self, row: usize) -> Option<&[f32]> {
        let start = row.checked_mul(self.ir_len)?;
        self.irs.get(start..start.checked_add(self.ir_len)?)
    }

    /// The impulse response from `actuator` to grid point `point_index`, or `None` if the dataset lacks the pair.
    pub fn ir(&self, point_index: u32, actuator: u16) -> Option<&[f32]> {
        self.row_ir(self.index.row(point_index, actuator)?)
    }

    /// The metadata of (`point_index`, `actuator`), or `None` if the dataset lacks the pair.
    pub fn meta(&self, point_index: u32, actuator: u16) -> Option<&IrMeta> {
        self.metas.get(self.index.row(point_index, actuator)?)
    }
}

/// Reads one batch file whole and checks its size and (if `verify`) checksum against the journal or manifest, so
/// that only verified bytes reach the Parquet decoder.
pub(crate) fn read_verified(dir: &Path, batch: &BatchInfo, verify: bool) -> Result<Bytes, StoreError> {
    let path = dir.join(BATCH_DIR).join(&batch.file);
    let bytes = match fs::read(&path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(StoreError::BatchMissing { file: batch.file.clone() });
        }
        Err(e) => return Err(StoreError::Io { op: "read", path, source: e }),
    };
    if bytes.len() as u64 != batch.size_bytes {
        return Err(StoreError::SizeMismatch {
            file: batch.file.clone(),
            expected_bytes: batch.size_bytes,
            actual_bytes: bytes.len() as u64,
        });
    }
    if !verify {
        return Ok(Bytes::from(bytes));
    }
    let actual = checksum::sha256(&bytes);
    if actual != batch.checksum {
        return Err(StoreError::ChecksumMismatch {
            file: batch.file.clone(),
            expected: batch.checksum.clone(),
            actual,
        });
    }
    Ok(Bytes::from(bytes))
}

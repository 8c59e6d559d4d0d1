//! Reading a finished dataset into memory, every file verified against its checksum first.

use std::fs;
use std::path::Path;

use bytes::Bytes;

use crate::checksum;
use crate::codec;
use crate::error::StoreError;
use crate::index::RowIndex;
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
}

impl Dataset {
    /// Opens the dataset in `dir`: reads and checks `manifest.json`, verifies each listed batch file's size and
    /// SHA-256 before parsing it, and reads every row, checking the same rules the writer enforces (rows valid against
    /// the grid, each (point, actuator) once, one IR length, one sample rate).
    ///
    /// # Errors
    /// - manifest: [`StoreError::ManifestMissing`] (absent: not finished, or not a dataset),
    ///   [`StoreError::ManifestMalformed`], [`StoreError::UnsupportedSchemaVersion`],
    ///   [`StoreError::ConfigHashMismatch`] (edited after writing); [`StoreError::EmptyDataset`] if it lists no batch;
    /// - a batch file: [`StoreError::BatchMissing`], [`StoreError::SizeMismatch`] (truncated),
    ///   [`StoreError::ChecksumMismatch`] (corrupt), [`StoreError::Parquet`], [`StoreError::SchemaMismatch`],
    ///   [`StoreError::RowCountMismatch`];
    /// - a row: [`StoreError::InvalidRecord`], [`StoreError::Duplicate`], [`StoreError::Inconsistent`];
    /// - [`StoreError::Io`] for any other failure to read.
    pub fn open(dir: impl AsRef<Path>) -> Result<Self, StoreError> {
        let dir = dir.as_ref();
        let manifest = Manifest::read(dir)?;
        if manifest.batches.is_empty() {
            return Err(StoreError::EmptyDataset { dir: dir.to_path_buf() });
        }
        let mut index = RowIndex::default();
        let mut metas = Vec::new();
        let mut irs = Vec::new();
        for batch in &manifest.batches {
            let bytes = read_verified(dir, batch)?;
            let decoded = codec::read_parquet(bytes, &batch.file)?;
            if decoded.metas.len() as u64 != batch.rows {
                return Err(StoreError::RowCountMismatch {
                    file: batch.file.clone(),
                    expected: batch.rows,
                    actual: decoded.metas.len() as u64,
                });
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
        Ok(Self { manifest, metas, irs, ir_len, sample_rate_hz, index, points, actuators })
    }

    /// The manifest.
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

/// Reads one batch file whole and checks its size and checksum against the manifest, so that only verified bytes
/// reach the Parquet decoder.
fn read_verified(dir: &Path, batch: &BatchInfo) -> Result<Bytes, StoreError> {
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

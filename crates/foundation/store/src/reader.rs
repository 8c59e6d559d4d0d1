//! Reading a finished dataset into memory, every file verified against its checksum first.

use std::collections::BTreeSet;
use std::fs::File;
use std::io::Read;
use std::num::NonZeroUsize;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, PoisonError, mpsc};
use std::thread;

use bytes::Bytes;

use crate::checksum;
use crate::codec::{self, Decoded};
use crate::error::StoreError;
use crate::index::RowIndex;
use crate::journal::{self, BatchEntry, JOURNAL_FILE, Live};
use crate::manifest::{BATCH_DIR, BatchInfo, Manifest};
use crate::record::{IrMeta, IrRecord};

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
    /// Verify each file's SHA-256 before parsing it (default `true`). Skipping it saves the hash, about 0.27 s of CPU
    /// per 470 MB (the full paper dataset; 1.75 GB/s per core with the CPU's SHA extensions), and is for interactive
    /// use on trusted copies: sizes, row counts and keys are still checked, and Parquet's own page checks still catch
    /// most damage, but a bit flip inside a sample goes unseen.
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
    /// Files are read, verified and decoded on up to one thread per available core (at most 8), each file whole on
    /// one thread, so a dataset of several files opens faster than one compacted file; rows keep file order, and
    /// the error returned is the one a file-by-file read would meet first.
    ///
    /// # Errors
    /// - manifest: [`StoreError::ManifestMissing`] (not a dataset), [`StoreError::ManifestMalformed`],
    ///   [`StoreError::UnsupportedSchemaVersion`], [`StoreError::ConfigHashMismatch`] (edited after writing);
    ///   [`StoreError::EmptyDataset`] if nothing is committed;
    /// - a batch file: [`StoreError::BatchMissing`], [`StoreError::SizeMismatch`] (truncated),
    ///   [`StoreError::ChecksumMismatch`] (corrupt), [`StoreError::Parquet`] or [`StoreError::Arrow`] (not
    ///   decodable), [`StoreError::SchemaMismatch`], [`StoreError::RowCountMismatch`], [`StoreError::KeysMismatch`];
    /// - a row: [`StoreError::InvalidRecord`], [`StoreError::Duplicate`], [`StoreError::Inconsistent`];
    /// - [`StoreError::Io`] for any other failure to read.
    pub fn open_with(dir: impl AsRef<Path>, options: ReadOptions) -> Result<Self, StoreError> {
        let threads = thread::available_parallelism().map_or(1, NonZeroUsize::get).min(MAX_THREADS);
        Self::open_on(dir.as_ref(), options, threads)
    }

    /// [`Dataset::open_with`] on at most `threads` threads (1: all on the calling thread).
    fn open_on(dir: &Path, options: ReadOptions, threads: usize) -> Result<Self, StoreError> {
        let mut metas = Vec::new();
        let mut irs = Vec::new();
        let read = read_committed(dir, options, threads, |total_rows, ir_len, decoded| {
            if irs.is_empty() {
                // Room for every row the journal lists, so that the 470 MB of a full dataset are not reallocated as
                // they grow. Only a hint: the counts are not trusted, and a failed reservation just means growing.
                let rows = usize::try_from(total_rows).unwrap_or(usize::MAX);
                let _ = metas.try_reserve_exact(rows);
                let _ = irs.try_reserve_exact(rows.saturating_mul(ir_len));
            }
            metas.extend_from_slice(&decoded.metas);
            // Every row has the dataset's IR length (checked), so the values append back to back.
            irs.extend_from_slice(&decoded.ir_values);
            Ok(())
        })?;
        let Committed { manifest, index, notes } = read;
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

    /// Reads the dataset in `dir` one committed file at a time, without holding it whole: the same checks as
    /// [`Dataset::open_with`] (the same files, in the same order), and each file's rows handed to `consume` as soon
    /// as they are read and checked. Memory: a few decoded files at once (a compacted dataset is one file, read
    /// whole). Returns the manifest, its batch list as the journal has it.
    ///
    /// # Errors
    /// As [`Dataset::open_with`], or the first error of `consume` (no file after it is read).
    pub fn stream<E: From<StoreError>>(
        dir: impl AsRef<Path>,
        options: ReadOptions,
        mut consume: impl FnMut(BatchRows<'_>) -> Result<(), E>,
    ) -> Result<Manifest, E> {
        let threads = thread::available_parallelism().map_or(1, NonZeroUsize::get).min(MAX_THREADS);
        let mut consumer_error = None;
        let read = read_committed(dir.as_ref(), options, threads, |_, ir_len, decoded| {
            let rows = BatchRows { rows: &decoded.metas, irs: &decoded.ir_values, ir_len };
            consume(rows).map_err(|e| {
                consumer_error = Some(e);
                // Only stops the read: the consumer's own error is returned below.
                StoreError::InvalidRecord { location: "stream".into(), reason: "stopped by its consumer".into() }
            })
        });
        match (read, consumer_error) {
            (_, Some(e)) => Err(e),
            (Err(e), None) => Err(e.into()),
            (Ok(read), None) => Ok(read.manifest),
        }
    }

    /// The (point, actuator) keys the journal of the dataset in `dir` commits, sorted, read from the journal alone
    /// (no batch file is opened or verified: a count for a progress bar, the points an exporter lists first);
    /// `None` for a dataset written before the journal existed.
    ///
    /// # Errors
    /// [`StoreError::Io`] if the journal exists but cannot be read.
    pub fn committed_keys(dir: impl AsRef<Path>) -> Result<Option<BTreeSet<(u32, u16)>>, StoreError> {
        Ok(journal::read(dir.as_ref())?
            .map(|read| Live::replay(&read.entries).batches.iter().flat_map(|b| b.keys.iter().copied()).collect()))
    }

    /// Reads one committed file of the dataset in `dir`, as its journal entry `batch` describes it (from
    /// [`crate::journal::view`]): its size and (unless `options` says otherwise) SHA-256 verified, its row count and
    /// keys checked against the entry. For a reader that follows a dataset file by file as it grows.
    ///
    /// # Errors
    /// [`StoreError::BatchMissing`] (also when a resume has just quarantined it), [`StoreError::SizeMismatch`],
    /// [`StoreError::ChecksumMismatch`], [`StoreError::Parquet`] / [`StoreError::Arrow`],
    /// [`StoreError::RowCountMismatch`], [`StoreError::KeysMismatch`], [`StoreError::Io`].
    pub fn read_batch(
        dir: impl AsRef<Path>,
        batch: &BatchEntry,
        options: ReadOptions,
    ) -> Result<Vec<IrRecord>, StoreError> {
        let mut decoded = Decoded::default();
        load(dir.as_ref(), &batch.info(), options.verify_checksums, &mut Vec::new(), &mut decoded)?;
        check_rows(&batch.file, batch.rows, Some(&batch.keys), &decoded)?;
        Ok(decoded.rows().map(|(meta, ir)| IrRecord { meta: *meta, ir: ir.to_vec() }).collect())
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

/// The rows of one committed file, as [`Dataset::stream`] hands them over.
#[derive(Debug, Clone, Copy)]
pub struct BatchRows<'a> {
    /// Metadata of each row, in file order.
    pub rows: &'a [IrMeta],
    /// Their impulse responses back to back (row `r` at `r * ir_len..(r + 1) * ir_len`).
    pub irs: &'a [f32],
    /// Length of every impulse response of the dataset, samples.
    pub ir_len: usize,
}

impl<'a> BatchRows<'a> {
    /// Each row with its impulse response.
    pub fn iter(&self) -> impl Iterator<Item = (&'a IrMeta, &'a [f32])> + use<'a> {
        let ir_len = self.ir_len.max(1);
        self.rows.iter().zip(self.irs.chunks_exact(ir_len))
    }
}

/// What [`read_committed`] read besides the rows.
struct Committed {
    manifest: Manifest,
    index: RowIndex,
    notes: Vec<String>,
}

/// Reads the committed files of the dataset in `dir` (see [`Dataset::open_with`]) and hands each file's rows,
/// checked, to `consume` with the total row count the journal lists (a hint) and the dataset's IR length.
fn read_committed(
    dir: &Path,
    options: ReadOptions,
    threads: usize,
    mut consume: impl FnMut(u64, usize, &Decoded) -> Result<(), StoreError>,
) -> Result<Committed, StoreError> {
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
    let files: Vec<&BatchInfo> = batches.iter().map(|(info, _)| info).collect();
    let total_rows = batches.iter().map(|(info, _)| info.rows).fold(0, u64::saturating_add);
    let mut index = RowIndex::default();
    for_each_file(dir, &files, options.verify_checksums, threads, |i, decoded| {
        let Some((batch, keys)) = batches.get(i) else { return Ok(()) };
        check_rows(&batch.file, batch.rows, keys.as_deref(), decoded)?;
        let checked = index.check(&batch.file, &manifest.meta.grid, decoded.rows())?;
        let ir_len = checked.ir_len();
        index.accept(checked);
        consume(total_rows, ir_len, decoded)
    })?;
    Ok(Committed { manifest, index, notes })
}

/// Checks a decoded file against what its journal entry (or manifest line) says: `rows` rows, and, when the journal
/// lists them, these keys in this order.
///
/// # Errors
/// [`StoreError::RowCountMismatch`], [`StoreError::KeysMismatch`].
fn check_rows(file: &str, rows: u64, keys: Option<&[(u32, u16)]>, decoded: &Decoded) -> Result<(), StoreError> {
    if decoded.metas.len() as u64 != rows {
        return Err(StoreError::RowCountMismatch {
            file: file.to_owned(),
            expected: rows,
            actual: decoded.metas.len() as u64,
        });
    }
    if let Some(keys) = keys
        && let Some(row) = decoded.metas.iter().zip(keys).position(|(m, k)| m.key() != *k)
    {
        let reason = format!("row {row} is {:?}, the journal says {:?}", decoded.metas[row].key(), keys[row]);
        return Err(StoreError::KeysMismatch { file: file.to_owned(), reason });
    }
    Ok(())
}

/// Most threads [`Dataset::open_with`] reads and decodes files on: past a few, the disk is the limit.
const MAX_THREADS: usize = 8;

/// Reads, verifies (as [`read_verified`]) and decodes each of `files` in `dir`, and hands each decoded file to
/// `consume` on the calling thread, in the order of `files`.
///
/// With `threads` > 1 (and more than one file), that many scoped worker threads read, hash and decode files ahead
/// of `consume`: at most `2 * threads` decoded files are held at once, the one being consumed included, which bounds
/// the memory beyond the dataset itself. Files reach `consume` in the same order, and the error returned is the
/// same, as when decoding one file after the other: the first in file order, whether of reading, decoding or
/// `consume`; no file after it is consumed.
///
/// # Errors
/// As [`read_verified`] and [`codec::read_parquet_into`], or the first error of `consume`.
fn for_each_file(
    dir: &Path,
    files: &[&BatchInfo],
    verify: bool,
    threads: usize,
    mut consume: impl FnMut(usize, &Decoded) -> Result<(), StoreError>,
) -> Result<(), StoreError> {
    let threads = threads.min(files.len());
    if threads <= 1 {
        let (mut buffer, mut decoded) = (Vec::new(), Decoded::default());
        for (i, info) in files.iter().enumerate() {
            load(dir, info, verify, &mut buffer, &mut decoded)?;
            consume(i, &decoded)?;
        }
        return Ok(());
    }
    let window = 2 * threads;
    // Tickets: which file to load next, with a buffer to decode it into (one already consumed, once there is one).
    let (ticket_tx, ticket_rx) = mpsc::channel::<(usize, Decoded)>();
    let ticket_rx = Mutex::new(ticket_rx);
    let (done_tx, done_rx) = mpsc::channel::<(usize, Result<Decoded, StoreError>)>();
    let stop = AtomicBool::new(false);
    thread::scope(|scope| {
        for _ in 0..threads {
            let done_tx = done_tx.clone();
            let (ticket_rx, stop) = (&ticket_rx, &stop);
            scope.spawn(move || {
                let mut buffer = Vec::new();
                loop {
                    // Ends when the consumer has gone (its ticket sender is dropped) or stops early on an error.
                    let ticket = ticket_rx.lock().unwrap_or_else(PoisonError::into_inner).recv();
                    let Ok((i, mut decoded)) = ticket else { break };
                    let Some(info) = files.get(i).filter(|_| !stop.load(Ordering::Relaxed)) else { break };
                    let result = load(dir, info, verify, &mut buffer, &mut decoded).map(|()| decoded);
                    if done_tx.send((i, result)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(done_tx);
        // Moved in, so that it is dropped (and idle workers end) as soon as this closure returns, before the scope
        // joins them.
        let ticket_tx = ticket_tx;
        for i in 0..files.len().min(window) {
            let _ = ticket_tx.send((i, Decoded::default()));
        }
        let mut ready: Vec<Option<Result<Decoded, StoreError>>> = files.iter().map(|_| None).collect();
        let result = (|| {
            for (i, info) in files.iter().enumerate() {
                let decoded = loop {
                    if let Some(result) = ready.get_mut(i).and_then(Option::take) {
                        break result?;
                    }
                    match done_rx.recv() {
                        Ok((j, result)) => {
                            if let Some(slot) = ready.get_mut(j) {
                                *slot = Some(result);
                            }
                        }
                        // Every worker has ended without delivering file i: only a panic does that, and the scope
                        // raises it again when this closure returns.
                        Err(_) => {
                            let path = dir.join(BATCH_DIR).join(&info.file);
                            let source = std::io::Error::other("a reader thread stopped");
                            return Err(StoreError::Io { op: "read", path, source });
                        }
                    }
                };
                consume(i, &decoded)?;
                if i + window < files.len() {
                    let _ = ticket_tx.send((i + window, decoded));
                }
            }
            Ok(())
        })();
        stop.store(true, Ordering::Relaxed);
        result
    })
}

/// Reads, verifies and decodes the file `info` of `dir` into `decoded`, reading its bytes into `buffer` (whose
/// allocation is kept for the next file).
///
/// # Errors
/// As [`read_verified`] and [`codec::read_parquet_into`].
fn load(
    dir: &Path,
    info: &BatchInfo,
    verify: bool,
    buffer: &mut Vec<u8>,
    decoded: &mut Decoded,
) -> Result<(), StoreError> {
    let bytes = read_verified(dir, info, verify, std::mem::take(buffer))?;
    let result = codec::read_parquet_into(bytes.clone(), &info.file, decoded);
    // The decoder has dropped its references: the allocation comes back without a copy (or, were it still shared,
    // the next file gets a fresh one).
    *buffer = bytes.try_into_mut().map(Vec::from).unwrap_or_default();
    result
}

/// Reads one batch file whole into `buffer` (replacing its contents, reusing its allocation) and checks its size
/// and (if `verify`) SHA-256 against the journal or manifest, so that only verified bytes reach the Parquet decoder.
///
/// # Errors
/// [`StoreError::BatchMissing`], [`StoreError::SizeMismatch`], [`StoreError::ChecksumMismatch`], or
/// [`StoreError::Io`] for any other failure to read.
pub(crate) fn read_verified(
    dir: &Path,
    batch: &BatchInfo,
    verify: bool,
    mut buffer: Vec<u8>,
) -> Result<Bytes, StoreError> {
    let path = dir.join(BATCH_DIR).join(&batch.file);
    let file = match File::open(&path) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(StoreError::BatchMissing { file: batch.file.clone() });
        }
        Err(e) => return Err(StoreError::Io { op: "read", path, source: e }),
    };
    let size_mismatch = |actual_bytes| StoreError::SizeMismatch {
        file: batch.file.clone(),
        expected_bytes: batch.size_bytes,
        actual_bytes,
    };
    let size = match file.metadata() {
        Ok(metadata) => metadata.len(),
        Err(e) => return Err(StoreError::Io { op: "read", path, source: e }),
    };
    if size != batch.size_bytes {
        return Err(size_mismatch(size));
    }
    buffer.clear();
    // The size was checked: a failed reservation would fail the read as well, which reports it.
    let _ = buffer.try_reserve_exact(usize::try_from(size).unwrap_or(usize::MAX));
    // At most one byte more than expected: enough to see a file that grew since, without reading all of it.
    if let Err(e) = file.take(size.saturating_add(1)).read_to_end(&mut buffer) {
        return Err(StoreError::Io { op: "read", path, source: e });
    }
    if buffer.len() as u64 != batch.size_bytes {
        return Err(size_mismatch(buffer.len() as u64));
    }
    if verify {
        let actual = checksum::sha256(&buffer);
        if actual != batch.checksum {
            return Err(StoreError::ChecksumMismatch {
                file: batch.file.clone(),
                expected: batch.checksum.clone(),
                actual,
            });
        }
    }
    Ok(Bytes::from(buffer))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use std::fs;

    use super::*;
    use crate::manifest::{DatasetMeta, GridSpec, SceneId};
    use crate::record::IrRecord;
    use crate::writer::{DatasetWriter, IfExists};

    const GRID: GridSpec = GridSpec { nx: 4, ny: 6, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };

    /// A dataset of one batch file per grid row: 6 files of 4 points x 2 actuators, 64-sample responses.
    fn dataset(dir: &Path) {
        let scene = SceneId { name: "none".into(), hash: "0".into() };
        let meta = DatasetMeta::new("test", serde_json::Map::new(), scene, "0", 1, GRID);
        let mut writer = DatasetWriter::create(dir, meta, IfExists::Refuse).unwrap();
        for iy in 0..GRID.ny as u32 {
            let mut records = Vec::new();
            for ix in 0..GRID.nx as u32 {
                for actuator in 0..2u16 {
                    let meta = IrMeta::at_grid(&GRID, ix, iy, actuator, 24_000.0).unwrap();
                    let scale = f32::from(actuator + 1);
                    let ir =
                        (0..64).map(|i| ((i as f32 + 1.0) * 0.37 + meta.point_index as f32).sin() * scale).collect();
                    records.push(IrRecord { meta, ir });
                }
            }
            writer.commit_batch(&records).unwrap();
        }
        writer.finish().unwrap();
    }

    fn batch_path(dir: &Path, n: usize) -> std::path::PathBuf {
        dir.join(BATCH_DIR).join(format!("batch-{n:06}.parquet"))
    }

    const VERIFY: ReadOptions = ReadOptions { verify_checksums: true };
    const TRUST: ReadOptions = ReadOptions { verify_checksums: false };

    #[test]
    fn threads_change_nothing_in_what_is_read() {
        let dir = tempfile::tempdir().unwrap();
        dataset(dir.path());
        let one = Dataset::open_on(dir.path(), VERIFY, 1).unwrap();
        assert_eq!((one.len(), one.ir_len()), (48, 64));
        for threads in [2, 3, 8] {
            for options in [VERIFY, TRUST] {
                let many = Dataset::open_on(dir.path(), options, threads).unwrap();
                assert_eq!(many.rows(), one.rows(), "{threads} threads");
                let bits = |d: &Dataset| d.irs().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&many), bits(&one), "{threads} threads");
                assert_eq!((many.points(), many.actuators()), (one.points(), one.actuators()));
                assert_eq!(many.manifest().batches, one.manifest().batches);
                assert_eq!(many.ir(13, 1), one.ir(13, 1));
            }
        }
    }

    /// Opens on 1 to 8 threads, several times each (workers finish in varying order), and returns the one error all
    /// of them gave.
    fn same_error_on_any_threads(dir: &Path, options: ReadOptions) -> StoreError {
        let first = Dataset::open_on(dir, options, 1).unwrap_err();
        for threads in 2..=8 {
            for _ in 0..5 {
                let err = Dataset::open_on(dir, options, threads).unwrap_err();
                assert_eq!(err.to_string(), first.to_string(), "{threads} threads");
            }
        }
        first
    }

    #[test]
    fn the_first_failing_file_in_order_is_reported_on_any_threads() {
        let dir = tempfile::tempdir().unwrap();
        dataset(dir.path());
        // Files 1 and 2 hold the same number of rows of the same length: the copy keeps the size, changes the keys.
        let (one, two) = (batch_path(dir.path(), 1), batch_path(dir.path(), 2));
        let (original, copy) = (fs::read(&one).unwrap(), fs::read(&two).unwrap());
        assert_eq!(copy.len(), original.len());
        fs::write(&one, &copy).unwrap();
        // And a later file, truncated: an error that a worker may meet before file 1 is consumed.
        let four = batch_path(dir.path(), 4);
        let whole = fs::read(&four).unwrap();
        fs::write(&four, &whole[..whole.len() / 2]).unwrap();
        let err = same_error_on_any_threads(dir.path(), VERIFY);
        assert!(
            matches!(err, StoreError::ChecksumMismatch { ref file, .. } if file == "batch-000001.parquet"),
            "{err}"
        );
        // Unverified, file 1 decodes, and the rows' keys give it away (an error of the consuming thread).
        let err = same_error_on_any_threads(dir.path(), TRUST);
        assert!(matches!(err, StoreError::KeysMismatch { ref file, .. } if file == "batch-000001.parquet"), "{err}");
        // With file 1 repaired, file 4 is the first to fail.
        fs::write(&one, &original).unwrap();
        for options in [VERIFY, TRUST] {
            let err = same_error_on_any_threads(dir.path(), options);
            assert!(
                matches!(err, StoreError::SizeMismatch { ref file, .. } if file == "batch-000004.parquet"),
                "{err}"
            );
        }
    }
}

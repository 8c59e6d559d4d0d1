//! Durable file writes: a file appears under its final name complete, or not at all, and survives a power cut once
//! the call returns.
//!
//! The sequence: write to a hidden temporary name in the same directory, fsync the file, rename it over the final
//! name (atomic within one file system), fsync the directory (so that the rename itself is on disk).

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::checksum::HashingWriter;
use crate::error::StoreError;

/// What a durable write produced.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Written {
    /// File size, bytes.
    pub size_bytes: u64,
    /// Checksum of the file's bytes ([`crate::checksum`]).
    pub checksum: String,
}

/// The writer handed to the closure of [`write_file`].
pub(crate) type FileSink = HashingWriter<BufWriter<BudgetedFile>>;

/// An optional cap on the bytes a dataset writer may still write, shared by its batch files, journal and manifest: a
/// testing aid that makes a full disk reproducible without root or a small file system. Unlimited by default.
#[derive(Debug, Clone, Default)]
pub(crate) struct WriteBudget(Option<Arc<AtomicU64>>);

impl WriteBudget {
    /// A budget of `bytes`.
    pub(crate) fn limited(bytes: u64) -> Self {
        Self(Some(Arc::new(AtomicU64::new(bytes))))
    }

    /// Takes `n` bytes from the budget, or fails as a full disk does (taking nothing).
    pub(crate) fn take(&self, n: usize) -> io::Result<()> {
        let Some(remaining) = &self.0 else { return Ok(()) };
        let n = n as u64;
        remaining
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| left.checked_sub(n))
            .map(|_| ())
            .map_err(|_| io::Error::new(io::ErrorKind::StorageFull, "write budget exhausted (simulated full disk)"))
    }

    /// Gives back `n` bytes that were taken but not written.
    fn refund(&self, n: usize) {
        if let Some(remaining) = &self.0 {
            remaining.fetch_add(n as u64, Ordering::Relaxed);
        }
    }
}

/// A file whose writes draw on a [`WriteBudget`], and which remembers the first I/O error, so that the caller can
/// report a full disk as such even when a library (Parquet) wraps the error in its own.
#[derive(Debug)]
pub(crate) struct BudgetedFile {
    file: File,
    budget: WriteBudget,
    first_error: Option<io::ErrorKind>,
}

impl BudgetedFile {
    fn new(file: File, budget: WriteBudget) -> Self {
        Self { file, budget, first_error: None }
    }

    fn record<T>(&mut self, result: io::Result<T>) -> io::Result<T> {
        if let Err(e) = &result {
            self.first_error.get_or_insert(e.kind());
        }
        result
    }
}

impl Write for BudgetedFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let taken = self.budget.take(buf.len());
        self.record(taken)?;
        let written = self.file.write(buf);
        let written = self.record(written);
        self.budget.refund(buf.len() - *written.as_ref().unwrap_or(&0));
        written
    }

    fn flush(&mut self) -> io::Result<()> {
        let flushed = self.file.flush();
        self.record(flushed)
    }
}

/// Suffix of temporary files; a leading dot also hides them from pyarrow's and polars' directory readers.
pub(crate) const TEMP_SUFFIX: &str = ".tmp";

/// The temporary name of `name`.
pub(crate) fn temp_name(name: &str) -> String {
    format!(".{name}{TEMP_SUFFIX}")
}

/// Writes `dir/name` durably with the bytes that `fill` writes, and returns their size and checksum.
///
/// A stale temporary file from an interrupted earlier write is overwritten. On error the temporary file is removed
/// (best effort) and nothing appears under `name`.
///
/// # Errors
/// [`StoreError::Io`] naming the step that failed, or whatever `fill` returns.
pub(crate) fn write_file(
    dir: &Path,
    name: &str,
    budget: &WriteBudget,
    fill: impl FnOnce(&mut FileSink) -> Result<(), StoreError>,
) -> Result<Written, StoreError> {
    write_file_into(dir, dir, name, budget, fill)
}

/// As [`write_file`], with the temporary file in `staging_dir` and the result in `target_dir` (the same file
/// system): a directory of finished files then never holds a temporary one, which directory readers such as polars
/// would trip over.
///
/// The staging directory is not fsync'd after the rename: were a crash to resurrect the temporary's name, the file
/// is a hidden `*.tmp` that every reader ignores and `DatasetWriter::resume` deletes; skipping that fsync saves a
/// quarter of a commit's cost.
///
/// # Errors
/// As [`write_file`]; a full disk (or an exhausted [`WriteBudget`]) is [`StoreError::DiskFull`] even when the
/// Parquet encoder reported it.
pub(crate) fn write_file_into(
    staging_dir: &Path,
    target_dir: &Path,
    name: &str,
    budget: &WriteBudget,
    fill: impl FnOnce(&mut FileSink) -> Result<(), StoreError>,
) -> Result<Written, StoreError> {
    let temp = staging_dir.join(temp_name(name));
    let result = write_temp_then_rename(&temp, &target_dir.join(name), budget, fill);
    if result.is_err() {
        // Best effort: the error that matters is the one being returned; a leftover hidden file is harmless.
        let _ = fs::remove_file(&temp);
    }
    let written = result?;
    sync_dir(target_dir)?;
    Ok(written)
}

/// Writes `dir/name` durably with `bytes` (temporary name, fsync, rename, directory fsync): a small file outside a
/// dataset (an experiment session's plan) that must appear complete or not at all.
///
/// # Errors
/// [`StoreError::Io`] / [`StoreError::DiskFull`] naming the step that failed.
pub fn write_bytes(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), StoreError> {
    let path = dir.join(name);
    write_file(dir, name, &WriteBudget::default(), |sink| {
        sink.write_all(bytes).map_err(StoreError::io("write", &path))
    })?;
    Ok(())
}

fn write_temp_then_rename(
    temp: &Path,
    target: &Path,
    budget: &WriteBudget,
    fill: impl FnOnce(&mut FileSink) -> Result<(), StoreError>,
) -> Result<Written, StoreError> {
    let file = File::create(temp).map_err(StoreError::io("create", temp))?;
    let mut sink = HashingWriter::new(BufWriter::new(BudgetedFile::new(file, budget.clone())));
    let filled = fill(&mut sink).and_then(|()| sink.flush().map_err(StoreError::io("write", temp)));
    if let Err(e) = filled {
        // A full disk under the Parquet encoder arrives wrapped in a Parquet error: name it for what it is.
        return Err(match sink.get_ref().get_ref().first_error {
            Some(kind @ (io::ErrorKind::StorageFull | io::ErrorKind::QuotaExceeded)) => {
                StoreError::from_io("write", temp.into(), io::Error::new(kind, e.to_string()))
            }
            _ => e,
        });
    }
    let (buffered, checksum, size_bytes) = sink.finish();
    let file = buffered.into_inner().map_err(|e| StoreError::from_io("write", temp.into(), e.into()))?;
    file.file.sync_all().map_err(StoreError::io("fsync", temp))?;
    drop(file);
    fs::rename(temp, target).map_err(StoreError::io("rename into place", target))?;
    Ok(Written { size_bytes, checksum })
}

/// Makes the directory's entries (creations, renames, removals) durable.
///
/// # Errors
/// [`StoreError::Io`] if the directory cannot be opened or synced.
pub fn sync_dir(dir: &Path) -> Result<(), StoreError> {
    #[cfg(unix)]
    {
        File::open(dir).and_then(|d| d.sync_all()).map_err(StoreError::io("fsync directory", dir))?;
    }
    // Elsewhere a directory cannot be opened as a file; NTFS journals its metadata, so the rename is durable anyway.
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}

/// Sorted entry names of `dir` (names that are not UTF-8 lossily converted).
///
/// # Errors
/// [`StoreError::Io`] if the directory cannot be listed.
pub(crate) fn entry_names(dir: &Path) -> Result<Vec<String>, StoreError> {
    let mut names = Vec::new();
    for entry in fs::read_dir(dir).map_err(StoreError::io("list directory", dir))? {
        let entry = entry.map_err(StoreError::io("list directory", dir))?;
        names.push(entry.file_name().to_string_lossy().into_owned());
    }
    names.sort_unstable();
    Ok(names)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn writes_the_bytes_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let written = write_file(dir.path(), "a.bin", &WriteBudget::default(), |w| {
            w.write_all(b"hello").map_err(StoreError::io("write", "a.bin"))
        })
        .unwrap();
        assert_eq!(fs::read(dir.path().join("a.bin")).unwrap(), b"hello");
        assert_eq!(written, Written { size_bytes: 5, checksum: crate::checksum::sha256(b"hello") });
        let names: Vec<_> = fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["a.bin"]);
    }

    #[test]
    fn write_bytes_writes_a_whole_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        write_bytes(dir.path(), "plan.json", b"{}").unwrap();
        write_bytes(dir.path(), "plan.json", b"{\"a\": 1}").unwrap();
        assert_eq!(fs::read(dir.path().join("plan.json")).unwrap(), b"{\"a\": 1}");
        assert_eq!(entry_names(dir.path()).unwrap(), ["plan.json"]);
        assert!(write_bytes(&dir.path().join("missing"), "x", b"").is_err());
    }

    #[test]
    fn replaces_an_existing_file_atomically() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("m.json"), b"old").unwrap();
        write_file(dir.path(), "m.json", &WriteBudget::default(), |w| {
            w.write_all(b"new").map_err(StoreError::io("write", "m.json"))
        })
        .unwrap();
        assert_eq!(fs::read(dir.path().join("m.json")).unwrap(), b"new");
    }

    #[test]
    fn a_failing_fill_leaves_neither_target_nor_temporary() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join("keep.json"), b"old").unwrap();
        let err = write_file(dir.path(), "keep.json", &WriteBudget::default(), |w| {
            w.write_all(b"partial").map_err(StoreError::io("write", "keep.json"))?;
            Err(StoreError::EmptyBatch)
        })
        .unwrap_err();
        assert!(matches!(err, StoreError::EmptyBatch));
        // The old content survives a failed replacement, and the half-written temporary is gone.
        assert_eq!(fs::read(dir.path().join("keep.json")).unwrap(), b"old");
        assert!(!dir.path().join(temp_name("keep.json")).exists());
    }

    #[test]
    fn staging_in_another_directory_leaves_the_target_directory_clean() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("batches");
        fs::create_dir(&target).unwrap();
        let written = write_file_into(dir.path(), &target, "b.parquet", &WriteBudget::default(), |w| {
            w.write_all(b"data").map_err(StoreError::io("write", "b.parquet"))
        })
        .unwrap();
        assert_eq!(written.size_bytes, 4);
        assert_eq!(fs::read(target.join("b.parquet")).unwrap(), b"data");
        let names = |d: &Path| fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name()).collect::<Vec<_>>();
        assert_eq!(names(&target), ["b.parquet"]);
        assert_eq!(names(dir.path()), ["batches"]);
    }

    #[test]
    fn a_missing_directory_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope");
        let err = write_file(&missing, "a", &WriteBudget::default(), |_| Ok(())).unwrap_err();
        assert!(matches!(err, StoreError::Io { op: "create", .. }), "{err}");
    }
}

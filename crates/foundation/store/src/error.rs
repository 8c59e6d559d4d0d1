//! The one error type of this crate.

use std::path::PathBuf;

/// Why a dataset could not be written or read.
///
/// Every variant names the file (or the batch row) it is about, so that a message alone tells a person where to look.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The operating system refused a file operation.
    #[error("{op} {path}: {source}")]
    Io {
        /// What was being done ("create", "write", "rename", ...).
        op: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// `DatasetWriter::create` found a directory that already holds files, and was not told to replace them.
    #[error("{dir} is not empty (it holds {entry}); refusing to write a dataset into it")]
    NotEmpty {
        /// The dataset directory.
        dir: PathBuf,
        /// One entry found in it.
        entry: String,
    },
    /// The dataset metadata given to the writer is outside its valid range.
    #[error("invalid dataset metadata {field}: {reason}")]
    InvalidMeta {
        /// The offending field, with its unit where it has one.
        field: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// A record (given to the writer, or read from a file) is outside its valid range.
    #[error("{location}: invalid record: {reason}")]
    InvalidRecord {
        /// Where: `"commit row 3"` or `"batch-000001.parquet row 3"`.
        location: String,
        /// What was wrong.
        reason: String,
    },
    /// The same (point, actuator) pair appears twice in a dataset.
    #[error("{location}: duplicate record for point {point_index}, actuator {actuator} (first seen at {first})")]
    Duplicate {
        /// Grid point index.
        point_index: u32,
        /// Actuator number.
        actuator: u16,
        /// Where it was seen first.
        first: String,
        /// Where it was seen again.
        location: String,
    },
    /// A record's impulse response length or sample rate differs from the rest of the dataset.
    #[error("{location}: {what} is {found}, but the dataset's is {expected}")]
    Inconsistent {
        /// Where.
        location: String,
        /// `"ir length (samples)"` or `"sample_rate_hz"`.
        what: &'static str,
        /// The dataset's value (from its first record).
        expected: String,
        /// This record's value.
        found: String,
    },
    /// A batch with no records was committed.
    #[error("a batch must hold at least one record")]
    EmptyBatch,
    /// A dataset with no batches was finished or opened: it has nothing to read.
    #[error("{dir}: the dataset has no batches")]
    EmptyDataset {
        /// The dataset directory.
        dir: PathBuf,
    },
    /// The dataset directory has no `manifest.json` (not a dataset, or its creation did not complete).
    #[error("{path} not found: not a dataset")]
    ManifestMissing {
        /// Where the manifest was expected.
        path: PathBuf,
    },
    /// `manifest.json` is not valid JSON, lacks a field, or a field is out of range.
    #[error("{path}: malformed manifest: {reason}")]
    ManifestMalformed {
        /// The manifest file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// The manifest was written by a newer (or unknown) schema version.
    #[error("schema version {found} is not supported (this build reads version {supported})")]
    UnsupportedSchemaVersion {
        /// Version in the manifest.
        found: u32,
        /// Version this build reads and writes.
        supported: u32,
    },
    /// The manifest's `config_hash` does not match its content: it was edited after it was written.
    #[error("config_hash mismatch: the manifest says {stored}, its content hashes to {computed}")]
    ConfigHashMismatch {
        /// Hash stored in the manifest.
        stored: String,
        /// Hash of the manifest's content.
        computed: String,
    },
    /// A batch file listed in the manifest is absent.
    #[error("batch file {file} listed in the manifest is missing")]
    BatchMissing {
        /// File name inside the dataset directory.
        file: String,
    },
    /// A batch file's size differs from the manifest's: it was truncated or appended to.
    #[error("batch file {file} is {actual_bytes} bytes, the manifest says {expected_bytes} (truncated?)")]
    SizeMismatch {
        /// File name.
        file: String,
        /// Size recorded at commit, bytes.
        expected_bytes: u64,
        /// Size on disk, bytes.
        actual_bytes: u64,
    },
    /// A batch file's bytes do not hash to the manifest's checksum: it is corrupt.
    #[error("batch file {file} is corrupt: checksum {actual}, the manifest says {expected}")]
    ChecksumMismatch {
        /// File name.
        file: String,
        /// Checksum recorded at commit.
        expected: String,
        /// Checksum of the bytes on disk.
        actual: String,
    },
    /// A batch file holds a different number of rows than the manifest says.
    #[error("batch file {file} holds {actual} rows, the manifest says {expected}")]
    RowCountMismatch {
        /// File name.
        file: String,
        /// Rows recorded at commit.
        expected: u64,
        /// Rows read.
        actual: u64,
    },
    /// A batch file's columns are not the dataset schema.
    #[error("batch file {file}: schema mismatch: {reason}")]
    SchemaMismatch {
        /// File name.
        file: String,
        /// Which column is missing or has the wrong type.
        reason: String,
    },
    /// The Parquet library could not encode or decode a batch file.
    #[error("batch file {file}: parquet: {source}")]
    Parquet {
        /// File name.
        file: String,
        /// The underlying error.
        source: parquet::errors::ParquetError,
    },
    /// Arrow refused to assemble or decode a record batch.
    #[error("batch file {file}: arrow: {source}")]
    Arrow {
        /// File name.
        file: String,
        /// The underlying error.
        source: arrow_schema::ArrowError,
    },
    /// The disk (or the writer's test budget, see `DatasetWriter::with_write_budget`) is full. The call that failed
    /// committed nothing, and everything committed before it is intact.
    #[error("{op} {path}: the disk is full ({source}); nothing was committed by this call: free space, then resume")]
    DiskFull {
        /// What was being done.
        op: &'static str,
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// `journal.jsonl` could not be used: a line the writer needs is unreadable, or the journal is not where a
    /// dataset's journal should be.
    #[error("{path}: journal: {reason}")]
    Journal {
        /// The journal file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
    /// A batch file's rows are not the (point, actuator) keys its journal entry lists.
    #[error("batch file {file}: its rows do not match its journal entry: {reason}")]
    KeysMismatch {
        /// File name.
        file: String,
        /// The first difference.
        reason: String,
    },
    /// `DatasetWriter::resume` was given metadata that differs from the dataset's, and not told to force.
    #[error(
        "{dir}: the configuration differs from the dataset's ({}); resume with the original configuration, or force \
         to continue anyway",
        differences.join("; ")
    )]
    ConfigChanged {
        /// The dataset directory.
        dir: PathBuf,
        /// One `key.path: old -> new` line per difference.
        differences: Vec<String>,
    },
    /// Another writer (this process or another) holds the dataset's journal lock.
    #[error("{path} is locked by another writer; only one writer may append to a dataset at a time")]
    Locked {
        /// The journal file.
        path: PathBuf,
    },
    /// An earlier failure left this writer unable to tell what is on disk (for example a failed fsync of the
    /// journal); it refuses further commits. Everything it committed is safe: resume the dataset to continue.
    #[error("the writer of {dir} stopped after an earlier failure ({reason}); resume the dataset to continue")]
    Poisoned {
        /// The dataset directory.
        dir: PathBuf,
        /// The earlier failure.
        reason: String,
    },
    /// A (point, actuator) pair asked for is not in the dataset.
    #[error("the dataset has no response for point {point_index}, actuator {actuator}")]
    NotInDataset {
        /// Grid point index.
        point_index: u32,
        /// Actuator number.
        actuator: u16,
    },
    /// Polars refused to read the dataset's files (feature `polars`).
    #[cfg(feature = "polars")]
    #[error("{dir}: polars: {reason}")]
    Polars {
        /// The dataset directory.
        dir: PathBuf,
        /// Polars' message.
        reason: String,
    },
    /// A WAV file could not be written or read.
    #[error("{path}: wav: {reason}")]
    Wav {
        /// The WAV file.
        path: PathBuf,
        /// What was wrong.
        reason: String,
    },
}

impl StoreError {
    /// An error for `op` on `path`; a short constructor for `map_err`. A full disk or an exceeded quota becomes
    /// [`StoreError::DiskFull`], anything else [`StoreError::Io`].
    pub(crate) fn io(op: &'static str, path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::from_io(op, path, source)
    }

    /// As [`StoreError::io`], applied at once.
    pub(crate) fn from_io(op: &'static str, path: PathBuf, source: std::io::Error) -> Self {
        use std::io::ErrorKind;
        if matches!(source.kind(), ErrorKind::StorageFull | ErrorKind::QuotaExceeded) {
            Self::DiskFull { op, path, source }
        } else {
            Self::Io { op, path, source }
        }
    }
}

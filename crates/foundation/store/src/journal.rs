//! `journal.jsonl`: the append-only commit journal, the source of truth for what a dataset holds.
//!
//! One JSON object per line, appended and fsync'd after the file it names is durable under its final name:
//! `{"seq":0,"at":"2026-01-31T23:59:59.999Z","kind":"batch","file":"batch-000000.parquet","rows":8,...,
//! "crc32":"89abcdef"}`. `crc32` is the CRC-32 (IEEE, as `zlib.crc32`) of the line's text without it: the line up to
//! `,"crc32":"` followed by `}`. A line without its newline, that is not JSON, or whose CRC does not match is ignored
//! (a crash mid-append tears at most the last line) and reported; `DatasetWriter::resume` rewrites the journal
//! without it.
//!
//! Kinds: `batch` (a committed batch file, with its size, SHA-256 and keys, and optionally the writer's session
//! `state` after it, a JSON object the recipe defines), `compaction` (a file that replaces the
//! batches it lists in `supersedes`), `quarantine` (a file taken out of the dataset by resume, with the reason) and
//! `forced-resume` (a resume that accepted a changed configuration, with the differences).

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use chrono::{SecondsFormat, Utc};
use serde::{Deserialize, Serialize};

use crate::checksum;
use crate::durable::{self, WriteBudget};
use crate::error::StoreError;
use crate::manifest::{BatchInfo, is_batch_file_name};

/// File name of the journal inside a dataset directory.
pub const JOURNAL_FILE: &str = "journal.jsonl";

/// What marks the start of a line's CRC field.
const CRC_FIELD: &str = ",\"crc32\":\"";

/// One batch file as the journal records it: enough to verify it and to know its keys without opening it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BatchEntry {
    /// File name inside the dataset's `batches/` directory.
    pub file: String,
    /// Number of rows.
    pub rows: u64,
    /// File size, bytes.
    pub size_bytes: u64,
    /// SHA-256 of the file, `"sha256:<hex>"`.
    pub checksum: String,
    /// Length of every impulse response in the file, samples.
    pub ir_len: u64,
    /// Sample rate of every impulse response, Hz.
    pub sample_rate_hz: f64,
    /// `(point_index, actuator)` of every row, in file order.
    pub keys: Vec<(u32, u16)>,
    /// For a compaction: the batch files this one replaces.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub supersedes: Vec<String>,
    /// For a batch: the writer's session state after it (a JSON object the recipe defines, such as the velocity
    /// range in force), committed atomically with its rows so that a resume continues from it. Absent in lines
    /// written before it existed, and in compactions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub state: Option<serde_json::Map<String, serde_json::Value>>,
}

impl BatchEntry {
    /// The manifest's view of this file.
    pub fn info(&self) -> BatchInfo {
        BatchInfo {
            file: self.file.clone(),
            rows: self.rows,
            size_bytes: self.size_bytes,
            checksum: self.checksum.clone(),
        }
    }
}

/// One journal line's content.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum JournalEntry {
    /// A committed batch file.
    Batch(BatchEntry),
    /// A compacted file that replaces the files in its `supersedes`.
    Compaction(BatchEntry),
    /// A file taken out of the dataset (moved to `quarantine/`); its keys are no longer committed.
    Quarantine {
        /// File name inside `batches/` (where it was).
        file: String,
        /// Why.
        reason: String,
    },
    /// A resume that accepted metadata differing from the manifest's.
    ForcedResume {
        /// One `key.path: old -> new` per difference.
        differences: Vec<String>,
    },
}

#[derive(Debug, Serialize, Deserialize)]
struct Line {
    seq: u64,
    at: String,
    #[serde(flatten)]
    entry: JournalEntry,
}

/// A journal line that was ignored.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JournalIssue {
    /// Line number, 1-based.
    pub line: usize,
    /// Whether it is the last line (a torn append: expected after a crash) rather than damage in the middle.
    pub torn_tail: bool,
    /// What was wrong.
    pub reason: String,
}

/// Encodes one line, newline included.
fn encode_line(seq: u64, entry: &JournalEntry) -> Result<String, String> {
    let at = Utc::now().to_rfc3339_opts(SecondsFormat::Millis, true);
    let body = serde_json::to_string(&Line { seq, at, entry: entry.clone() }).map_err(|e| e.to_string())?;
    let open = body.strip_suffix('}').ok_or("a journal line must be a JSON object")?;
    Ok(format!("{open}{CRC_FIELD}{:08x}\"}}\n", crc32fast::hash(body.as_bytes())))
}

/// Decodes one line (without its newline).
fn decode_line(text: &str) -> Result<Line, String> {
    let at = text.rfind(CRC_FIELD).ok_or("no crc32 field")?;
    let crc_text = text[at + CRC_FIELD.len()..].strip_suffix("\"}").ok_or("the crc32 field does not end the line")?;
    let stored = u32::from_str_radix(crc_text, 16).map_err(|_| format!("crc32 {crc_text:?} is not hexadecimal"))?;
    let body = format!("{}}}", &text[..at]);
    let computed = crc32fast::hash(body.as_bytes());
    if computed != stored {
        return Err(format!("crc32 mismatch: the line says {stored:08x}, its text hashes to {computed:08x}"));
    }
    serde_json::from_str(&body).map_err(|e| format!("not a journal entry: {e}"))
}

/// What a journal file holds.
#[derive(Debug, Default)]
pub(crate) struct JournalRead {
    /// Good entries with their sequence numbers, in order.
    pub entries: Vec<(u64, JournalEntry)>,
    /// When each of `entries` was journaled (its `at`), in the same order.
    pub at: Vec<String>,
    /// Lines ignored.
    pub issues: Vec<JournalIssue>,
    /// The good lines, newlines included: the journal as it should be.
    pub good_text: String,
}

impl JournalRead {
    /// The sequence number the next appended line takes.
    pub(crate) fn next_seq(&self) -> u64 {
        self.entries.last().map_or(0, |(seq, _)| seq + 1)
    }
}

/// Reads `dir/journal.jsonl`, or `None` if the dataset has none (written before the journal existed).
///
/// # Errors
/// [`StoreError::Io`] if the file exists but cannot be read.
pub(crate) fn read(dir: &Path) -> Result<Option<JournalRead>, StoreError> {
    let path = dir.join(JOURNAL_FILE);
    let bytes = match fs::read(&path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(StoreError::from_io("read", path, e)),
    };
    let mut read = JournalRead::default();
    let mut chunks: Vec<&[u8]> = bytes.split(|&b| b == b'\n').collect();
    // After the last newline: empty for a journal that ends cleanly, a torn line otherwise.
    let tail = chunks.pop().unwrap_or_default();
    let count = chunks.len() + usize::from(!tail.is_empty());
    for (i, chunk) in chunks.iter().enumerate() {
        let issue = |reason: String| JournalIssue { line: i + 1, torn_tail: i + 1 == count, reason };
        let decoded = std::str::from_utf8(chunk).map_err(|e| e.to_string()).and_then(decode_line);
        match decoded {
            Ok(line) if line.seq < read.next_seq() => {
                read.issues.push(issue(format!("sequence number {} out of order", line.seq)));
            }
            Ok(line) => {
                read.good_text.push_str(std::str::from_utf8(chunk).unwrap_or_default());
                read.good_text.push('\n');
                read.entries.push((line.seq, line.entry));
                read.at.push(line.at);
            }
            Err(reason) => read.issues.push(issue(reason)),
        }
    }
    if !tail.is_empty() {
        read.issues.push(JournalIssue {
            line: count,
            torn_tail: true,
            reason: format!("no newline at the end ({} bytes): an append interrupted by a crash", tail.len()),
        });
    }
    Ok(Some(read))
}

/// One batch commit as the journal records it.
#[derive(Debug, Clone, PartialEq)]
pub struct JournalCommit {
    /// Sequence number of its journal line.
    pub seq: u64,
    /// When it was journaled: RFC 3339, UTC, milliseconds (`2026-01-31T23:59:59.999Z`).
    pub at: String,
    /// The committed file.
    pub batch: BatchEntry,
}

/// What a dataset's journal says, for a reader that follows a dataset while it is written (see [`view`]).
#[derive(Debug, Clone, Default)]
pub struct JournalView {
    /// Every batch line, in journal order, whether or not its file still holds the dataset (compactions are not
    /// commits: they add no rows).
    pub commits: Vec<JournalCommit>,
    /// The files that hold the dataset now (after compactions and quarantines), in commit order.
    pub live: Vec<BatchEntry>,
    /// Lines ignored: a torn last line (an append in progress, or a crash) or damage.
    pub issues: Vec<JournalIssue>,
}

/// Reads the journal of the dataset in `dir` without taking the writer's lock or changing anything, so that it is
/// safe beside a running writer: a line being appended is reported as a torn tail and left for the next read.
/// `None` if the dataset has no journal (yet, or written before the journal existed).
///
/// # Errors
/// [`StoreError::Io`] if the file exists but cannot be read.
pub fn view(dir: &Path) -> Result<Option<JournalView>, StoreError> {
    let Some(read) = read(dir)? else { return Ok(None) };
    let live = Live::replay(&read.entries);
    let commits = read
        .entries
        .iter()
        .zip(&read.at)
        .filter_map(|((seq, entry), at)| match entry {
            JournalEntry::Batch(batch) => Some(JournalCommit { seq: *seq, at: at.clone(), batch: batch.clone() }),
            _ => None,
        })
        .collect();
    let issues = read.issues.into_iter().chain(live.issues).collect();
    Ok(Some(JournalView { commits, live: live.batches, issues }))
}

/// The dataset a journal describes: the batch files that hold it, in journal order.
#[derive(Debug, Default)]
pub(crate) struct Live {
    /// Files whose rows are the dataset.
    pub batches: Vec<BatchEntry>,
    /// Files replaced by a compaction: garbage, to be deleted.
    pub superseded: Vec<String>,
    /// Entries that make no sense (reported like bad lines, and ignored).
    pub issues: Vec<JournalIssue>,
}

impl Live {
    /// Replays `entries`.
    pub(crate) fn replay(entries: &[(u64, JournalEntry)]) -> Self {
        let mut live = Live::default();
        let mut named = std::collections::HashSet::new();
        for (index, (seq, entry)) in entries.iter().enumerate() {
            let issue = |reason: String| JournalIssue { line: index + 1, torn_tail: false, reason };
            match entry {
                JournalEntry::Batch(batch) | JournalEntry::Compaction(batch) => {
                    if let Err(reason) = check_entry(batch) {
                        live.issues.push(issue(format!("entry {seq}: {reason}")));
                        continue;
                    }
                    if !named.insert(batch.file.clone()) {
                        live.issues.push(issue(format!("entry {seq}: file {} was already committed", batch.file)));
                        continue;
                    }
                    for old in &batch.supersedes {
                        live.batches.retain(|b| &b.file != old);
                        live.superseded.push(old.clone());
                    }
                    live.batches.push(batch.clone());
                }
                JournalEntry::Quarantine { file, .. } => live.batches.retain(|b| &b.file != file),
                JournalEntry::ForcedResume { .. } => {}
            }
        }
        live
    }
}

/// Checks a batch entry's own consistency.
fn check_entry(batch: &BatchEntry) -> Result<(), String> {
    if !is_batch_file_name(&batch.file) || batch.supersedes.iter().any(|f| !is_batch_file_name(f)) {
        return Err(format!("file name {:?} is not a plain visible *.parquet name", batch.file));
    }
    if !checksum::is_well_formed(&batch.checksum) {
        return Err(format!("checksum {:?} is not sha256:<hex>", batch.checksum));
    }
    if batch.keys.len() as u64 != batch.rows {
        return Err(format!("{} keys for {} rows", batch.keys.len(), batch.rows));
    }
    Ok(())
}

/// The open journal of a writer: appends lines durably, and holds the dataset's writer lock.
#[derive(Debug)]
pub(crate) struct JournalWriter {
    file: File,
    dir: PathBuf,
    path: PathBuf,
    /// Length of the journal in bytes: where the next line starts.
    len: u64,
    next_seq: u64,
    /// Set when a failure left the journal in an unknown state.
    broken: Option<String>,
}

impl JournalWriter {
    /// Creates an empty journal in `dir` (refusing an existing one) and makes it durable.
    ///
    /// # Errors
    /// [`StoreError::Io`] / [`StoreError::DiskFull`].
    pub(crate) fn create(dir: &Path) -> Result<Self, StoreError> {
        let path = dir.join(JOURNAL_FILE);
        let file =
            OpenOptions::new().append(true).create_new(true).open(&path).map_err(StoreError::io("create", &path))?;
        let writer = Self::locked(file, dir, 0, 0)?;
        writer.file.sync_all().map_err(StoreError::io("fsync", &writer.path))?;
        durable::sync_dir(dir)?;
        Ok(writer)
    }

    /// Opens the journal in `dir` for appending at `next_seq`; it must end at a line boundary.
    ///
    /// # Errors
    /// [`StoreError::Locked`] if another writer holds it; [`StoreError::Io`].
    pub(crate) fn open(dir: &Path, next_seq: u64) -> Result<Self, StoreError> {
        let path = dir.join(JOURNAL_FILE);
        let file = OpenOptions::new().append(true).open(&path).map_err(StoreError::io("open", &path))?;
        let len = file.metadata().map_err(StoreError::io("stat", &path))?.len();
        Self::locked(file, dir, len, next_seq)
    }

    fn locked(file: File, dir: &Path, len: u64, next_seq: u64) -> Result<Self, StoreError> {
        let path = dir.join(JOURNAL_FILE);
        crate::lock::try_lock_exclusive(&file, &path)?;
        Ok(Self { file, dir: dir.to_path_buf(), path, len, next_seq, broken: None })
    }

    /// Appends `entry` as one line and fsyncs it: when this returns `Ok`, the entry survives a power cut.
    ///
    /// On a failed write the journal is cut back to where it was, so that it still ends at a line boundary; if even
    /// that fails, or an fsync fails (after which the kernel may have dropped the data), the writer is poisoned.
    ///
    /// # Errors
    /// [`StoreError::DiskFull`], [`StoreError::Io`], [`StoreError::Poisoned`], [`StoreError::Journal`].
    pub(crate) fn append(&mut self, entry: &JournalEntry, budget: &WriteBudget) -> Result<(), StoreError> {
        if let Some(reason) = &self.broken {
            return Err(StoreError::Poisoned { dir: self.dir.clone(), reason: reason.clone() });
        }
        let line = encode_line(self.next_seq, entry)
            .map_err(|reason| StoreError::Journal { path: self.path.clone(), reason })?;
        let written = budget.take(line.len()).and_then(|()| self.file.write_all(line.as_bytes()));
        if let Err(e) = written {
            if let Err(cut) = self.file.set_len(self.len).and_then(|()| self.file.sync_data()) {
                self.broken = Some(format!("a failed append could not be taken back: {cut}"));
            }
            return Err(StoreError::from_io("append to", self.path.clone(), e));
        }
        if let Err(e) = self.file.sync_data() {
            self.broken = Some(format!("fsync of the journal failed: {e}"));
            return Err(StoreError::from_io("fsync", self.path.clone(), e));
        }
        self.len += line.len() as u64;
        self.next_seq += 1;
        Ok(())
    }

    /// The sequence number of the next line.
    pub(crate) fn next_seq(&self) -> u64 {
        self.next_seq
    }

    /// Why the journal refuses appends, if it does.
    pub(crate) fn broken(&self) -> Option<&str> {
        self.broken.as_deref()
    }
}

/// Replaces the journal of `dir` by `text` durably (temporary file, fsync, rename, directory fsync).
///
/// # Errors
/// [`StoreError::Io`] / [`StoreError::DiskFull`].
pub(crate) fn rewrite(dir: &Path, text: &str, budget: &WriteBudget) -> Result<(), StoreError> {
    let path = dir.join(JOURNAL_FILE);
    durable::write_file(dir, JOURNAL_FILE, budget, |sink| {
        sink.write_all(text.as_bytes()).map_err(StoreError::io("write", &path))
    })?;
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    fn entry(file: &str, keys: &[(u32, u16)]) -> JournalEntry {
        JournalEntry::Batch(BatchEntry {
            file: file.into(),
            rows: keys.len() as u64,
            size_bytes: 100,
            checksum: checksum::sha256(file.as_bytes()),
            ir_len: 16,
            sample_rate_hz: 24_000.5,
            keys: keys.to_vec(),
            supersedes: Vec::new(),
            state: None,
        })
    }

    #[test]
    fn lines_round_trip_and_their_crc_is_zlib_crc32_of_the_line_without_it() {
        let original = entry("batch-000003.parquet", &[(1, 0), (1, 7)]);
        let line = encode_line(3, &original).unwrap();
        assert!(line.ends_with("\"}\n") && !line[..line.len() - 1].contains('\n'), "{line}");
        let decoded = decode_line(line.trim_end_matches('\n')).unwrap();
        assert_eq!((decoded.seq, decoded.entry), (3, original));
        // The documented rule, recomputed by hand.
        let text = line.trim_end_matches('\n');
        let at = text.rfind(CRC_FIELD).unwrap();
        let body = format!("{}}}", &text[..at]);
        assert_eq!(
            format!("{:08x}", crc32fast::hash(body.as_bytes())),
            &text[at + CRC_FIELD.len()..at + CRC_FIELD.len() + 8]
        );
    }

    #[test]
    fn a_batch_line_without_state_still_reads_and_one_with_state_round_trips() {
        // A line as written before the field existed: no `state`.
        let old = encode_line(0, &entry("batch-000000.parquet", &[(0, 0)])).unwrap();
        assert!(!old.contains("state"), "an absent state is not written: {old}");
        let JournalEntry::Batch(batch) = decode_line(old.trim_end_matches('\n')).unwrap().entry else { panic!() };
        assert_eq!(batch.state, None);
        let JournalEntry::Batch(mut with_state) = entry("batch-000001.parquet", &[(1, 0)]) else { unreachable!() };
        with_state.state = serde_json::json!({"velocity_range_m_s": 1.0}).as_object().cloned();
        let line = encode_line(1, &JournalEntry::Batch(with_state.clone())).unwrap();
        let decoded = decode_line(line.trim_end_matches('\n')).unwrap();
        assert_eq!(decoded.entry, JournalEntry::Batch(with_state));
    }

    #[test]
    fn any_single_changed_byte_is_detected() {
        let line = encode_line(0, &entry("batch-000000.parquet", &[(0, 0)])).unwrap();
        let text = line.trim_end_matches('\n');
        for i in 0..text.len() {
            let mut bytes = text.as_bytes().to_vec();
            bytes[i] ^= 0x01;
            let Ok(changed) = String::from_utf8(bytes) else { continue };
            assert!(decode_line(&changed).is_err(), "flip at {i} went unnoticed: {changed}");
        }
    }

    #[test]
    fn replay_applies_compaction_and_quarantine_and_ignores_a_file_named_twice() {
        let mut compaction = match entry("compacted-000002.parquet", &[(0, 0), (1, 0)]) {
            JournalEntry::Batch(b) => b,
            _ => unreachable!(),
        };
        compaction.supersedes = vec!["batch-000000.parquet".into(), "batch-000001.parquet".into()];
        let entries = vec![
            (0, entry("batch-000000.parquet", &[(0, 0)])),
            (1, entry("batch-000001.parquet", &[(1, 0)])),
            (2, JournalEntry::Compaction(compaction)),
            (3, entry("batch-000003.parquet", &[(2, 0)])),
            (4, entry("batch-000003.parquet", &[(3, 0)])),
            (5, entry("batch-000005.parquet", &[(4, 0)])),
            (6, JournalEntry::Quarantine { file: "batch-000005.parquet".into(), reason: "corrupt".into() }),
        ];
        let live = Live::replay(&entries);
        let files: Vec<_> = live.batches.iter().map(|b| b.file.as_str()).collect();
        assert_eq!(files, ["compacted-000002.parquet", "batch-000003.parquet"]);
        assert_eq!(live.superseded, ["batch-000000.parquet", "batch-000001.parquet"]);
        assert_eq!(live.issues.len(), 1);
        assert!(live.issues[0].reason.contains("already committed"), "{:?}", live.issues);
    }
}

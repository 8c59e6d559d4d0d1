//! Continuing a dataset after a stop of any kind (Ctrl-C, kill -9, power loss, a full disk): verify what the journal
//! says is committed, set aside what cannot be trusted, and hand back a writer that continues where it stopped.

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufReader, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use chrono::{SecondsFormat, Utc};
use serde_json::Value;

use crate::checksum::HashingWriter;
use crate::durable::{self, TEMP_SUFFIX, WriteBudget};
use crate::error::StoreError;
use crate::index::RowIndex;
use crate::journal::{self, BatchEntry, JOURNAL_FILE, JournalEntry, JournalIssue, JournalWriter, Live};
use crate::manifest::{BATCH_DIR, DatasetMeta, Manifest};
use crate::writer::{DatasetWriter, QUARANTINE_DIR, is_own_root_file};

/// A file [`DatasetWriter::resume`] took out of the dataset.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Quarantined {
    /// Its name in `batches/`.
    pub file: String,
    /// Where it is now (inside `quarantine/`), or `None` if it was missing.
    pub moved_to: Option<PathBuf>,
    /// Why.
    pub reason: String,
}

/// What [`DatasetWriter::resume`] found and did.
#[derive(Debug, Clone, Default)]
pub struct ResumeReport {
    /// `(point_index, actuator)` of every committed row that verified: the recipe measures everything else.
    pub committed: BTreeSet<(u32, u16)>,
    /// Committed files that failed verification (missing, truncated, corrupt, inconsistent) and orphans (files in
    /// `batches/` that the journal never committed); their keys are not in `committed`.
    pub quarantined: Vec<Quarantined>,
    /// Journal lines ignored (a torn last line after a crash, or damage); the journal was rewritten without them.
    pub journal_issues: Vec<JournalIssue>,
    /// Files superseded by a compaction, and leftovers of an unfinished one, deleted.
    pub removed: Vec<String>,
    /// Differences between the dataset's metadata and the expected one, accepted because `force` was set (empty
    /// otherwise).
    pub forced_differences: Vec<String>,
    /// The session state committed with the last committed batch that verified and carries one (see
    /// [`DatasetWriter::commit_batch_with_state`]): what the run continues from. `None` when no such batch exists
    /// (a fresh dataset, or one written without state).
    pub state: Option<serde_json::Map<String, Value>>,
    /// Bytes read and checksummed.
    pub verified_bytes: u64,
    /// Wall-clock time of the whole resume, s.
    pub elapsed_s: f64,
}

impl DatasetWriter {
    /// Reopens the dataset in `dir` for writing after a stop of any kind.
    ///
    /// 1. Reads `manifest.json`; refuses metadata that differs from `expected_meta` (configuration, scene,
    ///    calibration, seed, grid, software version: everything `config_hash` covers) with
    ///    [`StoreError::ConfigChanged`] listing each difference (`config.scan.repetitions: 5 -> 3`), unless `force`,
    ///    in which case the differences are journaled (`forced-resume`) and the manifest keeps the original metadata.
    /// 2. Takes the writer lock and reads `journal.jsonl`; lines that are torn or damaged are reported and the
    ///    journal is rewritten (atomically) without them.
    /// 3. Verifies every committed file fully (size and SHA-256, several files in parallel); a file that is missing,
    ///    truncated or corrupt, or whose keys clash with another, is journaled as quarantined and moved to
    ///    `quarantine/`: its keys are then not committed, so the recipe measures them again.
    /// 4. Moves files in `batches/` that the journal never committed (a crash between rename and journal append) to
    ///    `quarantine/`, deletes files superseded by a compaction and stale temporary files, and refreshes the
    ///    manifest's batch list.
    ///
    /// Nothing is ever deleted that the journal has not superseded: suspect files are moved, with a line in
    /// `quarantine/notes.jsonl` each.
    ///
    /// # Errors
    /// [`StoreError::ManifestMissing`] (not a dataset: create it instead) and the other manifest errors;
    /// [`StoreError::ConfigChanged`]; [`StoreError::Journal`] if the dataset has no journal (written before it
    /// existed); [`StoreError::Locked`] if another writer has it open; [`StoreError::Io`] /
    /// [`StoreError::DiskFull`].
    pub fn resume(
        dir: impl AsRef<Path>,
        expected_meta: &DatasetMeta,
        force: bool,
    ) -> Result<(DatasetWriter, ResumeReport), StoreError> {
        let start = Instant::now();
        let dir = dir.as_ref().to_path_buf();
        expected_meta.validate()?;
        let mut manifest = Manifest::read(&dir)?;
        let differences = if expected_meta.config_hash() == manifest.config_hash {
            Vec::new()
        } else {
            meta_differences(&manifest.meta, expected_meta)
        };
        if !differences.is_empty() && !force {
            return Err(StoreError::ConfigChanged { dir, differences });
        }
        let read = journal::read(&dir)?.ok_or_else(|| StoreError::Journal {
            path: dir.join(JOURNAL_FILE),
            reason: "missing: the dataset was written before the journal existed and cannot be resumed".into(),
        })?;
        let mut journal = JournalWriter::open(&dir, read.next_seq())?;
        let budget = WriteBudget::default();
        if !read.issues.is_empty() {
            journal::rewrite(&dir, &read.good_text, &budget)?;
            // The lock moves to the new file; the old handle (and its lock) is dropped on assignment.
            journal = JournalWriter::open(&dir, read.next_seq())?;
        }
        let live = Live::replay(&read.entries);
        let mut report = ResumeReport { forced_differences: differences.clone(), ..ResumeReport::default() };
        report.journal_issues = read.issues.into_iter().chain(live.issues.iter().cloned()).collect();
        if !differences.is_empty() {
            journal.append(&JournalEntry::ForcedResume { differences }, &budget)?;
        }

        let (verdicts, verified_bytes) = verify_all(&dir, &live.batches);
        report.verified_bytes = verified_bytes;
        let mut index = RowIndex::default();
        let mut good = Vec::new();
        for (batch, verdict) in live.batches.iter().zip(verdicts) {
            let restored = verdict.and_then(|()| {
                let ir_len = usize::try_from(batch.ir_len).map_err(|e| e.to_string())?;
                index.restore(&batch.file, &batch.keys, ir_len, batch.sample_rate_hz).map_err(|e| e.to_string())
            });
            match restored {
                Ok(()) => {
                    good.push(batch.info());
                    // Live batches are in commit order (a compaction replaces all batches before it).
                    if batch.state.is_some() {
                        report.state.clone_from(&batch.state);
                    }
                }
                Err(reason) => {
                    // Journal first: from then on no reader takes the file for part of the dataset.
                    journal.append(
                        &JournalEntry::Quarantine { file: batch.file.clone(), reason: reason.clone() },
                        &budget,
                    )?;
                    report.quarantined.push(quarantine(&dir, &batch.file, reason)?);
                }
            }
        }
        clean_directories(&dir, &live, &good, &mut report)?;
        manifest.batches = good;
        manifest.write_with(&dir, &budget)?;
        report.committed = index.keys().collect();
        report.elapsed_s = start.elapsed().as_secs_f64();
        Ok((DatasetWriter::from_parts(dir, manifest, index, journal), report))
    }
}

/// Deletes stale temporaries and superseded files, and quarantines orphans.
fn clean_directories(
    dir: &Path,
    live: &Live,
    good: &[crate::manifest::BatchInfo],
    report: &mut ResumeReport,
) -> Result<(), StoreError> {
    for name in durable::entry_names(dir)? {
        if name.starts_with('.') && name.ends_with(TEMP_SUFFIX) && is_own_root_file(&name) {
            let path = dir.join(&name);
            fs::remove_file(&path).map_err(StoreError::io("remove", &path))?;
        }
    }
    let batch_dir = dir.join(BATCH_DIR);
    let committed: HashSet<&str> = good.iter().map(|b| b.file.as_str()).collect();
    let superseded: HashSet<&str> = live.superseded.iter().map(String::as_str).collect();
    for name in durable::entry_names(&batch_dir)? {
        if committed.contains(name.as_str()) {
            continue;
        }
        let path = batch_dir.join(&name);
        if superseded.contains(name.as_str()) || name.starts_with("compacted-") {
            // Superseded: its rows live on in the compacted file. An unjournaled compacted file: a copy of rows
            // that the batches still hold.
            fs::remove_file(&path).map_err(StoreError::io("remove", &path))?;
            report.removed.push(name);
        } else {
            let reason = "not in the journal: written but never committed (a stop between the file's rename and its \
                          journal line)";
            report.quarantined.push(quarantine(dir, &name, reason.to_string())?);
        }
    }
    durable::sync_dir(&batch_dir)?;
    durable::sync_dir(dir)
}

/// Moves `batches/<file>` (if present) into `quarantine/` under a name not yet taken there, and notes why.
fn quarantine(dir: &Path, file: &str, reason: String) -> Result<Quarantined, StoreError> {
    let source = dir.join(BATCH_DIR).join(file);
    let target_dir = dir.join(QUARANTINE_DIR);
    fs::create_dir_all(&target_dir).map_err(StoreError::io("create directory", &target_dir))?;
    let moved_to = if source.exists() {
        let mut target = target_dir.join(file);
        let mut n = 1;
        while target.exists() {
            target = target_dir.join(format!("{file}.{n}"));
            n += 1;
        }
        fs::rename(&source, &target).map_err(StoreError::io("move to quarantine", &source))?;
        durable::sync_dir(&target_dir)?;
        durable::sync_dir(&dir.join(BATCH_DIR))?;
        Some(target)
    } else {
        None
    };
    let note = serde_json::json!({
        "at": Utc::now().to_rfc3339_opts(SecondsFormat::Millis, true),
        "file": file,
        "moved_to": moved_to.as_ref().and_then(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned()),
        "reason": reason,
    });
    let notes = target_dir.join("notes.jsonl");
    let mut out = OpenOptions::new().create(true).append(true).open(&notes).map_err(StoreError::io("open", &notes))?;
    writeln!(out, "{note}").and_then(|()| out.sync_data()).map_err(StoreError::io("write", &notes))?;
    Ok(Quarantined { file: file.to_string(), moved_to, reason })
}

/// Verifies each file's size and SHA-256 against its entry, several files at a time; returns one verdict per entry
/// and the bytes hashed.
fn verify_all(dir: &Path, batches: &[BatchEntry]) -> (Vec<Result<(), String>>, u64) {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 8).min(batches.len().max(1));
    let mut verdicts: Vec<Result<(), String>> = vec![Ok(()); batches.len()];
    let mut bytes = 0;
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    let mine = batches.iter().enumerate().skip(t).step_by(threads);
                    mine.map(|(i, b)| (i, verify_file(&dir.join(BATCH_DIR).join(&b.file), b))).collect::<Vec<_>>()
                })
            })
            .collect();
        for worker in workers {
            // A worker cannot panic short of a bug in sha2 or std; were it to, its files count as unverified.
            for (i, verdict) in worker.join().unwrap_or_default() {
                if let Ok(n) = verdict {
                    bytes += n;
                }
                verdicts[i] = verdict.map(|_| ());
            }
        }
    });
    (verdicts, bytes)
}

/// Size and SHA-256 of one file against its entry: the bytes hashed, or why it failed.
fn verify_file(path: &Path, batch: &BatchEntry) -> Result<u64, String> {
    let file = match File::open(path) {
        Ok(file) => file,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Err("missing".into()),
        Err(e) => return Err(format!("cannot open: {e}")),
    };
    let size = file.metadata().map_err(|e| format!("cannot stat: {e}"))?.len();
    if size != batch.size_bytes {
        return Err(format!("{size} bytes, the journal says {} (truncated?)", batch.size_bytes));
    }
    let mut hasher = HashingWriter::new(io::sink());
    io::copy(&mut BufReader::with_capacity(1 << 20, file), &mut hasher).map_err(|e| format!("cannot read: {e}"))?;
    let (_, actual, hashed) = hasher.finish();
    if actual != batch.checksum {
        return Err(format!("corrupt: checksum {actual}, the journal says {}", batch.checksum));
    }
    Ok(hashed)
}

/// One `key.path: old -> new` line per leaf that differs between two metadata (objects compared key by key, arrays
/// and scalars as values).
pub(crate) fn meta_differences(stored: &DatasetMeta, expected: &DatasetMeta) -> Vec<String> {
    let (mut a, mut b) = (BTreeMap::new(), BTreeMap::new());
    flatten("", &serde_json::to_value(stored).unwrap_or(Value::Null), &mut a);
    flatten("", &serde_json::to_value(expected).unwrap_or(Value::Null), &mut b);
    let keys: BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    let show = |v: Option<&Value>| v.map_or_else(|| "(absent)".to_string(), crate::manifest::canonical_json);
    let mut out: Vec<String> = keys
        .into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| format!("{k}: {} -> {}", show(a.get(k)), show(b.get(k))))
        .collect();
    if out.is_empty() {
        // Same values, different hash: only possible if the stored hash was computed differently.
        out.push("config_hash: the metadata hashes differently (same values)".into());
    }
    out
}

fn flatten(prefix: &str, value: &Value, out: &mut BTreeMap<String, Value>) {
    match value {
        Value::Object(map) if !map.is_empty() => {
            for (key, item) in map {
                let path = if prefix.is_empty() { key.clone() } else { format!("{prefix}.{key}") };
                flatten(&path, item, out);
            }
        }
        other => {
            out.insert(prefix.to_string(), other.clone());
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;
    use crate::manifest::{GridSpec, SceneId};

    #[test]
    fn differences_name_each_changed_added_and_removed_leaf() {
        let config = serde_json::json!({"scan": {"repetitions": 5, "band_hz": [62.0, 625.0]}, "old": true});
        let a = DatasetMeta::new(
            "scan",
            config.as_object().cloned().unwrap(),
            SceneId { name: "p".into(), hash: "h".into() },
            "0.1.0",
            1,
            GridSpec::centred(3, 2, 0.005),
        );
        let mut b = a.clone();
        b.config = serde_json::json!({"scan": {"repetitions": 3, "band_hz": [62.0, 625.0]}, "new": "x"})
            .as_object()
            .cloned()
            .unwrap();
        b.seed = 2;
        assert_eq!(
            meta_differences(&a, &b),
            [
                "config.new: (absent) -> \"x\"",
                "config.old: true -> (absent)",
                "config.scan.repetitions: 5 -> 3",
                "seed: 1 -> 2"
            ]
        );
    }
}

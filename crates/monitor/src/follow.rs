//! Following a run directory: the manifest, the journal and the committed files, read the way resume reads them but
//! never written, locked or moved. A poll rereads the journal only when its size or modification time changed and
//! reads each newly committed file once.

use std::collections::{HashMap, HashSet};
use std::fs;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use metaplate_store::journal::{BatchEntry, JournalView};
use metaplate_store::{Dataset, IrMeta, IrRecord, JOURNAL_FILE, MANIFEST_FILE, Manifest, ReadOptions, StoreError};

/// What a run directory holds at one poll.
#[derive(Debug, Clone, Default)]
pub struct RunFiles {
    /// The manifest, once the run has written it.
    pub manifest: Option<Manifest>,
    /// The journal as last read.
    pub journal: JournalView,
    /// The rows of every live file read so far, by file name.
    pub rows: HashMap<String, Vec<IrMeta>>,
    /// The rows, responses included, of the most recent commit whose file is live and read.
    pub last_commit: Option<(u64, Vec<IrRecord>)>,
    /// Why the last poll could not read something (a file quarantined under it, a manifest being written); retried
    /// at the next poll.
    pub problem: Option<String>,
    /// The last lines of the run's log (up to 6 KiB, whole lines), as last read; empty without a log.
    pub log_tail: String,
    /// Free bytes for an unprivileged writer on the run's file system, as last asked (at a commit or a log line).
    pub free_bytes: Option<u64>,
}

impl RunFiles {
    /// The rows of every live file read so far.
    pub fn all_rows(&self) -> impl Iterator<Item = &IrMeta> {
        self.rows.values().flatten()
    }
}

/// Follows one run directory (see the module's documentation).
#[derive(Debug)]
pub struct Follower {
    dir: PathBuf,
    /// Size and modification time of the manifest when last read.
    manifest_stamp: Option<(u64, SystemTime)>,
    /// Size and modification time of the journal when last read completely.
    stamp: Option<(u64, SystemTime)>,
    /// Size and modification time of the log when its tail was last read.
    log_stamp: Option<(u64, SystemTime)>,
    files: RunFiles,
}

/// Size and modification time of `path`, or `None` if it is not there.
fn stamp_of(path: &Path) -> Option<(u64, SystemTime)> {
    fs::metadata(path).ok().and_then(|m| Some((m.len(), m.modified().ok()?)))
}

impl Follower {
    /// Follows `dir`, which need not exist yet.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into(), manifest_stamp: None, stamp: None, log_stamp: None, files: RunFiles::default() }
    }

    /// The directory followed.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// What the directory held at the last poll.
    pub fn files(&self) -> &RunFiles {
        &self.files
    }

    /// Looks at the directory again; returns whether anything the snapshot shows changed. A directory emptied, or
    /// holding another dataset than before (deleted and started again), is followed from scratch.
    pub fn poll(&mut self) -> bool {
        metaplate_store::test_hook::pause_from_env(TEST_POLL_PAUSE_ENV);
        let mut changed = false;
        let manifest_stamp = stamp_of(&self.dir.join(MANIFEST_FILE));
        if manifest_stamp != self.manifest_stamp {
            match Manifest::read(&self.dir) {
                Ok(manifest) => {
                    let same = |old: &Manifest| {
                        old.created_at == manifest.created_at && old.config_hash == manifest.config_hash
                    };
                    if !self.files.manifest.as_ref().is_none_or(same) {
                        self.restart();
                    }
                    self.files.manifest = Some(manifest);
                    self.manifest_stamp = manifest_stamp;
                    changed = true;
                }
                Err(_) if manifest_stamp.is_none() && self.files.manifest.is_some() => {
                    self.restart();
                    return true;
                }
                // Not there yet, or being replaced: looked at again at the next poll.
                Err(_) => {}
            }
        }
        let Some(recipe) = self.files.manifest.as_ref().map(|m| m.meta.recipe.clone()) else { return changed };
        // Every file is read here, on the follower's thread: requests only read what this published, so a slow
        // disk delays the page's news, never its answers.
        let log = log_path(&self.dir, &recipe);
        let log_stamp = log.as_deref().and_then(stamp_of);
        if log_stamp != self.log_stamp {
            self.files.log_tail = log.as_deref().map(log_tail).unwrap_or_default();
            self.files.free_bytes = metaplate_store::free_bytes(&self.dir);
            self.log_stamp = log_stamp;
            changed = true;
        }
        let stamp = stamp_of(&self.dir.join(JOURNAL_FILE));
        if stamp.is_none() || stamp == self.stamp {
            return changed;
        }
        match self.read_journal() {
            Ok(()) => {
                self.stamp = stamp;
                self.files.problem = None;
                self.files.free_bytes = metaplate_store::free_bytes(&self.dir);
            }
            // Left unstamped, so that the next poll tries again.
            Err(e) => self.files.problem = Some(e.to_string()),
        }
        true
    }

    /// Forgets everything read.
    fn restart(&mut self) {
        (self.manifest_stamp, self.stamp, self.log_stamp, self.files) = (None, None, None, RunFiles::default());
    }

    /// Rereads the journal and reads the live files not read yet; forgets files no longer live.
    fn read_journal(&mut self) -> Result<(), StoreError> {
        let Some(view) = metaplate_store::journal::view(&self.dir)? else { return Ok(()) };
        let live: HashSet<&str> = view.live.iter().map(|b| b.file.as_str()).collect();
        self.files.rows.retain(|file, _| live.contains(file.as_str()));
        let mut result = Ok(());
        for batch in &view.live {
            if self.files.rows.contains_key(&batch.file) {
                continue;
            }
            match read(&self.dir, batch) {
                Ok(records) => {
                    self.files.rows.insert(batch.file.clone(), records.iter().map(|r| r.meta).collect());
                    let seq = view.commits.iter().find(|c| c.batch.file == batch.file).map(|c| c.seq);
                    if let Some(seq) = seq
                        && self.files.last_commit.as_ref().is_none_or(|(last, _)| seq > *last)
                    {
                        self.files.last_commit = Some((seq, records));
                    }
                }
                Err(e) => result = Err(e),
            }
        }
        self.files.journal = view;
        result
    }
}

/// Bytes of the log's tail shown.
const LOG_TAIL_BYTES: u64 = 6 * 1024;

/// Test hook, not an API: the environment variable a test sets to a number of milliseconds every poll then takes
/// before it reads anything, as on a slow disk (`metaplate_store::test_hook`); unset (or not a number) means no pause.
#[doc(hidden)]
pub const TEST_POLL_PAUSE_ENV: &str = "METAPLATE_TEST_POLL_PAUSE_MS";

/// The run's log (`scan.log`, `calibrate.log`, or any `*.log`) in `dir`.
fn log_path(dir: &Path, recipe: &str) -> Option<PathBuf> {
    let named = dir.join(format!("{recipe}.log"));
    if named.is_file() {
        return Some(named);
    }
    let entries = fs::read_dir(dir).ok()?;
    entries.filter_map(Result::ok).map(|e| e.path()).find(|p| p.extension().is_some_and(|x| x == "log"))
}

/// The last lines of the log at `path` (up to [`LOG_TAIL_BYTES`], whole lines), or empty.
fn log_tail(path: &Path) -> String {
    let Ok(mut file) = fs::File::open(path) else { return String::new() };
    let len = file.metadata().map_or(0, |m| m.len());
    let start = len.saturating_sub(LOG_TAIL_BYTES);
    let mut bytes = Vec::new();
    if file.seek(SeekFrom::Start(start)).is_err() || file.take(LOG_TAIL_BYTES).read_to_end(&mut bytes).is_err() {
        return String::new();
    }
    let text = String::from_utf8_lossy(&bytes);
    // A cut first line is dropped, unless it is all there is.
    match text.split_once('\n') {
        Some((_, rest)) if start > 0 => rest.to_owned(),
        _ => text.into_owned(),
    }
}

fn read(dir: &Path, batch: &BatchEntry) -> Result<Vec<IrRecord>, StoreError> {
    Dataset::read_batch(dir, batch, ReadOptions::default())
}

/// The committed rows, responses included, of grid point `point` (scan) or unit `point` (the point index a
/// calibration's rows carry), from the live file that holds it; `None` when no live file does.
///
/// # Errors
/// As [`Dataset::read_batch`].
pub fn point_records(dir: &Path, journal: &JournalView, point: u32) -> Result<Option<Vec<IrRecord>>, StoreError> {
    let Some(batch) = journal.live.iter().find(|b| b.keys.iter().any(|(p, _)| *p == point)) else { return Ok(None) };
    let records = read(dir, batch)?;
    Ok(Some(records.into_iter().filter(|r| r.meta.point_index == point).collect()))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use metaplate_store::{BATCH_DIR, DatasetMeta, DatasetWriter, GridSpec, IfExists, SceneId};

    use super::*;

    fn point(grid: &GridSpec, index: u32) -> Vec<IrRecord> {
        let (ix, iy) = (index % grid.nx as u32, index / grid.nx as u32);
        (0..2)
            .map(|a| IrRecord { meta: IrMeta::at_grid(grid, ix, iy, a, 24_000.0).unwrap(), ir: vec![0.5; 8] })
            .collect()
    }

    #[test]
    fn a_follower_reads_each_commit_once_waits_out_a_torn_line_and_a_missing_file_and_starts_over_on_a_new_run() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run");
        let mut follower = Follower::new(&dir);
        assert!(!follower.poll() && follower.files().manifest.is_none(), "nothing there yet");

        let grid = GridSpec::centred(3, 2, 0.005);
        let config = serde_json::json!({"points": [0, 1, 2]}).as_object().cloned().unwrap();
        let meta = DatasetMeta::new("scan", config, SceneId { name: "s".into(), hash: "h".into() }, "0", 1, grid);
        let mut writer = DatasetWriter::create(&dir, meta.clone(), IfExists::Refuse).unwrap();
        writer.commit_batch(&point(&grid, 0)).unwrap();
        assert!(follower.poll());
        assert_eq!((follower.files().rows.len(), follower.files().journal.commits.len()), (1, 1));
        assert_eq!(follower.files().last_commit.as_ref().map(|(seq, rows)| (*seq, rows.len())), Some((0, 2)));
        assert!(!follower.poll(), "nothing new: nothing read again");

        // An append in progress: the line is left for later.
        let journal = dir.join(JOURNAL_FILE);
        let mut text = fs::read(&journal).unwrap();
        let committed_len = text.len();
        text.extend_from_slice(b"{\"seq\":1,\"at\":\"2026");
        fs::write(&journal, &text).unwrap();
        follower.poll();
        assert_eq!(follower.files().journal.commits.len(), 1);
        assert!(follower.files().journal.issues.iter().all(|i| i.torn_tail));
        text.truncate(committed_len);
        fs::write(&journal, &text).unwrap();

        // A committed file gone from under it (a resume quarantining it): said, and tried again at the next poll.
        writer.commit_batch(&point(&grid, 1)).unwrap();
        let second = dir.join(BATCH_DIR).join("batch-000001.parquet");
        let hidden = dir.join("hidden.parquet");
        fs::rename(&second, &hidden).unwrap();
        follower.poll();
        assert!(follower.files().problem.is_some(), "the missing file is reported");
        assert_eq!(follower.files().rows.len(), 1);
        fs::rename(&hidden, &second).unwrap();
        follower.poll();
        assert_eq!((follower.files().rows.len(), follower.files().problem.as_deref()), (2, None));
        assert_eq!(follower.files().last_commit.as_ref().map(|(seq, _)| *seq), Some(1));
        drop(writer);

        // The directory deleted and a new run started in it: followed from scratch.
        fs::remove_dir_all(&dir).unwrap();
        assert!(follower.poll() && follower.files().manifest.is_none() && follower.files().rows.is_empty());
        let mut writer = DatasetWriter::create(&dir, meta, IfExists::Refuse).unwrap();
        writer.commit_batch(&point(&grid, 2)).unwrap();
        assert!(follower.poll());
        let points: Vec<u32> = follower.files().all_rows().map(|m| m.point_index).collect();
        assert_eq!(points, [2, 2]);
    }
}

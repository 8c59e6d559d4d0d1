//! One writer per session: the session's journal is locked by the process that runs it, with the store's writer
//! lock (`metaplate_store::lock`: released by the operating system when the process dies, so a `kill -9` never
//! leaves it held), and the holder records its pid and host in `writer.json` beside it. A second process is refused
//! at once, naming the session and the holder, and writes nothing.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};

use metaplate_store::{LockHolder, StoreError, try_lock_exclusive};

use crate::error::ExperimentError;

/// The journal file of a session directory: the file its writer appends to and locks.
pub const JOURNAL_FILE: &str = "journal.jsonl";

/// Where the process holding a session's lock records itself (pid and host, JSON).
pub const WRITER_FILE: &str = "writer.json";

/// A session's writer lock, held: the journal open for appending and locked.
#[derive(Debug)]
pub struct SessionLock {
    journal: File,
    dir: PathBuf,
}

impl SessionLock {
    /// Locks the session in `dir` if it has a journal; `None` for a directory without a session (nothing is
    /// created).
    ///
    /// # Errors
    /// [`ExperimentError::Locked`] when another process holds it; [`ExperimentError::Io`].
    pub fn acquire_existing(dir: &Path) -> Result<Option<Self>, ExperimentError> {
        let path = dir.join(JOURNAL_FILE);
        if !path.exists() {
            return Ok(None);
        }
        let journal = OpenOptions::new().append(true).open(&path).map_err(ExperimentError::io("open", &path))?;
        Self::lock(journal, dir, &path).map(Some)
    }

    /// Creates `dir` and an empty journal in it (or opens the one there) and locks it: the first step of a new
    /// session.
    ///
    /// # Errors
    /// As [`SessionLock::acquire_existing`].
    pub fn create(dir: &Path) -> Result<Self, ExperimentError> {
        std::fs::create_dir_all(dir).map_err(ExperimentError::io("create", dir))?;
        let path = dir.join(JOURNAL_FILE);
        let journal =
            OpenOptions::new().create(true).append(true).open(&path).map_err(ExperimentError::io("create", &path))?;
        Self::lock(journal, dir, &path)
    }

    fn lock(journal: File, dir: &Path, path: &Path) -> Result<Self, ExperimentError> {
        try_lock_exclusive(&journal, path).map_err(|e| match e {
            StoreError::Locked { .. } => ExperimentError::Locked {
                dir: dir.to_path_buf(),
                holder: LockHolder::read(dir, WRITER_FILE).map_or_else(|| "pid unknown".to_owned(), |h| h.to_string()),
            },
            other => other.into(),
        })?;
        LockHolder::this_process().record(dir, WRITER_FILE)?;
        Ok(Self { journal, dir: dir.to_path_buf() })
    }

    /// The session directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The locked journal: the lock lasts as long as this file is open.
    pub(crate) fn into_journal(self) -> File {
        self.journal
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    #[test]
    fn a_second_lock_is_refused_naming_the_holder_and_a_dropped_one_is_free() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("S");
        assert!(SessionLock::acquire_existing(&dir).unwrap().is_none());
        assert!(!dir.exists(), "nothing is created for a directory without a session");
        let first = SessionLock::create(&dir).unwrap();
        let journal_before = std::fs::read(dir.join(JOURNAL_FILE)).unwrap();
        let err = SessionLock::acquire_existing(&dir).unwrap_err();
        let text = err.to_string();
        assert!(text.contains(&dir.display().to_string()), "{text}");
        assert!(text.contains(&format!("pid {}", std::process::id())), "{text}");
        assert!(matches!(SessionLock::create(&dir), Err(ExperimentError::Locked { .. })));
        assert_eq!(std::fs::read(dir.join(JOURNAL_FILE)).unwrap(), journal_before);
        drop(first);
        assert!(SessionLock::acquire_existing(&dir).unwrap().is_some());
    }
}

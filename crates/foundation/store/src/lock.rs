//! One writer at a time: the exclusive lock a writer takes on the file it appends to (a dataset's `journal.jsonl`,
//! an experiment session's journal), and who holds it.
//!
//! The lock is the operating system's advisory whole-file lock (`flock` on Unix, `LockFileEx` on Windows, through
//! [`File::try_lock`]): it lives as long as the open file, and the system releases it when the process dies, so a
//! `kill -9` never leaves a lock behind. A writer may also record itself ([`LockHolder::record`]: its pid and host in
//! a small file beside the locked one), so that a refused process can name the one it waits for; a stale record
//! (its process gone) is harmless, since only the lock decides.

use std::fs::{File, TryLockError};
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::durable::write_bytes;
use crate::error::StoreError;

/// Takes the exclusive writer lock on `file` (opened from `path`) without waiting.
///
/// # Errors
/// [`StoreError::Locked`] when another open file (this process's or another's) holds it; [`StoreError::Io`].
pub fn try_lock_exclusive(file: &File, path: &Path) -> Result<(), StoreError> {
    match file.try_lock() {
        Ok(()) => Ok(()),
        Err(TryLockError::WouldBlock) => Err(StoreError::Locked { path: path.to_path_buf() }),
        Err(TryLockError::Error(e)) => Err(StoreError::from_io("lock", path.to_path_buf(), e)),
    }
}

/// The process that holds a writer lock, as it recorded itself.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LockHolder {
    /// Its process id.
    pub pid: u32,
    /// Its host's name, where the system gives one.
    pub host: Option<String>,
}

impl LockHolder {
    /// This process, on this host.
    #[must_use]
    pub fn this_process() -> Self {
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .ok()
            .or_else(|| std::env::var("HOSTNAME").ok())
            .or_else(|| std::env::var("COMPUTERNAME").ok())
            .map(|h| h.trim().to_owned())
            .filter(|h| !h.is_empty());
        Self { pid: std::process::id(), host }
    }

    /// Writes this holder durably as `dir/name` (JSON), replacing an earlier record. Call it holding the lock.
    ///
    /// # Errors
    /// [`StoreError::Io`] / [`StoreError::DiskFull`].
    pub fn record(&self, dir: &Path, name: &str) -> Result<(), StoreError> {
        let json = serde_json::to_vec(self)
            .map_err(|e| StoreError::from_io("encode", dir.join(name), std::io::Error::other(e)))?;
        write_bytes(dir, name, &json)
    }

    /// The holder recorded as `dir/name`, if a readable record is there.
    #[must_use]
    pub fn read(dir: &Path, name: &str) -> Option<Self> {
        serde_json::from_slice(&std::fs::read(dir.join(name)).ok()?).ok()
    }
}

impl std::fmt::Display for LockHolder {
    /// `pid N on HOST`, or `pid N` without a host.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "pid {}", self.pid)?;
        if let Some(host) = &self.host {
            write!(f, " on {host}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    #[test]
    fn a_second_open_file_is_refused_until_the_first_closes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("journal.jsonl");
        let first = File::create(&path).unwrap();
        try_lock_exclusive(&first, &path).unwrap();
        let second = File::options().append(true).open(&path).unwrap();
        assert!(matches!(try_lock_exclusive(&second, &path), Err(StoreError::Locked { .. })));
        drop(first);
        try_lock_exclusive(&second, &path).unwrap();
    }

    #[test]
    fn a_holder_records_itself_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(LockHolder::read(dir.path(), "writer.json"), None);
        let me = LockHolder::this_process();
        me.record(dir.path(), "writer.json").unwrap();
        assert_eq!(LockHolder::read(dir.path(), "writer.json"), Some(me.clone()));
        assert!(me.to_string().starts_with(&format!("pid {}", std::process::id())));
    }
}

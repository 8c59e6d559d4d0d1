//! `metaplate monitor`: a read-only web page and API that follow a calibration or scan directory while it runs, after
//! it finished, or after it was killed.
//!
//! The monitor reads what resume reads (`manifest.json`, `journal.jsonl`, the committed Parquet files, the run's
//! log) and nothing else; it opens every file read-only, takes no lock, and tolerates a torn last journal line and
//! files appearing (or being quarantined) under it, so it can never harm the run. It is a separate process: the
//! recipes, drivers and mocks know nothing of it, and its async runtime (tokio) stays out of the measurement path.
//!
//! It binds a loopback address only ([`serve`] refuses any other), refuses a request whose `Host` header is not a
//! loopback name with 403 (DNS rebinding), and answers only GET and HEAD (405 otherwise). To watch from another
//! machine, tunnel: `ssh -L 8765:127.0.0.1:8765 lab-pc`, then open `http://localhost:8765/`.
//!
//! Endpoints:
//! - `/`: one self-contained page (inline script and style; it fetches only this API) with the grid by status, the
//!   SNR map on a fixed scale, the last committed point's spectra, progress, the remaining time, retries, free disk,
//!   the time since the last commit with a stall warning (once the run has ended: when it did), and the log's tail;
//!   it updates on each `commit` event.
//! - `/api/state`: a JSON snapshot: `status` (`waiting` for the dataset, `running`, `stalled`, `stopped`,
//!   `finished`), `recipe`, `unit` (`point` or `actuator`), `points_total`, `points_done` (units), `status_counts`
//!   (units by worst status: `measured`, `re-measured`, `overrange`, `dropout`, `failed`, `pending`), `started_at`,
//!   `elapsed_s` (wall clock since the dataset was created, to the last commit once finished), `median_point_s`,
//!   `remaining_s: {median, p90}` (from the journal's commit times, by `metaplate_recipes::RemainingTime`),
//!   `finish_at: {median, p90}` (clock times, RFC 3339 UTC), `last_commit_age_s`, `stall_after_s`, `stalled`,
//!   `retries` (the committed rows' retries), `re_measured` (rows), `disk: {free_bytes, need_bytes}` (free space of
//!   the run's file system, and the mean committed file size times the units left), `last_seq`, `journal_issues`,
//!   `problem` (a read that failed and will be retried).
//! - `/api/view`: what the page draws: `state`, `status_svg`, `snr_svg`, `snr_scale_db`, `spectrum` (the last
//!   committed point's magnitude per actuator, dB on log-spaced frequencies), `log_tail`.
//! - `/api/point/N`: grid point N's committed rows (actuator, status, SNR, retries, time, impulse response) and its
//!   worst status; 404 while it is not committed.
//! - `/events`: server-sent events, one `commit` per journal commit with `id` its sequence number and data
//!   `{seq, at, file, point (a calibration: actuator), rows, status, snr_db}`; `Last-Event-ID: N` replays the
//!   commits after N; a comment every [`KEEP_ALIVE`] keeps an idle stream open.
//!
//! # How it reads and serves
//!
//! - [`follow`], on a thread of its own: the manifest; the journal through `metaplate_store::journal::view` when its
//!   size or modification time changes; each newly committed file once, through
//!   `metaplate_store::Dataset::read_batch`. Files are only opened for reading, with no lock; a torn last line, and
//!   files quarantined under it, are tolerated and retried at the next poll ([`POLL_INTERVAL`]). The log's tail and
//!   the free space (`metaplate_store::free_bytes`) are read there too, so a request never waits for the disk
//!   (`/api/point/N` apart, which reads its point's file on a blocking task).
//! - [`state`]: the `/api/state` snapshot and the commit events, from what the follower read; the per-point status
//!   and SNR reduction and its fixed SNR scale are `metaplate_recipes::cells`, which the report's maps use too.
//! - [`view`]: what the page draws and one point's rows. The page (`page.html`) is self-contained and carries the
//!   view it was served with.
//! - The server: axum on a current-thread tokio runtime, the Host and method guard ([`is_loopback_host`]), the
//!   routes and the server-sent events.
//! - [`notices`]: `--notify-command` for a run the monitor watches: once per change of the run's status to
//!   finished, stopped, failed or stalled.

pub mod follow;
pub mod notices;
mod server;
pub mod state;
pub mod view;

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, RwLock};

pub use server::{KEEP_ALIVE, POLL_INTERVAL, is_loopback_host};

/// Why the monitor could not serve.
#[derive(Debug, thiserror::Error)]
pub enum MonitorError {
    /// The address to bind is not a loopback address.
    #[error(
        "{addr} is not a loopback address: the monitor serves this machine only (bind 127.0.0.1 or [::1], and use \
         `ssh -L PORT:127.0.0.1:PORT HOST` to watch from elsewhere)"
    )]
    NotLoopback {
        /// The address asked for.
        addr: SocketAddr,
    },
    /// The path to follow is there and is not a directory.
    #[error("{} is a file, not a run directory: give the directory a scan or a calibration writes (its --out)", path.display())]
    NotADirectory {
        /// The path given.
        path: PathBuf,
    },
    /// Starting the runtime, binding or serving failed.
    #[error("{op}: {source}")]
    Io {
        /// What was being done.
        op: &'static str,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// Refuses a `run_dir` that is there and is not a directory (a file given by mistake would otherwise be waited for
/// forever); a path that does not exist yet is a run still to start, and passes.
///
/// # Errors
/// [`MonitorError::NotADirectory`], naming the path.
pub fn check_run_dir(run_dir: &Path) -> Result<(), MonitorError> {
    match std::fs::metadata(run_dir) {
        Ok(meta) if !meta.is_dir() => Err(MonitorError::NotADirectory { path: run_dir.to_path_buf() }),
        _ => Ok(()),
    }
}

/// Serves the monitor of the run directory `run_dir` (which need not exist yet) on `bind`, a loopback address (port
/// 0: any free port), until the process ends. `on_ready` is called once with the address bound, before the first
/// request is served.
///
/// # Errors
/// [`MonitorError::NotADirectory`] for a path that is not a directory ([`check_run_dir`]);
/// [`MonitorError::NotLoopback`] for another address; [`MonitorError::Io`] if the address cannot be bound or the
/// runtime cannot start.
pub fn serve(
    run_dir: impl Into<PathBuf>,
    bind: SocketAddr,
    on_ready: impl FnOnce(SocketAddr),
) -> Result<(), MonitorError> {
    let run_dir = run_dir.into();
    check_run_dir(&run_dir)?;
    if !bind.ip().is_loopback() {
        return Err(MonitorError::NotLoopback { addr: bind });
    }
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .enable_time()
        .build()
        .map_err(|source| MonitorError::Io { op: "starting the runtime", source })?;
    let mut follower = follow::Follower::new(run_dir);
    follower.poll();
    let (changes, _) = tokio::sync::watch::channel(0);
    let files = RwLock::new(Arc::new(follower.files().clone()));
    let shared = Arc::new(server::Shared { dir: follower.dir().to_path_buf(), files, changes });
    let follower_share = Arc::clone(&shared);
    std::thread::Builder::new()
        .name("monitor-follow".into())
        .spawn(move || server::follow(follower, &follower_share))
        .map_err(|source| MonitorError::Io { op: "starting the follower thread", source })?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(bind)
            .await
            .map_err(|source| MonitorError::Io { op: "binding the address", source })?;
        let addr = listener.local_addr().map_err(|source| MonitorError::Io { op: "binding the address", source })?;
        on_ready(addr);
        axum::serve(listener, server::router(shared)).await.map_err(|source| MonitorError::Io { op: "serving", source })
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn a_file_is_refused_by_name_at_once_and_a_directory_yet_to_come_is_not() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("scan.log");
        std::fs::write(&file, "not a run").unwrap();
        let loopback = SocketAddr::from(([127, 0, 0, 1], 0));
        let error = serve(&file, loopback, |_| panic!("a file must not be served")).unwrap_err();
        assert!(matches!(&error, MonitorError::NotADirectory { path } if *path == file), "{error}");
        assert_eq!(
            error.to_string(),
            format!(
                "{} is a file, not a run directory: give the directory a scan or a calibration writes (its --out)",
                file.display()
            )
        );
        assert!(check_run_dir(&tmp.path().join("not-yet")).is_ok());
        assert!(check_run_dir(tmp.path()).is_ok());
    }
}

//! How a caller steers a running recipe (stop requests, a test hook) and what the recipe tells it (events).

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU64, AtomicUsize, Ordering};

/// Shared stop state of a run: the CLI's Ctrl-C handler raises it, the recipe reads it between steps.
///
/// Level 0: run. Level 1 (first Ctrl-C): finish the point in flight, commit it, stop. Level 2 (second Ctrl-C):
/// abandon the point in flight (nothing of it is committed) and stop. Commits themselves are never interrupted,
/// so neither level can corrupt the dataset.
#[derive(Debug, Clone)]
pub struct RunControl {
    level: Arc<AtomicU8>,
    stop_after_commits: Arc<AtomicUsize>,
    /// Test hook: bytes the dataset writer may write (`u64::MAX`: unlimited).
    write_budget_bytes: Arc<AtomicU64>,
}

impl Default for RunControl {
    /// As [`RunControl::new`] (a derived default would stop after the first commit and allow no writes).
    fn default() -> Self {
        Self::new()
    }
}

impl RunControl {
    /// A control that never stops by itself.
    pub fn new() -> Self {
        Self {
            level: Arc::new(AtomicU8::new(0)),
            stop_after_commits: Arc::new(AtomicUsize::new(usize::MAX)),
            write_budget_bytes: Arc::new(AtomicU64::new(u64::MAX)),
        }
    }

    /// Raises the stop level by one (saturating at 2) and returns the new level: what a Ctrl-C handler calls.
    pub fn request_stop(&self) -> u8 {
        let previous = self.level.fetch_update(Ordering::AcqRel, Ordering::Acquire, |l| Some((l + 1).min(2)));
        previous.map_or(2, |l| (l + 1).min(2))
    }

    /// The stop level: 0 run, 1 stop after the current commit, 2 abandon the point in flight.
    pub fn level(&self) -> u8 {
        self.level.load(Ordering::Acquire)
    }

    /// Whether the recipe should stop before starting the next point.
    pub fn stop_requested(&self) -> bool {
        self.level() >= 1
    }

    /// Whether the point in flight should be abandoned.
    pub fn abandon_requested(&self) -> bool {
        self.level() >= 2
    }

    /// Test hook: behave as if Ctrl-C were pressed once right after the `commits`-th commit of this run (counting
    /// from 1; commits made by earlier runs of a resumed dataset do not count).
    pub fn stop_after_commits(&self, commits: usize) {
        self.stop_after_commits.store(commits, Ordering::Release);
    }

    /// Test hook: the dataset a run opens with this control may take at most `bytes` more bytes (batch files,
    /// journal lines and manifest together); a write beyond fails as a full disk does. See
    /// `metaplate_store::DatasetWriter::with_write_budget`.
    pub fn limit_writes(&self, bytes: u64) {
        self.write_budget_bytes.store(bytes, Ordering::Release);
    }

    /// The write budget set by [`RunControl::limit_writes`], bytes; `None` when unlimited.
    pub(crate) fn write_budget_bytes(&self) -> Option<u64> {
        Some(self.write_budget_bytes.load(Ordering::Acquire)).filter(|b| *b != u64::MAX)
    }

    /// Called by the recipe after each commit, with the number of commits made by this run.
    pub(crate) fn committed(&self, commits_this_run: usize) {
        if commits_this_run >= self.stop_after_commits.load(Ordering::Acquire) {
            self.level.fetch_max(1, Ordering::AcqRel);
        }
    }
}

/// Something a recipe reports while it runs: the CLI turns these into a progress bar, log lines and `--json`
/// progress events.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// The run starts: `total` units (points for a scan, actuators for a calibration), `done` of them already
    /// committed by an earlier run.
    Started {
        /// Units in the whole run.
        total: usize,
        /// Units already committed (resume).
        done: usize,
        /// The dataset's directory.
        dataset: std::path::PathBuf,
        /// The dataset's configuration hash (`sha256:<hex>`), as its manifest holds it.
        config_hash: String,
        /// Whether an earlier run in the directory was continued; false for a new dataset, also when a resume was
        /// asked for a directory that held no run (the observer says so).
        resumed: bool,
    },
    /// What the run is doing now, for a live display: sent as each step of a unit begins.
    Phase {
        /// Grid point index (scan) or actuator number (calibration).
        unit: usize,
        /// The step.
        phase: Phase,
        /// While playing: the actuators driven (by their non-silent audio channels); empty otherwise.
        actuators: Vec<usize>,
    },
    /// One unit committed.
    Committed {
        /// Grid point index (scan) or actuator number (calibration).
        unit: usize,
        /// Units committed so far, this run and earlier ones.
        done: usize,
        /// Units in the whole run.
        total: usize,
        /// Median SNR of the unit's rows, dB, when measured.
        snr_db: Option<f64>,
        /// Status of the unit's worst row, as stored (`valid`, `re-measured`, ...).
        status: String,
        /// Simulated or real seconds since the run started, on the rig's clock.
        clock_s: f64,
        /// Where the unit was measured: its first row's grid column and row and position (m); for a calibration,
        /// the actuator's magnet.
        position: Option<UnitPosition>,
    },
    /// A measurement is repeated (bounded retry) or a point deferred to the end of the run.
    Retry {
        /// Grid point index or actuator.
        unit: usize,
        /// Attempt number about to be made (1 is the first repetition).
        attempt: u32,
        /// Why.
        reason: String,
    },
    /// A device fault was recovered (reconnect, reopen, settings re-applied).
    Recovered {
        /// What failed and what was done.
        detail: String,
    },
    /// A device has been unreachable longer than the configured limit: the run is paused and keeps polling.
    Paused {
        /// What is being waited for.
        detail: String,
    },
    /// After a device recovery, a committed point was measured again and compared with its committed response.
    ReferenceChecked {
        /// Grid point index of the reference.
        point: usize,
        /// Actuator re-measured.
        actuator: usize,
        /// Relative error of the new response against the committed one, dB (-20 dB: 10 % in amplitude).
        deviation_db: f64,
        /// Above this the rig is suspect and a warning is logged, dB.
        limit_db: f64,
    },
    /// The run stopped early on request; everything committed is kept.
    Stopped {
        /// Units committed.
        done: usize,
    },
    /// The run completed.
    Finished {
        /// Units committed.
        done: usize,
    },
}

/// A step of a unit, as [`Event::Phase`] reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Aiming the beam (moving the mirrors, settling, checking the signal).
    Moving,
    /// Playing the excitation and recording.
    Playing,
    /// Waiting for the unit's processing (deconvolution, quality gates, filter design).
    Processing,
    /// Writing the unit to the dataset (fsync'd batch, journal, manifest).
    Committing,
}

impl Phase {
    /// The word a display shows.
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Moving => "moving",
            Phase::Playing => "playing",
            Phase::Processing => "processing",
            Phase::Committing => "committing",
        }
    }
}

/// Where a committed unit was measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitPosition {
    /// Grid column.
    pub ix: u32,
    /// Grid row.
    pub iy: u32,
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
}

/// Receives a recipe's events (the CLI's progress display, a test's recorder).
pub trait Observer {
    /// Called for each event, on the recipe's thread.
    fn event(&mut self, event: &Event);
}

/// An observer that ignores everything.
#[derive(Debug, Default, Clone, Copy)]
pub struct Silent;

impl Observer for Silent {
    fn event(&mut self, _event: &Event) {}
}

impl<F: FnMut(&Event)> Observer for F {
    fn event(&mut self, event: &Event) {
        self(event)
    }
}

impl Event {
    /// Logs this event of `recipe`'s run (target `metaplate::run`, which the monitor reads): the start, commits,
    /// retries, recoveries, the end; not phases (a moment, not news).
    pub fn log(&self, recipe: &str) {
        match self {
            Event::Started { total, done, dataset, config_hash, .. } => {
                tracing::info!(total, done, dataset = %dataset.display(), config_hash, "{recipe} started")
            }
            Event::Committed { unit, done, total, snr_db, status, clock_s, .. } => {
                tracing::info!(unit, done, total, ?snr_db, status = %status, clock_s, "committed")
            }
            Event::Phase { .. } => {}
            Event::Retry { unit, attempt, reason } => tracing::info!(unit, attempt, %reason, "retry"),
            Event::Recovered { detail } => tracing::warn!(%detail, "recovered"),
            Event::Paused { detail } => tracing::warn!(%detail, "paused, polling"),
            Event::ReferenceChecked { point, actuator, deviation_db, limit_db } => {
                tracing::info!(point, actuator, deviation_db, limit_db, "reference point re-measured")
            }
            Event::Stopped { done } => tracing::info!(done, "stopped on request"),
            Event::Finished { done } => tracing::info!(done, "finished"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_levels_saturate_and_the_hook_raises_level_one() {
        let control = RunControl::new();
        assert!(!control.stop_requested());
        assert_eq!(control.request_stop(), 1);
        assert!(control.stop_requested() && !control.abandon_requested());
        assert_eq!(control.request_stop(), 2);
        assert_eq!(control.request_stop(), 2);
        assert!(control.abandon_requested());

        let hooked = RunControl::new();
        hooked.stop_after_commits(3);
        hooked.committed(2);
        assert!(!hooked.stop_requested());
        hooked.committed(3);
        assert_eq!(hooked.level(), 1);
    }

    #[test]
    fn the_default_control_runs_unlimited() {
        let control = RunControl::default();
        control.committed(usize::MAX - 1);
        assert!(!control.stop_requested(), "no stop hook by default");
        assert_eq!(control.write_budget_bytes(), None);
        control.limit_writes(1000);
        assert_eq!(control.write_budget_bytes(), Some(1000));
    }
}

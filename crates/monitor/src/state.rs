//! What `/api/state` and `/events` say, computed from what [`crate::follow`] read: progress, status counts, the
//! remaining-time estimates, the stall flag, disk space ([`RunState`]); one commit ([`CommitEvent`]).
//!
//! Every type here derives `Serialize` with its fields in alphabetical order: the JSON the monitor served when
//! these were `serde_json::Value` objects (whose keys sort), byte for byte.

use std::collections::BTreeMap;
use std::path::Path;

use chrono::{DateTime, SecondsFormat, Utc};
use metaplate_figures::CellStatus;
use metaplate_recipes::RemainingTime;
use metaplate_recipes::cells::{cell_status, planned_points, rank};
use metaplate_store::{IrMeta, JournalCommit, Status};
use serde::Serialize;
use serde_json::{Map, Value};

use crate::follow::RunFiles;

/// A run whose last commit is older than this many median point times (and [`STALL_MIN_S`]) is flagged as stalled.
pub const STALL_FACTOR: f64 = 4.0;
/// The shortest time without a commit that counts as a stall, s: a mock-lab point takes a fraction of a second.
pub const STALL_MIN_S: f64 = 30.0;
/// What a run measures one unit at a time, as its recipe says: grid points (scan) or actuators (calibrate).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Units {
    Points,
    Actuators,
}

impl Units {
    /// The units of a run with configuration `config`, and how many it plans.
    pub(crate) fn of_config(config: &Map<String, Value>) -> (Units, usize) {
        match config.get("actuator_sites_m").and_then(Value::as_array) {
            Some(sites) => (Units::Actuators, sites.len()),
            None => (Units::Points, planned_points(config).len()),
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Units::Points => "point",
            Units::Actuators => "actuator",
        }
    }

    fn of_row(self, meta: &IrMeta) -> u32 {
        match self {
            Units::Points => meta.point_index,
            Units::Actuators => u32::from(meta.actuator),
        }
    }
}

/// Seconds since the Unix epoch of an RFC 3339 time, or `None` if it is not one.
fn unix_s(at: &str) -> Option<f64> {
    DateTime::parse_from_rfc3339(at).ok().map(|t| t.timestamp_millis() as f64 / 1e3)
}

fn clock_time(unix_s: f64) -> Option<String> {
    DateTime::<Utc>::from_timestamp_millis((unix_s * 1e3).round() as i64)
        .map(|t| t.to_rfc3339_opts(SecondsFormat::Secs, true))
}

/// Per unit: its worst status over its rows, its lowest finite SNR.
pub(crate) fn unit_cells<'a>(
    units: Units,
    rows: impl Iterator<Item = &'a IrMeta>,
) -> BTreeMap<u32, (CellStatus, Option<f64>)> {
    let mut out: BTreeMap<u32, (CellStatus, Option<f64>)> = BTreeMap::new();
    for meta in rows {
        let status = cell_status(meta.status);
        let snr = meta.snr_db.filter(|v| v.is_finite());
        let entry = out.entry(units.of_row(meta)).or_insert((status, snr));
        if rank(status) > rank(entry.0) {
            entry.0 = status;
        }
        if let Some(v) = snr {
            entry.1 = Some(entry.1.map_or(v, |c| c.min(v)));
        }
    }
    out
}

/// How the run's own log says it last ended, if it did since it last started: `finished` or `stopped`, with the
/// number of units the run had committed then (its `done=N`).
fn logged_end(log: &str) -> Option<(RunStatus, Option<usize>)> {
    let line = log.lines().rev().find(|l| {
        l.contains("metaplate::run:")
            && (l.contains(" started") || l.contains(" finished") || l.contains("stopped") || l.contains("run failed"))
    })?;
    let done = line.split_whitespace().find_map(|w| w.strip_prefix("done=")).and_then(|n| n.parse().ok());
    // "run failed" first: its message (after it) may name any word.
    if line.contains("run failed") {
        Some((RunStatus::Failed, None))
    } else if line.contains(" started") {
        None
    } else if line.contains(" finished") {
        Some((RunStatus::Finished, done))
    } else {
        Some((RunStatus::Stopped, done))
    }
}

/// A run as the monitor sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// No dataset in the directory yet.
    Waiting,
    /// Committing.
    Running,
    /// No commit for longer than [`RunState::stall_after_s`].
    Stalled,
    /// Stopped on request (its log says so), not finished.
    Stopped,
    /// Every planned unit committed.
    Finished,
    /// Ended in an error (its log says so).
    Failed,
}

impl RunStatus {
    /// The status's name, as the JSON and the page spell it.
    pub fn as_str(self) -> &'static str {
        match self {
            RunStatus::Waiting => "waiting",
            RunStatus::Running => "running",
            RunStatus::Stalled => "stalled",
            RunStatus::Stopped => "stopped",
            RunStatus::Finished => "finished",
            RunStatus::Failed => "failed",
        }
    }

    /// Whether the run has ended: finished, stopped or failed.
    pub fn has_ended(self) -> bool {
        matches!(self, RunStatus::Finished | RunStatus::Stopped | RunStatus::Failed)
    }
}

/// A pair of estimates: the median and the 90th percentile (`null` while unknown).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimates<T> {
    /// The median.
    pub median: Option<T>,
    /// The 90th percentile.
    pub p90: Option<T>,
}

/// Free space and the space the rest of the run needs, bytes (`null` while unknown).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Disk {
    /// Free bytes for an unprivileged writer on the run's file system.
    pub free_bytes: Option<u64>,
    /// The mean committed file size times the units left.
    pub need_bytes: Option<u64>,
}

/// The `/api/state` snapshot (see the crate's documentation for each field). A field skipped when `None` is
/// absent while the run is [`RunStatus::Waiting`] (there is no dataset to say it), and present (its value possibly
/// `null`) once there is one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunState {
    /// The run's directory, as given.
    pub dir: String,
    /// Free and needed disk space.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disk: Option<Disk>,
    /// Wall-clock seconds since the dataset was created (to the last commit once finished).
    pub elapsed_s: f64,
    /// When the run will finish, clock times (RFC 3339 UTC); `null`s once finished.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub finish_at: Option<Estimates<String>>,
    /// The journal's damaged or torn lines.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub journal_issues: Option<Vec<String>>,
    /// Seconds since the last commit (or the dataset's creation).
    pub last_commit_age_s: Option<f64>,
    /// The last commit's sequence number.
    pub last_seq: Option<u64>,
    /// The median time per unit, s (`Some(None)`: not known yet).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub median_point_s: Option<Option<f64>>,
    /// Units committed.
    pub points_done: usize,
    /// Units planned.
    pub points_total: Option<usize>,
    /// A read that failed and will be retried.
    pub problem: Option<String>,
    /// Rows re-measured.
    pub re_measured: usize,
    /// `scan` or `calibrate`.
    pub recipe: Option<String>,
    /// The remaining time, s.
    pub remaining_s: Estimates<f64>,
    /// The committed rows' retries.
    pub retries: u64,
    /// A run without a commit for longer than this is stalled, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stall_after_s: Option<f64>,
    /// Whether the run is stalled.
    pub stalled: bool,
    /// When the dataset was created (RFC 3339).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub started_at: Option<String>,
    /// The run's status.
    pub status: RunStatus,
    /// Units by their worst status (`pending`: planned, not committed).
    pub status_counts: BTreeMap<&'static str, usize>,
    /// `point` or `actuator`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit: Option<&'static str>,
}

/// What `--notify-command` is given when a run the monitor watches ends or stalls (the notifier adds `event` and
/// `host`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Notice {
    /// Units by their worst status.
    pub committed_by_status: BTreeMap<&'static str, usize>,
    /// The run's directory.
    pub dataset: String,
    /// Units committed.
    pub done: usize,
    /// Seconds since the last commit.
    pub last_commit_age_s: Option<f64>,
    /// `scan` or `calibrate`.
    pub recipe: Option<String>,
    /// The remaining time, s.
    pub remaining_s: Estimates<f64>,
    /// The committed rows' retries.
    pub retries: u64,
    /// `monitor`.
    pub source: &'static str,
    /// Units planned.
    pub total: Option<usize>,
}

impl RunState {
    /// The notification of this state.
    pub fn notice(&self) -> Notice {
        Notice {
            committed_by_status: self.status_counts.clone(),
            dataset: self.dir.clone(),
            done: self.points_done,
            last_commit_age_s: self.last_commit_age_s,
            recipe: self.recipe.clone(),
            remaining_s: self.remaining_s.clone(),
            retries: self.retries,
            source: "monitor",
            total: self.points_total,
        }
    }
}

/// The `/api/state` snapshot of the run in `dir` at `now` (fields documented in the crate's documentation).
pub fn snapshot(files: &RunFiles, dir: &Path, now: DateTime<Utc>) -> RunState {
    let now_s = now.timestamp_millis() as f64 / 1e3;
    let Some(manifest) = &files.manifest else {
        return RunState {
            dir: dir.display().to_string(),
            disk: None,
            elapsed_s: 0.0,
            finish_at: None,
            journal_issues: None,
            last_commit_age_s: None,
            last_seq: None,
            median_point_s: None,
            points_done: 0,
            points_total: None,
            problem: files.problem.clone(),
            re_measured: 0,
            recipe: None,
            remaining_s: Estimates { median: None, p90: None },
            retries: 0,
            stall_after_s: None,
            stalled: false,
            started_at: None,
            status: RunStatus::Waiting,
            status_counts: BTreeMap::new(),
            unit: None,
        };
    };
    let meta = &manifest.meta;
    let (units, total) = Units::of_config(&meta.config);
    let cells = unit_cells(units, files.all_rows());
    let done = cells.len();
    let total = total.max(done);
    let mut status_counts: BTreeMap<&'static str, usize> = BTreeMap::new();
    for (status, _) in cells.values() {
        *status_counts.entry(status.label()).or_default() += 1;
    }
    status_counts.insert(CellStatus::Pending.label(), total - done);
    let retries: u64 = files.all_rows().filter_map(|m| m.retries).map(u64::from).sum();
    let re_measured = files.all_rows().filter(|m| m.status == Some(Status::ReMeasured)).count();

    let created_s = unix_s(&manifest.created_at);
    let commit_s: Vec<f64> = files.journal.commits.iter().filter_map(|c| unix_s(&c.at)).collect();
    let durations: Vec<f64> = created_s
        .into_iter()
        .chain(commit_s.iter().copied())
        .collect::<Vec<_>>()
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| d.is_finite() && *d >= 0.0)
        .collect();
    let median_point_s = metaplate_dsp::stats::median(&mut durations.clone());
    let remaining = RemainingTime::estimate(&durations, total - done).map(|r| (r.median_s, r.p90_s));
    let last_s = commit_s.last().copied().or(created_s);
    let log = &files.log_tail;
    // The log is read now and the journal at the last poll: an end the journal does not show yet is not taken.
    let logged = logged_end(log).filter(|(_, logged_done)| logged_done.is_none_or(|n| n <= done)).map(|(end, _)| end);
    let status = if done >= total && total > 0 { Some(RunStatus::Finished) } else { logged };
    let end_s = if status == Some(RunStatus::Finished) { last_s } else { Some(now_s) };
    let elapsed_s = match (created_s, end_s) {
        (Some(a), Some(b)) => (b - a).max(0.0),
        _ => 0.0,
    };
    let last_commit_age_s = last_s.map(|t| (now_s - t).max(0.0));
    let stall_after_s = median_point_s.map_or(STALL_MIN_S, |m| (STALL_FACTOR * m).max(STALL_MIN_S));
    let stalled = status.is_none() && last_commit_age_s.is_some_and(|age| age > stall_after_s);
    let status = status.unwrap_or(if stalled { RunStatus::Stalled } else { RunStatus::Running });
    let bytes_per_unit = {
        let sizes: Vec<u64> = files.journal.commits.iter().map(|c| c.batch.size_bytes).collect();
        (!sizes.is_empty()).then(|| sizes.iter().sum::<u64>() as f64 / sizes.len() as f64)
    };
    let finish = |r: f64| if status == RunStatus::Finished { None } else { clock_time(now_s + r) };
    RunState {
        dir: dir.display().to_string(),
        disk: Some(Disk {
            free_bytes: files.free_bytes,
            need_bytes: bytes_per_unit.map(|b| (b * (total - done) as f64).ceil() as u64),
        }),
        elapsed_s,
        finish_at: Some(Estimates {
            median: remaining.and_then(|r| finish(r.0)),
            p90: remaining.and_then(|r| finish(r.1)),
        }),
        journal_issues: Some(files.journal.issues.iter().map(|i| format!("line {}: {}", i.line, i.reason)).collect()),
        last_commit_age_s,
        last_seq: files.journal.commits.last().map(|c| c.seq),
        median_point_s: Some(median_point_s),
        points_done: done,
        points_total: Some(total),
        problem: files.problem.clone(),
        re_measured,
        recipe: Some(meta.recipe.clone()),
        remaining_s: Estimates { median: remaining.map(|r| r.0), p90: remaining.map(|r| r.1) },
        retries,
        stall_after_s: Some(stall_after_s),
        stalled,
        started_at: Some(manifest.created_at.clone()),
        status,
        status_counts,
        unit: Some(units.name()),
    }
}

/// The event `/events` sends for a commit. Its unit is named by its kind: `point` (the grid index) for a scan,
/// `actuator` for a calibration; the other is absent.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CommitEvent {
    /// A calibration's actuator (`Some(None)`: the commit names none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub actuator: Option<Option<u32>>,
    /// When it was journaled (RFC 3339).
    pub at: String,
    /// The committed file.
    pub file: String,
    /// A scan's grid point (`Some(None)`: the commit names none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point: Option<Option<u32>>,
    /// Rows committed.
    pub rows: u64,
    /// The journal line's sequence number.
    pub seq: u64,
    /// The unit's lowest SNR, dB (while its file holds the dataset).
    pub snr_db: Option<f64>,
    /// The unit's worst status (while its file holds the dataset).
    pub status: Option<&'static str>,
}

/// The event `/events` sends for `commit`: its sequence number, time, unit (`point`: the grid index, or
/// `actuator`) and (while its file holds the dataset) the unit's status and lowest SNR.
pub fn commit_event(files: &RunFiles, commit: &JournalCommit) -> CommitEvent {
    let units = files.manifest.as_ref().map_or(Units::Points, |m| Units::of_config(&m.meta.config).0);
    let unit = commit.batch.keys.first().map(|&(point, actuator)| match units {
        Units::Points => point,
        Units::Actuators => u32::from(actuator),
    });
    let rows = files.rows.get(&commit.batch.file);
    let cell = rows.and_then(|rows| unit_cells(units, rows.iter()).into_values().next());
    CommitEvent {
        actuator: (units == Units::Actuators).then_some(unit),
        at: commit.at.clone(),
        file: commit.batch.file.clone(),
        point: (units == Units::Points).then_some(unit),
        rows: commit.batch.rows,
        seq: commit.seq,
        snr_db: cell.and_then(|c| c.1),
        status: cell.map(|c| c.0.label()),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn the_log_says_how_the_run_last_ended() {
        let started = "2026-01-01T00:00:00Z  INFO metaplate::run: scan started total=6 done=0\n";
        assert_eq!(logged_end(started), None);
        let finished = format!("{started}x  INFO metaplate::run: finished done=6\n");
        assert_eq!(logged_end(&finished), Some((RunStatus::Finished, Some(6))));
        let stopped = format!("{started}x  INFO metaplate::run: stopped on request done=2\n");
        assert_eq!(logged_end(&stopped), Some((RunStatus::Stopped, Some(2))));
        let failed =
            format!("{started}x ERROR metaplate::run: run failed error=the DAQ stopped answering; finished 2\n");
        assert_eq!(logged_end(&failed), Some((RunStatus::Failed, None)));
        let resumed = format!("{started}x  INFO metaplate::run: stopped on request done=2\n{started}");
        assert_eq!(logged_end(&resumed), None);
    }
}

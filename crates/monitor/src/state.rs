//! What the page and `/api/state` show, computed from what [`crate::follow`] read: progress, status counts, the
//! remaining-time estimates, the stall flag, disk space, the last point's spectrum and the log's tail.

use std::collections::BTreeMap;
use std::path::Path;

use chrono::{DateTime, SecondsFormat, Utc};
use metaplate_figures::CellStatus;
use metaplate_recipes::RemainingTime;
use metaplate_store::{IrMeta, IrRecord, JournalCommit, Status};
use serde_json::{Value, json};

use crate::cells::{cell_status, grid_cells, planned_points, rank};
use crate::follow::RunFiles;

/// A run whose last commit is older than this many median point times (and [`STALL_MIN_S`]) is flagged as stalled.
pub const STALL_FACTOR: f64 = 4.0;
/// The shortest time without a commit that counts as a stall, s: a mock-lab point takes a fraction of a second.
pub const STALL_MIN_S: f64 = 30.0;
/// What a run measures one unit at a time, as its recipe says: grid points (scan) or actuators (calibrate).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Units {
    Points,
    Actuators,
}

impl Units {
    /// The units of a run with configuration `config`, and how many it plans.
    fn of_config(config: &serde_json::Map<String, Value>) -> (Units, usize) {
        match config.get("actuator_sites_m").and_then(Value::as_array) {
            Some(sites) => (Units::Actuators, sites.len()),
            None => (Units::Points, planned_points(config).len()),
        }
    }

    fn name(self) -> &'static str {
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
fn unit_cells<'a>(units: Units, rows: impl Iterator<Item = &'a IrMeta>) -> BTreeMap<u32, (CellStatus, Option<f64>)> {
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
fn logged_end(log: &str) -> Option<(&'static str, Option<usize>)> {
    let line = log.lines().rev().find(|l| {
        l.contains("metaplate::run:")
            && (l.contains(" started") || l.contains(" finished") || l.contains("stopped") || l.contains("run failed"))
    })?;
    let done = line.split_whitespace().find_map(|w| w.strip_prefix("done=")).and_then(|n| n.parse().ok());
    // "run failed" first: its message (after it) may name any word.
    if line.contains("run failed") {
        Some(("failed", None))
    } else if line.contains(" started") {
        None
    } else if line.contains(" finished") {
        Some(("finished", done))
    } else {
        Some(("stopped", done))
    }
}

/// The `/api/state` snapshot of the run in `dir` at `now` (fields documented in the crate's documentation).
pub fn snapshot(files: &RunFiles, dir: &Path, now: DateTime<Utc>) -> Value {
    let now_s = now.timestamp_millis() as f64 / 1e3;
    let Some(manifest) = &files.manifest else {
        return json!({
            "dir": dir.display().to_string(), "status": "waiting", "recipe": null,
            "points_total": null, "points_done": 0, "status_counts": {}, "elapsed_s": 0.0,
            "remaining_s": {"median": null, "p90": null}, "last_commit_age_s": null, "stalled": false,
            "retries": 0, "re_measured": 0, "last_seq": null, "problem": files.problem,
        });
    };
    let meta = &manifest.meta;
    let (units, total) = Units::of_config(&meta.config);
    let cells = unit_cells(units, files.all_rows());
    let done = cells.len();
    let total = total.max(done);
    let mut status_counts: BTreeMap<&str, usize> = BTreeMap::new();
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
    let status = if done >= total && total > 0 { Some("finished") } else { logged };
    let end_s = if status == Some("finished") { last_s } else { Some(now_s) };
    let elapsed_s = match (created_s, end_s) {
        (Some(a), Some(b)) => (b - a).max(0.0),
        _ => 0.0,
    };
    let last_commit_age_s = last_s.map(|t| (now_s - t).max(0.0));
    let stall_after_s = median_point_s.map_or(STALL_MIN_S, |m| (STALL_FACTOR * m).max(STALL_MIN_S));
    let stalled = status.is_none() && last_commit_age_s.is_some_and(|age| age > stall_after_s);
    let status = status.unwrap_or(if stalled { "stalled" } else { "running" });
    let bytes_per_unit = {
        let sizes: Vec<u64> = files.journal.commits.iter().map(|c| c.batch.size_bytes).collect();
        (!sizes.is_empty()).then(|| sizes.iter().sum::<u64>() as f64 / sizes.len() as f64)
    };
    let finish = |r: f64| if status == "finished" { None } else { clock_time(now_s + r) };
    json!({
        "dir": dir.display().to_string(),
        "recipe": meta.recipe,
        "unit": units.name(),
        "status": status,
        "points_total": total,
        "points_done": done,
        "status_counts": status_counts,
        "started_at": manifest.created_at,
        "elapsed_s": elapsed_s,
        "median_point_s": median_point_s,
        "remaining_s": {"median": remaining.map(|r| r.0), "p90": remaining.map(|r| r.1)},
        "finish_at": {
            "median": remaining.and_then(|r| finish(r.0)),
            "p90": remaining.and_then(|r| finish(r.1)),
        },
        "last_commit_age_s": last_commit_age_s,
        "stall_after_s": stall_after_s,
        "stalled": stalled,
        "retries": retries,
        "re_measured": re_measured,
        "disk": {
            "free_bytes": files.free_bytes,
            "need_bytes": bytes_per_unit.map(|b| (b * (total - done) as f64).ceil() as u64),
        },
        "last_seq": files.journal.commits.last().map(|c| c.seq),
        "journal_issues": files.journal.issues.iter().map(|i| format!("line {}: {}", i.line, i.reason)).collect::<Vec<_>>(),
        "problem": files.problem,
    })
}

/// The event `/events` sends for `commit`: its sequence number, time, unit (`point`: the grid index, or
/// `actuator`) and (while its file holds the dataset) the unit's status and lowest SNR.
pub fn commit_event(files: &RunFiles, commit: &JournalCommit) -> Value {
    let units = files.manifest.as_ref().map_or(Units::Points, |m| Units::of_config(&m.meta.config).0);
    let unit = commit.batch.keys.first().map(|&(point, actuator)| match units {
        Units::Points => point,
        Units::Actuators => u32::from(actuator),
    });
    let rows = files.rows.get(&commit.batch.file);
    let cell = rows.and_then(|rows| unit_cells(units, rows.iter()).into_values().next());
    json!({
        "seq": commit.seq,
        "at": commit.at,
        "file": commit.batch.file,
        units.name(): unit,
        "rows": commit.batch.rows,
        "status": cell.map(|c| c.0.label()),
        "snr_db": cell.and_then(|c| c.1),
    })
}

/// The status and SNR maps of a scan as inline SVG (`None` for a calibration, which has no grid to show).
pub fn maps_svg(files: &RunFiles, width_px: usize, snr_scale_db: (f64, f64)) -> Option<(String, String)> {
    let meta = &files.manifest.as_ref()?.meta;
    if meta.config.contains_key("actuator_sites_m") {
        return None;
    }
    let (states, snr) = grid_cells(&meta.grid, &planned_points(&meta.config), files.all_rows());
    let (nx, ny) = (meta.grid.nx, meta.grid.ny);
    Some((
        metaplate_figures::status_map_svg(nx, ny, &states, width_px),
        metaplate_figures::snr_map_svg(nx, ny, &snr, snr_scale_db, width_px),
    ))
}

/// Log-spaced frequencies of the spectrum plot, Hz.
const SPECTRUM_BAND_HZ: (f64, f64) = (20.0, 2000.0);
/// Points per actuator of the spectrum plot.
const SPECTRUM_POINTS: usize = 240;

/// The magnitude spectra, dB (re 1), of `records` (one per actuator; a calibration's rows carry their `kind`) on log-spaced frequencies: the largest bin in
/// each frequency's interval, so that narrow resonances are not lost. `{"freq_hz": [...], "actuators": [{"actuator",
/// "db": [...]}]}`; a response that cannot be transformed (non-finite samples) is left out.
pub fn spectra(records: &[IrRecord]) -> Value {
    let Some(first) = records.first() else { return Value::Null };
    let fs = first.meta.sample_rate_hz;
    let hi = SPECTRUM_BAND_HZ.1.min(fs / 2.0);
    let ratio = (hi / SPECTRUM_BAND_HZ.0).max(1.0);
    let freq_hz: Vec<f64> =
        (0..=SPECTRUM_POINTS).map(|i| SPECTRUM_BAND_HZ.0 * ratio.powf(i as f64 / SPECTRUM_POINTS as f64)).collect();
    let mut actuators = Vec::new();
    for record in records {
        let x: Vec<f64> = record.ir.iter().map(|v| f64::from(*v)).collect();
        let n = x.len().max(2);
        let Ok(spectrum) = metaplate_dsp::fft::forward(&x, n) else { continue };
        let bin = |f: f64| ((f * n as f64 / fs).round() as usize).min(spectrum.len() - 1);
        let db: Vec<Option<f64>> = freq_hz
            .windows(2)
            .map(|w| {
                let (a, b) = (bin(w[0]), bin(w[1]).max(bin(w[0])));
                let peak = spectrum[a..=b].iter().map(|c| c.norm()).fold(0.0, f64::max);
                (peak > 0.0).then(|| 20.0 * peak.log10())
            })
            .collect();
        let kind = record.meta.kind.map(|k| k.as_str());
        actuators.push(json!({"actuator": record.meta.actuator, "kind": kind, "db": db}));
    }
    let centres: Vec<f64> = freq_hz.windows(2).map(|w| (w[0] * w[1]).sqrt()).collect();
    json!({"point": first.meta.point_index, "freq_hz": centres, "actuators": actuators})
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
        assert_eq!(logged_end(&finished), Some(("finished", Some(6))));
        let stopped = format!("{started}x  INFO metaplate::run: stopped on request done=2\n");
        assert_eq!(logged_end(&stopped), Some(("stopped", Some(2))));
        let failed =
            format!("{started}x ERROR metaplate::run: run failed error=the DAQ stopped answering; finished 2\n");
        assert_eq!(logged_end(&failed), Some(("failed", None)));
        let resumed = format!("{started}x  INFO metaplate::run: stopped on request done=2\n{started}");
        assert_eq!(logged_end(&resumed), None);
    }
}

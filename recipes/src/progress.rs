//! What an observer keeps of a run's events ([`RunProgress`]: counts, unit times, retries, statuses) and what it
//! says of them: one JSON line per event ([`EventLine`], what `calibrate --json` and `scan --json` print) and the
//! summary a notification carries ([`RunSummary`]).
//!
//! Every line's fields are declared in alphabetical order: the lines were first printed from `serde_json` objects,
//! which sort their keys, and they stay byte-identical.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use crate::events::Event;
use crate::remaining::RemainingTime;

/// A remaining time as the lines print it (`{"median": s, "p90": s}`), s.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RemainingLine {
    /// Remaining units times the median unit time, s.
    pub median: f64,
    /// Remaining units times the 90th-percentile unit time, s.
    pub p90: f64,
}

impl From<RemainingTime> for RemainingLine {
    fn from(r: RemainingTime) -> Self {
        Self { median: r.median_s, p90: r.p90_s }
    }
}

/// One `--json` progress line: an [`Event`] with the run's name and unit kind (and, for a commit, the rate, the
/// remaining time and the wall clock), or the `failed` line of a run that ended in an error.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum EventLine {
    /// `started`.
    Started {
        /// The dataset's configuration hash.
        config_hash: String,
        /// The dataset's directory.
        dataset: String,
        /// Units committed before this run.
        done: usize,
        /// `"started"`.
        event: &'static str,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// Whether an earlier run was continued (false: a new dataset, even with `--resume`).
        resumed: bool,
        /// Units in the run.
        total: usize,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `committed`.
    Committed {
        /// Wall clock, RFC 3339 with milliseconds, UTC.
        at: String,
        /// Rig clock since the run started, s.
        clock_s: f64,
        /// Units committed so far.
        done: usize,
        /// Hours left on the rig's clock at this run's rate.
        eta_h: Option<f64>,
        /// `"committed"`.
        event: &'static str,
        /// Grid column, when the unit has a position.
        #[serde(skip_serializing_if = "Option::is_none")]
        ix: Option<u32>,
        /// Grid row, when the unit has a position.
        #[serde(skip_serializing_if = "Option::is_none")]
        iy: Option<u32>,
        /// Units per hour of the rig's clock, this run.
        rate_per_hour: Option<f64>,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// The remaining time, s.
        remaining_s: Option<RemainingLine>,
        /// Retries and deferrals so far.
        retries: usize,
        /// Median SNR of the unit's rows, dB.
        snr_db: Option<f64>,
        /// The unit's worst row's status.
        status: String,
        /// Units in the run.
        total: usize,
        /// Grid point or actuator.
        unit: usize,
        /// `points` or `actuators`.
        unit_kind: &'static str,
        /// Wall seconds since this run started.
        wall_s: f64,
        /// x, m, when the unit has a position.
        #[serde(skip_serializing_if = "Option::is_none")]
        x_m: Option<f64>,
        /// y, m, when the unit has a position.
        #[serde(skip_serializing_if = "Option::is_none")]
        y_m: Option<f64>,
    },
    /// `phase`.
    Phase {
        /// The actuators driven (while playing).
        actuators: Vec<usize>,
        /// `"phase"`.
        event: &'static str,
        /// The step's word.
        phase: &'static str,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// Grid point or actuator.
        unit: usize,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `retry`.
    Retry {
        /// The attempt about to be made.
        attempt: u32,
        /// `"retry"`.
        event: &'static str,
        /// Why.
        reason: String,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// Grid point or actuator.
        unit: usize,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `recovered` and `paused`.
    Note {
        /// What happened.
        detail: String,
        /// `"recovered"` or `"paused"`.
        event: &'static str,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `reference_checked`.
    ReferenceChecked {
        /// Actuator re-measured.
        actuator: usize,
        /// Relative error against the committed response, dB.
        deviation_db: f64,
        /// `"reference_checked"`.
        event: &'static str,
        /// The warning limit, dB.
        limit_db: f64,
        /// Grid point of the reference.
        point: usize,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `stopped` and `finished`.
    Ended {
        /// Units committed.
        done: usize,
        /// `"stopped"` or `"finished"`.
        event: &'static str,
        /// `scan` or `calibrate`.
        recipe: &'static str,
        /// `points` or `actuators`.
        unit_kind: &'static str,
    },
    /// `failed`: the run ended in an error.
    Failed {
        /// The dataset's directory.
        dataset: String,
        /// The error, its causes after colons.
        error: String,
        /// `"failed"`.
        event: &'static str,
        /// `scan` or `calibrate`.
        recipe: &'static str,
    },
}

impl EventLine {
    /// The `failed` line of `recipe` writing into `dataset`.
    pub fn failed(recipe: &'static str, dataset: &std::path::Path, error: String) -> Self {
        EventLine::Failed { dataset: dataset.display().to_string(), error, event: "failed", recipe }
    }
}

/// What a notification says of a run so far (`--notify-command`; the notifier adds `event` and `host`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    /// Units committed by this run, by their worst row's status.
    pub committed_by_status: BTreeMap<String, usize>,
    /// The dataset's directory, once started.
    pub dataset: Option<String>,
    /// Units committed so far.
    pub done: usize,
    /// `scan` or `calibrate`.
    pub recipe: &'static str,
    /// The remaining time, s.
    pub remaining_s: Option<RemainingLine>,
    /// Retries and deferrals so far.
    pub retries: usize,
    /// Units in the run.
    pub total: usize,
    /// `points` or `actuators`.
    pub unit_kind: &'static str,
    /// Wall seconds since this run started.
    pub wall_s: f64,
}

/// A run's progress as its events tell it: feed every event to [`RunProgress::track`] first, then ask.
#[derive(Debug, Clone)]
pub struct RunProgress {
    recipe: &'static str,
    unit_kind: &'static str,
    /// When this run started (wall clock).
    started: Instant,
    /// Units committed before this run (resume), for the rate.
    done_at_start: usize,
    /// Rig-clock duration of each unit this run committed, s.
    durations_s: Vec<f64>,
    /// Rig clock at the last commit (or the start), s.
    last_commit_clock_s: f64,
    retries: usize,
    total: usize,
    done: usize,
    dataset: Option<PathBuf>,
    status_counts: BTreeMap<String, usize>,
}

impl RunProgress {
    /// The progress of a run of `recipe` (`scan`, `calibrate`) counting `unit_kind`s (`points`, `actuators`),
    /// starting now.
    pub fn new(recipe: &'static str, unit_kind: &'static str) -> Self {
        Self {
            recipe,
            unit_kind,
            started: Instant::now(),
            done_at_start: 0,
            durations_s: Vec::new(),
            last_commit_clock_s: 0.0,
            retries: 0,
            total: 0,
            done: 0,
            dataset: None,
            status_counts: BTreeMap::new(),
        }
    }

    /// Keeps what the counts need of `event`.
    pub fn track(&mut self, event: &Event) {
        match event {
            Event::Started { total, done, dataset, .. } => {
                (self.total, self.done, self.done_at_start) = (*total, *done, *done);
                self.dataset = Some(dataset.clone());
            }
            Event::Committed { done, total, clock_s, status, .. } => {
                self.durations_s.push(clock_s - self.last_commit_clock_s);
                (self.last_commit_clock_s, self.done, self.total) = (*clock_s, *done, *total);
                *self.status_counts.entry(status.clone()).or_default() += 1;
            }
            Event::Retry { .. } => self.retries += 1,
            _ => {}
        }
    }

    /// `scan` or `calibrate`.
    pub fn recipe(&self) -> &'static str {
        self.recipe
    }

    /// `points` or `actuators`.
    pub fn unit_kind(&self) -> &'static str {
        self.unit_kind
    }

    /// Retries and deferrals so far.
    pub fn retries(&self) -> usize {
        self.retries
    }

    /// Rate (units per hour) and ETA (hours) on the rig's clock, once this run has committed something.
    pub fn rate_and_eta(&self, done: usize, total: usize, clock_s: f64) -> Option<(f64, f64)> {
        let now = done.checked_sub(self.done_at_start).filter(|n| *n > 0)?;
        if !(clock_s.is_finite() && clock_s > 0.0) {
            return None;
        }
        let per_hour = now as f64 / clock_s * 3600.0;
        Some((per_hour, total.saturating_sub(done) as f64 / per_hour))
    }

    /// The remaining time on the rig's clock, from the units this run committed.
    pub fn remaining(&self) -> Option<RemainingTime> {
        RemainingTime::estimate(&self.durations_s, self.total.saturating_sub(self.done))
    }

    /// Wall-clock seconds per rig-clock second so far (1 on real instruments, less on the fast-forward mock lab),
    /// so that a remaining rig time becomes a time of day.
    pub fn wall_per_rig_s(&self) -> Option<f64> {
        let rig_s = self.last_commit_clock_s;
        (rig_s > 0.0).then(|| self.started.elapsed().as_secs_f64() / rig_s)
    }

    /// The remaining time as a display says it: `left 2.50 h (p90 3.10 h), ends ~04:10 UTC` (the time of day from this
    /// run's wall time per rig time); `None` before this run's first commit.
    pub fn remaining_text(&self) -> Option<String> {
        let r = self.remaining()?;
        let ends = self.wall_per_rig_s().map_or_else(String::new, |ratio| {
            let at = chrono::Utc::now() + chrono::Duration::milliseconds((r.median_s * ratio * 1e3) as i64);
            format!(", ends ~{} UTC", at.format("%H:%M"))
        });
        Some(format!("left {} (p90 {}){ends}", duration_text(r.median_s), duration_text(r.p90_s)))
    }

    /// What a notification says of the run so far.
    pub fn summary(&self) -> RunSummary {
        RunSummary {
            committed_by_status: self.status_counts.clone(),
            dataset: self.dataset.as_ref().map(|d| d.display().to_string()),
            done: self.done,
            recipe: self.recipe,
            remaining_s: self.remaining().map(Into::into),
            retries: self.retries,
            total: self.total,
            unit_kind: self.unit_kind,
            wall_s: self.started.elapsed().as_secs_f64(),
        }
    }

    /// The `--json` line of `event` (tracked already).
    pub fn line(&self, event: &Event) -> EventLine {
        let (recipe, unit_kind) = (self.recipe, self.unit_kind);
        match event {
            Event::Started { total, done, dataset, config_hash, resumed } => EventLine::Started {
                config_hash: config_hash.clone(),
                dataset: dataset.display().to_string(),
                done: *done,
                event: "started",
                recipe,
                resumed: *resumed,
                total: *total,
                unit_kind,
            },
            Event::Committed { unit, done, total, snr_db, status, clock_s, position } => {
                let (rate_per_hour, eta_h) = self.rate_and_eta(*done, *total, *clock_s).unzip();
                EventLine::Committed {
                    at: chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, true),
                    clock_s: *clock_s,
                    done: *done,
                    eta_h,
                    event: "committed",
                    ix: position.map(|p| p.ix),
                    iy: position.map(|p| p.iy),
                    rate_per_hour,
                    recipe,
                    remaining_s: self.remaining().map(Into::into),
                    retries: self.retries,
                    snr_db: *snr_db,
                    status: status.clone(),
                    total: *total,
                    unit: *unit,
                    unit_kind,
                    wall_s: self.started.elapsed().as_secs_f64(),
                    x_m: position.map(|p| p.x_m),
                    y_m: position.map(|p| p.y_m),
                }
            }
            Event::Phase { unit, phase, actuators } => EventLine::Phase {
                actuators: actuators.clone(),
                event: "phase",
                phase: phase.as_str(),
                recipe,
                unit: *unit,
                unit_kind,
            },
            Event::Retry { unit, attempt, reason } => EventLine::Retry {
                attempt: *attempt,
                event: "retry",
                reason: reason.clone(),
                recipe,
                unit: *unit,
                unit_kind,
            },
            Event::Recovered { detail } => {
                EventLine::Note { detail: detail.clone(), event: "recovered", recipe, unit_kind }
            }
            Event::Paused { detail } => EventLine::Note { detail: detail.clone(), event: "paused", recipe, unit_kind },
            Event::ReferenceChecked { point, actuator, deviation_db, limit_db } => EventLine::ReferenceChecked {
                actuator: *actuator,
                deviation_db: *deviation_db,
                event: "reference_checked",
                limit_db: *limit_db,
                point: *point,
                recipe,
                unit_kind,
            },
            Event::Stopped { done } => EventLine::Ended { done: *done, event: "stopped", recipe, unit_kind },
            Event::Finished { done } => EventLine::Ended { done: *done, event: "finished", recipe, unit_kind },
        }
    }
}

/// A duration, s, in the unit a reader expects: seconds under 2 minutes, minutes under 2 hours, then hours (the one
/// duration formatter of displays: a run's remaining time, the report's measurement times).
pub fn duration_text(seconds: f64) -> String {
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("{:.1} min", seconds / 60.0)
    } else {
        format!("{:.2} h", seconds / 3600.0)
    }
}

/// The command line that continues this run: the original arguments with `--resume` added (once).
pub fn resume_command() -> String {
    let mut args: Vec<String> = std::env::args().collect();
    if !args.iter().any(|a| a == "--resume") {
        args.push("--resume".into());
    }
    args.iter().map(|a| shell_quote(a)).collect::<Vec<_>>().join(" ")
}

/// `text` quoted for a POSIX shell when it needs it.
fn shell_quote(text: &str) -> String {
    let plain = !text.is_empty() && text.bytes().all(|b| b.is_ascii_alphanumeric() || b"-_./=:,+@%".contains(&b));
    if plain { text.to_string() } else { format!("'{}'", text.replace('\'', r"'\''")) }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;
    use crate::events::UnitPosition;

    #[test]
    fn durations_take_the_unit_a_reader_expects() {
        assert_eq!(duration_text(59.6), "60 s");
        assert_eq!(duration_text(600.0), "10.0 min");
        assert_eq!(duration_text(9000.0), "2.50 h");
    }

    /// Keys in the order a line prints them.
    fn keys(line: &EventLine) -> Vec<String> {
        let text = serde_json::to_string(line).unwrap();
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        let sorted: Vec<String> = value.as_object().unwrap().keys().cloned().collect();
        let mut printed: Vec<(usize, String)> =
            sorted.iter().map(|k| (text.find(&format!("\"{k}\":")).unwrap(), k.clone())).collect();
        printed.sort();
        printed.into_iter().map(|(_, k)| k).collect()
    }

    #[test]
    fn every_line_prints_its_keys_in_alphabetical_order() {
        let mut progress = RunProgress::new("scan", "points");
        let position = UnitPosition { ix: 1, iy: 2, x_m: 0.1, y_m: 0.2 };
        let events = [
            Event::Started { total: 4, done: 1, dataset: "d".into(), config_hash: "h".into(), resumed: true },
            Event::Committed {
                unit: 3,
                done: 2,
                total: 4,
                snr_db: Some(30.0),
                status: "valid".into(),
                clock_s: 10.0,
                position: Some(position),
            },
            Event::Phase { unit: 3, phase: crate::events::Phase::Playing, actuators: vec![0] },
            Event::Retry { unit: 3, attempt: 1, reason: "r".into() },
            Event::Paused { detail: "p".into() },
            Event::ReferenceChecked { point: 0, actuator: 1, deviation_db: -30.0, limit_db: -20.0 },
            Event::Finished { done: 4 },
        ];
        for event in &events {
            progress.track(event);
            let line = progress.line(event);
            let printed = keys(&line);
            let mut sorted = printed.clone();
            sorted.sort();
            assert_eq!(printed, sorted, "{line:?}");
        }
        let failed = keys(&EventLine::failed("scan", std::path::Path::new("d"), "e".into()));
        assert_eq!(failed, ["dataset", "error", "event", "recipe"]);
        assert_eq!(progress.summary().committed_by_status.get("valid"), Some(&1));
        assert_eq!(progress.retries(), 1);
    }

    #[test]
    fn a_commit_without_a_position_has_no_position_keys_and_rates_start_with_this_run() {
        let mut progress = RunProgress::new("calibrate", "actuators");
        progress.track(&Event::Started {
            total: 8,
            done: 2,
            dataset: "d".into(),
            config_hash: "h".into(),
            resumed: true,
        });
        assert_eq!(progress.rate_and_eta(2, 8, 10.0), None, "nothing committed by this run yet");
        let commit = Event::Committed {
            unit: 2,
            done: 3,
            total: 8,
            snr_db: None,
            status: "valid".into(),
            clock_s: 100.0,
            position: None,
        };
        progress.track(&commit);
        let text = serde_json::to_string(&progress.line(&commit)).unwrap();
        assert!(!text.contains("\"ix\"") && !text.contains("\"x_m\"") && text.contains("\"snr_db\":null"), "{text}");
        let (rate, eta) = progress.rate_and_eta(3, 8, 100.0).unwrap();
        assert_eq!((rate, eta), (36.0, 5.0 / 36.0));
    }
}

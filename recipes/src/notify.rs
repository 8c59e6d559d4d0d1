//! `--notify-command`: a user's command (mail, a chat webhook, a desktop notification) run with a JSON summary on
//! its standard input when a run finishes, stops, fails or stalls, at most once per event; and the watch that
//! notices a stall (no commit for much longer than a unit usually takes); [`RunNotifications`] ties them to a run's
//! events.

use std::collections::BTreeSet;
use std::io::Write;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use metaplate_dsp::stats::median;
use serde::Serialize;
use serde_json::{Value, json};

use crate::events::Event;
use crate::progress::RunProgress;

/// How long a notification command may run before it is killed, s: a hung mail server must not hold the run.
const COMMAND_TIMEOUT_S: u64 = 30;

/// A run is stalled after this many times its median unit time without a commit...
const STALL_FACTOR: f64 = 3.0;
/// ...and never sooner than this, s (a paper-protocol point takes about 125 s).
const MIN_STALL_S: f64 = 120.0;
/// Before the first commit (setup, the first aim), s.
const FIRST_COMMIT_STALL_S: f64 = 900.0;

/// Runs the user's command once per event key.
pub struct Notifier {
    command: String,
    sent: Mutex<BTreeSet<String>>,
    timeout: Duration,
}

impl Notifier {
    /// A notifier running `command` with `sh -c`.
    pub fn new(command: String) -> Arc<Self> {
        Arc::new(Self { command, sent: Mutex::new(BTreeSet::new()), timeout: Duration::from_secs(COMMAND_TIMEOUT_S) })
    }

    /// Runs the command with `summary` (an object; `event` is set to `event`, `host` to this machine's name) as
    /// one JSON line on its standard input, its keys sorted, unless `key` was notified already. Waits for it at
    /// most [`COMMAND_TIMEOUT_S`], then kills it. A command that cannot start, fails or times out is reported on
    /// stderr: a notification never fails the run.
    pub fn notify(&self, key: &str, event: &str, summary: &impl Serialize) {
        let mut summary = serde_json::to_value(summary).unwrap_or(Value::Null);
        {
            let Ok(mut sent) = self.sent.lock() else { return };
            if !sent.insert(key.to_owned()) {
                return;
            }
        }
        if let Value::Object(map) = &mut summary {
            map.insert("event".into(), json!(event));
            if let Some(host) = hostname() {
                map.insert("host".into(), json!(host));
            }
        }
        if let Err(why) = self.run(&summary) {
            eprintln!("notify-command ({event}): {why}");
        }
    }

    fn run(&self, summary: &Value) -> Result<(), String> {
        let mut command = Command::new("sh");
        command.arg("-c").arg(&self.command).stdin(Stdio::piped()).stdout(Stdio::null());
        // Its own process group, so that a timeout kills what the shell started too (`curl`, `mail`), not only sh.
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut command, 0);
        let mut child = command.spawn().map_err(|e| format!("cannot start `sh -c {}`: {e}", self.command))?;
        if let Some(mut stdin) = child.stdin.take() {
            // A command that does not read its input is fine: a broken pipe here is not an error.
            let _ = writeln!(stdin, "{summary}");
        }
        let deadline = Instant::now() + self.timeout;
        loop {
            match child.try_wait() {
                Ok(Some(status)) if status.success() => return Ok(()),
                Ok(Some(status)) => return Err(format!("the command exited with {status}")),
                Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(50)),
                Ok(None) => {
                    // The group's id is the shell's pid (process_group(0) above); `kill` the command kills it all
                    // without unsafe code of ours.
                    #[cfg(unix)]
                    let _ = Command::new("kill")
                        .args(["-KILL", "--", &format!("-{}", child.id())])
                        .stderr(Stdio::null())
                        .status();
                    let _ = child.kill();
                    let _ = child.wait();
                    return Err(format!("the command ran longer than {:?} and was killed", self.timeout));
                }
                Err(e) => return Err(e.to_string()),
            }
        }
    }
}

/// This machine's name, for the notification (Linux; `None` elsewhere).
fn hostname() -> Option<String> {
    std::fs::read_to_string("/proc/sys/kernel/hostname").ok().map(|h| h.trim().to_owned()).filter(|h| !h.is_empty())
}

/// What the stall watch knows of the run.
struct WatchState {
    last_commit: Instant,
    commits: usize,
    /// Wall seconds between consecutive commits.
    unit_wall_s: Vec<f64>,
    /// The summary a stall notification carries.
    summary: Value,
}

/// A thread that notifies `stalled` once per commit gap that exceeds the stall limit: `stall_after_s` when given,
/// else [`STALL_FACTOR`] times the median wall time between commits, at least [`MIN_STALL_S`]
/// ([`FIRST_COMMIT_STALL_S`] before the first commit). Stops when dropped.
pub struct StallWatch {
    state: Arc<Mutex<WatchState>>,
    stop: Arc<AtomicBool>,
}

impl StallWatch {
    /// Starts the watch.
    pub fn start(notifier: Arc<Notifier>, stall_after_s: Option<f64>, summary: &impl Serialize) -> Self {
        let summary = serde_json::to_value(summary).unwrap_or(Value::Null);
        let state = Arc::new(Mutex::new(WatchState {
            last_commit: Instant::now(),
            commits: 0,
            unit_wall_s: Vec::new(),
            summary,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (watched, stopped) = (state.clone(), stop.clone());
        let poll = Duration::from_secs_f64(stall_after_s.map_or(1.0, |s| (s / 2.0).clamp(0.01, 1.0)));
        std::thread::spawn(move || {
            while !stopped.load(Ordering::Acquire) {
                std::thread::sleep(poll);
                let Ok(state) = watched.lock() else { return };
                let limit_s = stall_after_s.unwrap_or_else(|| match median(&mut state.unit_wall_s.clone()) {
                    Some(m) => (STALL_FACTOR * m).max(MIN_STALL_S),
                    None => FIRST_COMMIT_STALL_S,
                });
                let age_s = state.last_commit.elapsed().as_secs_f64();
                if age_s > limit_s && !stopped.load(Ordering::Acquire) {
                    let mut summary = state.summary.clone();
                    summary["last_commit_age_s"] = json!(age_s);
                    summary["stall_limit_s"] = json!(limit_s);
                    let key = format!("stalled after commit {}", state.commits);
                    drop(state);
                    notifier.notify(&key, "stalled", &summary);
                }
            }
        });
        Self { state, stop }
    }

    /// A unit was committed: the gap restarts; `summary` is what a later stall notification says.
    pub fn committed(&self, summary: &impl Serialize) {
        let summary = serde_json::to_value(summary).unwrap_or(Value::Null);
        if let Ok(mut state) = self.state.lock() {
            let gap_s = state.last_commit.elapsed().as_secs_f64();
            if state.commits > 0 {
                state.unit_wall_s.push(gap_s);
            }
            state.last_commit = Instant::now();
            state.commits += 1;
            state.summary = summary;
        }
    }
}

impl Drop for StallWatch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
    }
}

/// A run's notifications: the stall watch starts with the run and hears of every commit; the end (finished,
/// stopped) is notified once, with the run's [`RunProgress::summary`].
pub struct RunNotifications {
    notifier: Arc<Notifier>,
    stall_after_s: Option<f64>,
    watch: Option<StallWatch>,
}

impl RunNotifications {
    /// Notifications through `command` (`sh -c`), stalls after `stall_after_s` (default: see [`StallWatch`]).
    pub fn new(command: String, stall_after_s: Option<f64>) -> Self {
        Self { notifier: Notifier::new(command), stall_after_s, watch: None }
    }

    /// Hears `event`, after `progress` tracked it.
    pub fn event(&mut self, event: &Event, progress: &RunProgress) {
        match event {
            Event::Started { .. } => {
                let notifier = Arc::clone(&self.notifier);
                self.watch = Some(StallWatch::start(notifier, self.stall_after_s, &progress.summary()));
            }
            Event::Committed { .. } => {
                if let Some(watch) = &self.watch {
                    watch.committed(&progress.summary());
                }
            }
            Event::Finished { .. } | Event::Stopped { .. } => {
                self.watch = None;
                let name = if matches!(event, Event::Finished { .. }) { "finished" } else { "stopped" };
                self.notifier.notify(name, name, &progress.summary());
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    fn lines(path: &std::path::Path) -> Vec<Value> {
        std::fs::read_to_string(path).unwrap_or_default().lines().map(|l| serde_json::from_str(l).unwrap()).collect()
    }

    #[test]
    fn each_event_key_is_notified_once_with_the_summary_on_stdin() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("notes");
        let notifier = Notifier::new(format!("cat >> '{}'", file.display()));
        notifier.notify("finished", "finished", &json!({"done": 3}));
        notifier.notify("finished", "finished", &json!({"done": 4}));
        let got = lines(&file);
        assert_eq!(got.len(), 1, "{got:?}");
        assert_eq!((got[0]["event"].as_str(), got[0]["done"].as_u64()), (Some("finished"), Some(3)));
    }

    #[test]
    fn a_failing_or_hanging_command_does_not_fail_the_caller() {
        let notifier = Notifier::new("exit 7".into());
        assert!(notifier.run(&json!({})).unwrap_err().contains("exit"));
        let notifier = Notifier::new("/nonexistent/command/xyz".into());
        assert!(notifier.run(&json!({})).is_err());
        let hanging = Notifier {
            command: "sleep 30".into(),
            sent: Mutex::new(BTreeSet::new()),
            timeout: Duration::from_millis(200),
        };
        let started = Instant::now();
        assert!(hanging.run(&json!({})).unwrap_err().contains("killed"));
        assert!(started.elapsed() < Duration::from_secs(10), "killed at the timeout, not waited for");
    }

    #[test]
    fn a_stall_is_notified_once_per_gap() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("notes");
        let notifier = Notifier::new(format!("cat >> '{}'", file.display()));
        // Waits (up to 20 s, for a loaded machine) until the file holds `n` notifications.
        let wait_for = |n: usize| {
            let deadline = Instant::now() + Duration::from_secs(20);
            while lines(&file).len() < n && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(20));
            }
            lines(&file)
        };
        let watch = StallWatch::start(notifier, Some(0.05), &json!({"recipe": "scan"}));
        assert_eq!(wait_for(1).len(), 1, "the stall before the first commit");
        watch.committed(&json!({"recipe": "scan", "done": 1}));
        let got = wait_for(2);
        // The gap goes on: polls keep seeing it, and it is still notified once.
        std::thread::sleep(Duration::from_millis(300));
        drop(watch);
        let got_later = lines(&file);
        assert_eq!(got_later.len(), 2, "{got_later:?}");
        assert!(got.iter().all(|n| n["event"] == "stalled" && n["last_commit_age_s"].as_f64().unwrap() > 0.05));
        assert_eq!(got[1]["done"].as_u64(), Some(1));
    }
}

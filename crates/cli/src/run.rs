//! What `metaplate calibrate` and `metaplate scan` share: their common options, the log file in the run directory,
//! progress (a bar, or `--json` events on stdout), Ctrl-C, and how a run ends: its exit code ([`EXIT_CODES_HELP`])
//! and, for a run that stops early, the resume command.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;
use metaplate_recipes::{Event, Observer, Output, RecipeError, RemainingTime, RunControl};
use metaplate_store::{MANIFEST_FILE, SceneId, StoreError};
use serde_json::{Value, json};

use crate::notify::{Notifier, StallWatch};
use crate::progress;

/// Exit code of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: i32 = 130;

/// Exit code of a run that finished but committed flagged rows (status failed, dropout or overrange): the dataset
/// is whole, and some of it needs a look. Not 2, which is a usage error (clap's).
pub const EXIT_FLAGGED: i32 = 3;

/// The exit codes of `calibrate` and `scan`, for their `--help`.
pub const EXIT_CODES_HELP: &str = "Exit codes: 0 finished, every row valid or re-measured; 3 finished with flagged \
rows (failed, dropout or overrange; the summary says how many); 130 stopped by Ctrl-C (resume with --resume); 1 \
failed (the message says why); 2 bad arguments.";

/// Ends a run that finished: exits with [`EXIT_FLAGGED`] when it committed `flagged` flagged rows, saying so.
pub fn exit_if_flagged(flagged: usize, unit: &str) {
    if flagged > 0 {
        eprintln!("finished with {flagged} flagged {unit} (exit code {EXIT_FLAGGED})");
        std::process::exit(EXIT_FLAGGED);
    }
}

/// Where the instruments come from: exactly one of `--scene` and `--hardware`.
#[derive(Args, Debug, Clone)]
#[group(required = true, multiple = false)]
pub struct Source {
    /// Run on the mock lab of this scene: a built-in name (`metaplate scene list`) or a scene file. The mock lab
    /// runs the real drivers on a virtual clock, so hours of measurement take minutes.
    #[arg(long)]
    pub scene: Option<String>,
    /// Run on the real instruments named in this hardware file (format: `cli/hardware.example.toml`).
    #[arg(long)]
    pub hardware: Option<PathBuf>,
}

/// Options every measurement run takes.
#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    #[command(flatten)]
    pub source: Source,
    /// Dataset directory to write. It must be empty or absent, unless --resume.
    #[arg(long)]
    pub out: PathBuf,
    /// Continue the run already in --out after the last committed unit (after Ctrl-C, a crash or a power cut).
    /// The configuration must be the same as the first run's; committed files are verified and a corrupt one is
    /// quarantined and measured again.
    #[arg(long)]
    pub resume: bool,
    /// With --resume: continue even though the configuration differs from the dataset's (the differences are
    /// still reported, and journaled).
    #[arg(long, requires = "resume")]
    pub force: bool,
    /// Seed of every random choice (beam nudges; in the mock lab also noise, speckle and dropouts). Default: the
    /// scene's seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Print one JSON object per progress event on stdout (`{"event": "committed", ...}`), for unattended runs;
    /// the last one is `finished` or `stopped`.
    #[arg(long)]
    pub json: bool,
    /// Mock lab only: where the plate's Green's functions are cached.
    #[command(flatten)]
    pub cache: crate::cache::CacheArgs,
    /// Run this shell command (`sh -c CMD`) with a JSON summary on its standard input when the run finishes,
    /// stops, fails or stalls, once per event (mail, a chat webhook, a desktop notification: see the README).
    #[arg(long, value_name = "CMD")]
    pub notify_command: Option<String>,
    /// With --notify-command: the run is stalled after this many seconds without a commit (default: 3 x the
    /// median time between commits so far, at least 120 s; 900 s before the first commit).
    #[arg(long, requires = "notify_command", value_parser = positive_seconds)]
    pub stall_after_s: Option<f64>,
    /// The report `metaplate check --report FILE` wrote before this run: its verdict, when it ran, the failed checks
    /// and whether it checked this rig and wiring are recorded in the dataset (a resume keeps the first run's).
    #[arg(long, value_name = "FILE")]
    pub preflight: Option<PathBuf>,
}

/// A finite number of seconds above zero.
fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s.is_finite() && s > 0.0 => Ok(s),
        _ => Err(format!("`{text}` is not a positive number of seconds")),
    }
}

impl RunArgs {
    /// The recipe's output for `scene`, with the pre-flight report of `--preflight` if given.
    ///
    /// # Errors
    /// The report cannot be read or is not a pre-flight report.
    pub fn output(&self, scene: SceneId) -> anyhow::Result<Output> {
        Ok(Output {
            dir: self.out.clone(),
            scene,
            software_version: env!("CARGO_PKG_VERSION").to_string(),
            resume: self.resume,
            force: self.force,
            preflight: self.preflight.as_deref().map(read_preflight).transpose()?,
        })
    }
}

/// Reads a report `metaplate check --report` wrote; says so when its verdict is not a pass (the run still starts:
/// the dataset records the verdict).
fn read_preflight(path: &Path) -> anyhow::Result<serde_json::Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading the pre-flight report {}", path.display()))?;
    let report: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a pre-flight report (not JSON)", path.display()))?;
    match report["verdict"].as_str() {
        Some("pass") => {}
        Some(verdict) => {
            eprintln!("warning: the pre-flight in {} says `{verdict}`; the dataset records it", path.display());
        }
        None => anyhow::bail!("{} is not a pre-flight report (no `verdict`)", path.display()),
    }
    Ok(report)
}

/// A log file that is created only once the dataset exists: the store refuses to create a dataset in a directory
/// that holds anything, so lines logged before that are kept in memory and written out when `manifest.json`
/// appears (and dropped if the run fails before).
struct DeferredLog {
    path: PathBuf,
    manifest: PathBuf,
    pending: Vec<u8>,
    file: Option<File>,
}

impl Write for DeferredLog {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.file.is_none() {
            if !self.manifest.exists() {
                self.pending.extend_from_slice(buf);
                return Ok(buf.len());
            }
            let mut file = OpenOptions::new().create(true).append(true).open(&self.path)?;
            file.write_all(&self.pending)?;
            self.pending.clear();
            self.file = Some(file);
        }
        match &mut self.file {
            Some(file) => file.write(buf),
            None => Ok(buf.len()),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.as_mut().map_or(Ok(()), Write::flush)
    }
}

/// Sends `tracing` events (info and above, no colour codes) to `DIR/<recipe>.log`, appended on resume.
///
/// # Errors
/// When a global subscriber is already installed.
pub fn init_log(dir: &Path, recipe: &str) -> anyhow::Result<()> {
    let log = DeferredLog {
        path: dir.join(format!("{recipe}.log")),
        manifest: dir.join(MANIFEST_FILE),
        pending: Vec::new(),
        file: None,
    };
    tracing_subscriber::fmt()
        .with_writer(Mutex::new(log))
        .with_ansi(false)
        .with_max_level(tracing::Level::INFO)
        .try_init()
        .map_err(|e| anyhow::anyhow!("cannot set up the log: {e}"))
}

/// Installs the Ctrl-C handler: the first press asks `control` to stop after the current point, the second to
/// abandon it. Messages go to stderr, above `bar` when there is one.
///
/// # Errors
/// When a handler is already installed.
pub fn handle_ctrl_c(control: &RunControl, bar: Option<ProgressBar>) -> anyhow::Result<()> {
    let control = control.clone();
    ctrlc::set_handler(move || {
        let message = match control.request_stop() {
            1 => "stopping after the current point (Ctrl-C again to abandon it)",
            _ => "abandoning the current point; nothing of it is committed",
        };
        match &bar {
            Some(bar) => bar.suspend(|| eprintln!("{message}")),
            None => eprintln!("{message}"),
        }
    })
    .context("cannot install the Ctrl-C handler")
}

/// How progress is shown.
enum Display {
    /// An indicatif bar on stderr (hidden when stderr is not a terminal), created at `Started`.
    Bar(Option<ProgressBar>),
    /// One JSON object per event on stdout.
    Json,
}

/// The recipe's observer: logs every event, and shows progress as a bar or as JSON lines.
///
/// The bar ticks every second (elapsed wall time) and says what the run is doing: the unit and its phase (moving,
/// playing which actuators, processing, committing), the retries so far, and the remaining time as a median and a
/// conservative 90th percentile ([`RemainingTime`], on the rig's clock) with the wall-clock time it ends.
pub struct Reporter {
    recipe: &'static str,
    unit: &'static str,
    display: Display,
    /// Units committed before this run (resume), for the rate.
    done_at_start: usize,
    /// The bar, shared with the Ctrl-C handler.
    shared_bar: ProgressBar,
    /// When this run started (wall clock).
    started: std::time::Instant,
    /// Rig-clock duration of each unit this run committed, s.
    durations_s: Vec<f64>,
    /// Rig clock at the last commit (or the start), s.
    last_commit_clock_s: f64,
    /// Retries and deferrals so far.
    retries: usize,
    /// What the run does now, as the bar shows it.
    activity: String,
    /// The last commit's part of the bar's message (SNR).
    last_commit: String,
    total: usize,
    done: usize,
    /// The dataset's directory, once started.
    dataset: Option<PathBuf>,
    /// Units committed by this run, by their worst row's status.
    status_counts: std::collections::BTreeMap<String, usize>,
    /// `--notify-command`, and the stall watch it gets once the run starts.
    notifier: Option<Arc<Notifier>>,
    stall_after_s: Option<f64>,
    watch: Option<StallWatch>,
}

impl Reporter {
    /// A reporter for `recipe` (`scan`, `calibrate`) counting `unit`s (`points`, `actuators`), as the run's
    /// options ask: JSON lines with `--json`, notifications with `--notify-command`.
    pub fn new(recipe: &'static str, unit: &'static str, args: &RunArgs) -> Self {
        let shared_bar = progress::run_bar(0, 0, recipe);
        let display = if args.json { Display::Json } else { Display::Bar(None) };
        Self {
            recipe,
            unit,
            display,
            done_at_start: 0,
            shared_bar,
            started: std::time::Instant::now(),
            durations_s: Vec::new(),
            last_commit_clock_s: 0.0,
            retries: 0,
            activity: String::new(),
            last_commit: String::new(),
            total: 0,
            done: 0,
            dataset: None,
            status_counts: std::collections::BTreeMap::new(),
            notifier: args.notify_command.clone().map(Notifier::new),
            stall_after_s: args.stall_after_s,
            watch: None,
        }
    }

    /// What a notification says of the run so far.
    fn summary(&self) -> Value {
        json!({
            "recipe": self.recipe,
            "dataset": self.dataset.as_ref().map(|d| d.display().to_string()),
            "done": self.done,
            "total": self.total,
            "unit_kind": self.unit,
            "committed_by_status": self.status_counts,
            "retries": self.retries,
            "wall_s": self.started.elapsed().as_secs_f64(),
            "remaining_s": self.remaining().map(|r| json!({"median": r.median_s, "p90": r.p90_s})),
        })
    }

    /// Notifications: the watch starts with the run and hears of every commit; the end is notified once.
    fn notify(&mut self, event: &Event) {
        let Some(notifier) = self.notifier.clone() else { return };
        match event {
            Event::Started { .. } => {
                self.watch = Some(StallWatch::start(notifier, self.stall_after_s, self.summary()));
            }
            Event::Committed { .. } => {
                if let Some(watch) = &self.watch {
                    watch.committed(self.summary());
                }
            }
            Event::Finished { .. } | Event::Stopped { .. } => {
                self.watch = None;
                let name = if matches!(event, Event::Finished { .. }) { "finished" } else { "stopped" };
                notifier.notify(name, name, self.summary());
            }
            _ => {}
        }
    }

    /// The bar (for the Ctrl-C handler's messages), when progress is shown as a bar.
    pub fn bar(&self) -> Option<ProgressBar> {
        matches!(self.display, Display::Bar(_)).then(|| self.shared_bar.clone())
    }

    /// Rate (units per hour) and ETA (hours) on the rig's clock, once this run has committed something.
    fn rate_and_eta(&self, done: usize, total: usize, clock_s: f64) -> Option<(f64, f64)> {
        let now = done.checked_sub(self.done_at_start).filter(|n| *n > 0)?;
        if !(clock_s.is_finite() && clock_s > 0.0) {
            return None;
        }
        let per_hour = now as f64 / clock_s * 3600.0;
        Some((per_hour, total.saturating_sub(done) as f64 / per_hour))
    }

    /// The remaining time on the rig's clock, from the units this run committed.
    fn remaining(&self) -> Option<RemainingTime> {
        RemainingTime::estimate(&self.durations_s, self.total.saturating_sub(self.done))
    }

    /// Wall-clock seconds per rig-clock second so far (1 on real instruments, less on the fast-forward mock lab),
    /// so that a remaining rig time becomes a time of day.
    fn wall_per_rig_s(&self) -> Option<f64> {
        let rig_s = self.last_commit_clock_s;
        (rig_s > 0.0).then(|| self.started.elapsed().as_secs_f64() / rig_s)
    }

    fn remaining_text(&self) -> Option<String> {
        let r = self.remaining()?;
        let ends = self.wall_per_rig_s().map_or_else(String::new, |ratio| {
            let wall_s = r.median_s * ratio;
            let at = chrono::Utc::now() + chrono::Duration::milliseconds((wall_s * 1e3) as i64);
            format!(", ends ~{} UTC", at.format("%H:%M"))
        });
        Some(format!("left {} (p90 {}){ends}", hours(r.median_s), hours(r.p90_s)))
    }

    fn log(&self, event: &Event) {
        match event {
            Event::Started { total, done, dataset, config_hash } => {
                tracing::info!(total, done, dataset = %dataset.display(), config_hash, "{} started", self.recipe)
            }
            Event::Committed { unit, done, total, snr_db, status, clock_s, .. } => {
                tracing::info!(unit, done, total, ?snr_db, status = %status, clock_s, "committed")
            }
            // A phase is a moment, not news: the log keeps commits and what went wrong.
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

    fn json(&self, event: &Event) -> Value {
        let mut value = match event {
            Event::Started { total, done, dataset, config_hash } => json!({ "event": "started", "total": total,
                "done": done, "dataset": dataset.display().to_string(), "config_hash": config_hash }),
            Event::Committed { unit, done, total, snr_db, status, clock_s, position } => {
                let (rate, eta) = self.rate_and_eta(*done, *total, *clock_s).unzip();
                let remaining = self.remaining().map(|r| json!({"median": r.median_s, "p90": r.p90_s}));
                let mut v = json!({ "event": "committed", "unit": unit, "done": done, "total": total,
                    "snr_db": snr_db, "status": status, "clock_s": clock_s, "rate_per_hour": rate, "eta_h": eta,
                    "remaining_s": remaining, "retries": self.retries,
                    "wall_s": self.started.elapsed().as_secs_f64(),
                    "at": chrono::Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, true) });
                if let (Some(p), Value::Object(map)) = (position, &mut v) {
                    for (key, value) in
                        [("ix", json!(p.ix)), ("iy", json!(p.iy)), ("x_m", json!(p.x_m)), ("y_m", json!(p.y_m))]
                    {
                        map.insert(key.into(), value);
                    }
                }
                v
            }
            Event::Phase { unit, phase, actuators } => {
                json!({ "event": "phase", "unit": unit, "phase": phase.as_str(), "actuators": actuators })
            }
            Event::Retry { unit, attempt, reason } => {
                json!({ "event": "retry", "unit": unit, "attempt": attempt, "reason": reason })
            }
            Event::Recovered { detail } => json!({ "event": "recovered", "detail": detail }),
            Event::Paused { detail } => json!({ "event": "paused", "detail": detail }),
            Event::ReferenceChecked { point, actuator, deviation_db, limit_db } => {
                json!({ "event": "reference_checked", "point": point, "actuator": actuator,
                        "deviation_db": deviation_db, "limit_db": limit_db })
            }
            Event::Stopped { done } => json!({ "event": "stopped", "done": done }),
            Event::Finished { done } => json!({ "event": "finished", "done": done }),
        };
        if let Value::Object(map) = &mut value {
            map.insert("recipe".into(), json!(self.recipe));
            map.insert("unit_kind".into(), json!(self.unit));
        }
        value
    }

    /// Keeps the counts every display needs.
    fn track(&mut self, event: &Event) {
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

    fn show(&mut self, event: &Event) {
        let Display::Bar(slot) = &mut self.display else { return };
        match event {
            Event::Started { total, done, .. } => {
                self.shared_bar.set_length(*total as u64);
                self.shared_bar.set_position(*done as u64);
                // Ticks every second, so the elapsed time moves between commits that are minutes apart.
                self.shared_bar.enable_steady_tick(std::time::Duration::from_secs(1));
                *slot = Some(self.shared_bar.clone());
            }
            Event::Phase { unit, phase, actuators } => {
                let unit_name = if self.unit == "points" { "point" } else { "actuator" };
                let driven = match actuators.as_slice() {
                    [] => String::new(),
                    [one] => format!(" actuator {one}"),
                    all => format!(" {} actuators", all.len()),
                };
                self.activity = format!("{unit_name} {unit}: {}{driven}", phase.as_str());
            }
            Event::Committed { done, snr_db, .. } => {
                self.last_commit = snr_db.map_or_else(String::new, |snr| format!(" | SNR {snr:.1} dB"));
                self.shared_bar.set_position(*done as u64);
            }
            Event::Recovered { detail } | Event::Paused { detail } => {
                let detail = detail.clone();
                self.shared_bar.suspend(|| eprintln!("{detail}"));
            }
            Event::Retry { .. } | Event::ReferenceChecked { .. } => {}
            Event::Stopped { .. } | Event::Finished { .. } => {
                self.shared_bar.finish();
                return;
            }
        }
        let remaining = self.remaining_text().unwrap_or_else(|| "left: after the first commit".to_owned());
        self.shared_bar
            .set_message(format!("{} | retries {} | {remaining}{}", self.activity, self.retries, self.last_commit));
    }
}

/// Seconds as hours or minutes, for the bar.
fn hours(seconds: f64) -> String {
    if seconds >= 3600.0 { format!("{:.1} h", seconds / 3600.0) } else { format!("{:.0} min", seconds / 60.0) }
}

impl Observer for Reporter {
    fn event(&mut self, event: &Event) {
        self.log(event);
        self.track(event);
        self.notify(event);
        if matches!(self.display, Display::Json) {
            let line = self.json(event).to_string();
            let mut out = std::io::stdout().lock();
            // A closed stdout must not stop a measurement: the dataset and the log still record everything.
            let _ = writeln!(out, "{line}").and_then(|()| out.flush());
        } else {
            self.show(event);
        }
    }
}

/// Writes a run's failure into its log (`DIR/<recipe>.log`, once the dataset exists), where the monitor reads how a
/// run ended.
pub fn log_failure(message: &str) {
    tracing::error!(error = %message, "run failed");
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

/// Ends a run: passes a result through; for a run stopped by Ctrl-C prints the resume command and exits with
/// [`EXIT_INTERRUPTED`]; turns other errors into messages that say what to do (a non-empty directory, a changed
/// configuration), with the resume command when a dataset was started.
///
/// # Errors
/// The run's error, with advice.
pub fn conclude<T>(result: Result<T, RecipeError>, args: &RunArgs) -> anyhow::Result<T> {
    let error = match result {
        Ok(value) => return Ok(value),
        Err(error) => error,
    };
    match &error {
        RecipeError::Interrupted { committed } => {
            eprintln!("stopped with {committed} committed; everything committed is kept. Resume with:");
            eprintln!("  {}", resume_command());
            std::process::exit(EXIT_INTERRUPTED);
        }
        RecipeError::Store(StoreError::NotEmpty { .. }) => Err(anyhow::Error::new(error).context(format!(
            "{} already holds files: add --resume to continue the run in it, or choose another --out",
            args.out.display()
        ))),
        RecipeError::Store(StoreError::ConfigChanged { .. }) => Err(anyhow::Error::new(error)
            .context("the run in --out was made with another configuration: add --force to resume it anyway")),
        _ if args.out.join(MANIFEST_FILE).exists() => {
            eprintln!("the run stopped; everything committed is kept. Once the problem is fixed, resume with:");
            eprintln!("  {}", resume_command());
            Err(error.into())
        }
        _ => Err(error.into()),
    }
}

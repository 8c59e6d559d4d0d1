//! What `metaplate calibrate` and `metaplate scan` share: their common options, the log file in the run directory,
//! progress (a bar, or `--json` events on stdout), Ctrl-C, and how a run ends: its exit code ([`EXIT_CODES_HELP`])
//! and, for a run that stops early, the resume command.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;
use metaplate_recipes::notify::{Notifier, RunNotifications};
use metaplate_recipes::output::{RunLog, read_preflight_report};
use metaplate_recipes::{Event, EventLine, Observer, Output, RecipeError, RunControl, RunProgress};
use metaplate_store::{MANIFEST_FILE, SceneId, StoreError};

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
    /// Run on the real instruments named in this hardware file (format: `crates/cli/hardware.example.toml`).
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
    /// Mock lab only: aim through the lab's galvanometer mirrors with this taught fit (written by `metaplate aim
    /// teach --scene S --out FILE`) instead of the lab's exact aim; the beam lands off by the fit's error, which a
    /// scan's responses carry (a calibration's, on the magnets, do not); the rig record names the fit.
    #[arg(long, value_name = "FILE", requires = "scene")]
    pub galvo_fit: Option<PathBuf>,
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
    /// The fit of `--galvo-fit`, read; `None` without it.
    ///
    /// # Errors
    /// The file cannot be read or is not a galvo fit (the error names the file).
    pub fn galvo_fit(&self) -> anyhow::Result<Option<metaplate_aim::galvo::GalvoFit>> {
        Ok(self.galvo_fit.as_deref().map(metaplate_aim::galvo::file::read).transpose()?)
    }

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
    let report = read_preflight_report(path).map_err(anyhow::Error::msg)?;
    if let Some(verdict) = report["verdict"].as_str().filter(|v| *v != "pass") {
        eprintln!("warning: the pre-flight in {} says `{verdict}`; the dataset records it", path.display());
    }
    Ok(report)
}

/// Sends `tracing` events (info and above, no colour codes) to `DIR/<recipe>.log` ([`RunLog`]), appended on resume.
///
/// # Errors
/// When a global subscriber is already installed.
pub fn init_log(dir: &Path, recipe: &str) -> anyhow::Result<()> {
    tracing_subscriber::fmt()
        .with_writer(Mutex::new(RunLog::new(dir, recipe)))
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

/// The recipe's observer: logs every event, and shows progress as a bar or as JSON lines ([`EventLine`]).
///
/// The bar ticks every second (elapsed wall time) and says what the run is doing: the unit and its phase (moving,
/// playing which actuators, processing, committing), the retries so far, and the remaining time as a median and a
/// conservative 90th percentile (on the rig's clock) with the wall-clock time it ends.
pub struct Reporter {
    display: Display,
    /// The bar, shared with the Ctrl-C handler.
    shared_bar: ProgressBar,
    /// Whether `--resume` was given (a new run started instead is said plainly).
    resume: bool,
    progress: RunProgress,
    /// What the run does now, as the bar shows it.
    activity: String,
    /// The last commit's part of the bar's message (SNR).
    last_commit: String,
    /// `--notify-command`'s notifications.
    notifications: Option<RunNotifications>,
}

impl Reporter {
    /// A reporter for `recipe` (`scan`, `calibrate`) counting `unit`s (`points`, `actuators`), as the run's
    /// options ask: JSON lines with `--json`, notifications with `--notify-command`.
    pub fn new(recipe: &'static str, unit: &'static str, args: &RunArgs) -> Self {
        Self {
            display: if args.json { Display::Json } else { Display::Bar(None) },
            shared_bar: progress::run_bar(0, 0, recipe),
            resume: args.resume,
            progress: RunProgress::new(recipe, unit),
            activity: String::new(),
            last_commit: String::new(),
            notifications: args.notify_command.clone().map(|c| RunNotifications::new(c, args.stall_after_s)),
        }
    }

    /// The bar (for the Ctrl-C handler's messages), when progress is shown as a bar.
    pub fn bar(&self) -> Option<ProgressBar> {
        matches!(self.display, Display::Bar(_)).then(|| self.shared_bar.clone())
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
                let unit_name = if self.progress.unit_kind() == "points" { "point" } else { "actuator" };
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
        let remaining = self.progress.remaining_text().unwrap_or_else(|| "left: after the first commit".to_owned());
        let retries = self.progress.retries();
        self.shared_bar.set_message(format!("{} | retries {retries} | {remaining}{}", self.activity, self.last_commit));
    }
}

/// One JSON line on stdout. A closed stdout must not stop a measurement: the dataset and the log still record
/// everything.
fn print_line(line: &EventLine) {
    if let Ok(text) = serde_json::to_string(line) {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "{text}").and_then(|()| out.flush());
    }
}

impl Observer for Reporter {
    fn event(&mut self, event: &Event) {
        event.log(self.progress.recipe());
        self.progress.track(event);
        if let Event::Started { dataset, resumed: false, .. } = event
            && self.resume
        {
            let message = format!("--resume: {} holds no run to resume; a new run starts at 0", dataset.display());
            self.shared_bar.suspend(|| eprintln!("{message}"));
        }
        if let Some(notifications) = &mut self.notifications {
            notifications.event(event, &self.progress);
        }
        if matches!(self.display, Display::Json) {
            print_line(&self.progress.line(event));
        } else {
            self.show(event);
        }
    }
}

/// Reports a run of `recipe` that failed with `message`: in its log (`DIR/<recipe>.log`, once the dataset exists),
/// where the monitor reads how a run ended; as a `failed` line with `--json`; to `--notify-command`.
pub fn report_failure(recipe: &'static str, args: &RunArgs, message: &str) {
    tracing::error!(error = %message, "run failed");
    let failed = EventLine::failed(recipe, &args.out, message.to_owned());
    if args.json {
        print_line(&failed);
    }
    if let Some(command) = &args.notify_command {
        Notifier::new(command.clone()).notify("failed", "failed", &failed);
    }
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
            eprintln!("  {}", metaplate_recipes::resume_command());
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
            eprintln!("  {}", metaplate_recipes::resume_command());
            Err(error.into())
        }
        _ => Err(error.into()),
    }
}

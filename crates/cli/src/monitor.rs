//! `metaplate monitor RUN_DIR`: the read-only web page and API over a calibration or scan directory
//! (`metaplate-monitor`).

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::Args;
use metaplate_monitor::follow::Follower;
use metaplate_monitor::state::snapshot;
use serde_json::json;

use crate::notify::Notifier;

/// Arguments of `metaplate monitor`.
#[derive(Args, Debug)]
#[command(after_help = "To watch a run on another machine, tunnel to it and open the page locally:\n  ssh -L \
8765:127.0.0.1:8765 lab-pc   # then http://localhost:8765/")]
pub struct MonitorArgs {
    /// The run's directory (the --out of `scan` or `calibrate`): running, finished or killed; it need not exist yet.
    pub run_dir: PathBuf,
    /// Loopback address and port to serve on (port 0: any free port; the URL is printed). Other addresses are
    /// refused: use `ssh -L` to watch from elsewhere.
    #[arg(long, default_value = "127.0.0.1:8765")]
    pub bind: SocketAddr,
    /// Run this shell command (`sh -c CMD`) with a JSON summary on its standard input when the run finishes, stops,
    /// fails or stalls while the monitor watches, once per event (as `scan --notify-command`; the README has examples).
    #[arg(long, value_name = "CMD")]
    pub notify_command: Option<String>,
}

/// Serves until interrupted. Prints `monitor: http://ADDR/` on stdout once listening.
pub fn run(args: &MonitorArgs) -> anyhow::Result<()> {
    if let Some(command) = &args.notify_command {
        let (dir, notifier) = (args.run_dir.clone(), Notifier::new(command.clone()));
        std::thread::Builder::new().name("monitor-notify".into()).spawn(move || notify_on_changes(dir, notifier))?;
    }
    metaplate_monitor::serve(&args.run_dir, args.bind, |addr| {
        use std::io::Write as _;
        println!("monitor: http://{addr}/ following {} (read-only; Ctrl-C to stop)", args.run_dir.display());
        // Scripts and tests read the address as soon as it is printed.
        let _ = std::io::stdout().flush();
    })?;
    Ok(())
}

/// Watches the run for `--notify-command`: a follower of its own (read-only, as the page's) polled every second;
/// the command runs when the run's status changes to finished, stopped, failed or stalled while the monitor watches (a run
/// that had already ended when the monitor started is not news), once per event (a new stall after progress is a
/// new event).
fn notify_on_changes(dir: PathBuf, notifier: std::sync::Arc<Notifier>) {
    let mut follower = Follower::new(dir.clone());
    let mut previous: Option<String> = None;
    loop {
        follower.poll();
        let state = snapshot(follower.files(), &dir, chrono::Utc::now());
        let status = state["status"].as_str().unwrap_or("waiting").to_owned();
        if previous.as_deref().is_some_and(|p| p != status)
            && ["finished", "stopped", "failed", "stalled"].contains(&status.as_str())
        {
            let key = format!("{status} at {}", state["points_done"]);
            let summary = json!({
                "recipe": state["recipe"], "dataset": dir.display().to_string(), "done": state["points_done"],
                "total": state["points_total"], "committed_by_status": state["status_counts"],
                "retries": state["retries"], "remaining_s": state["remaining_s"],
                "last_commit_age_s": state["last_commit_age_s"], "source": "monitor",
            });
            notifier.notify(&key, &status, summary);
        }
        previous = Some(status);
        std::thread::sleep(std::time::Duration::from_secs(1));
    }
}

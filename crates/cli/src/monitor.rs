//! `metaplate monitor RUN_DIR`: the read-only web page and API over a calibration or scan directory
//! (`metaplate-monitor`).

use std::net::SocketAddr;
use std::path::PathBuf;

use clap::Args;
use metaplate_recipes::notify::Notifier;

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
    metaplate_monitor::check_run_dir(&args.run_dir)?;
    if let Some(command) = &args.notify_command {
        metaplate_monitor::notices::watch(args.run_dir.clone(), Notifier::new(command.clone()))?;
    }
    metaplate_monitor::serve(&args.run_dir, args.bind, |addr| {
        use std::io::Write as _;
        println!("monitor: http://{addr}/ following {} (read-only; Ctrl-C to stop)", args.run_dir.display());
        // Scripts and tests read the address as soon as it is printed.
        let _ = std::io::stdout().flush();
    })?;
    Ok(())
}

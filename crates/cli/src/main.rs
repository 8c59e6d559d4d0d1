//! The `metaplate` command-line tool.
//!
//! Each subcommand lives in its own module; this file only parses the command line and dispatches.

use clap::{Parser, Subcommand};

mod aim;
mod analyze;
mod budget;
mod cache;
mod calibrate;
mod check;
mod deconvolve;
mod demo;
mod design;
mod devices;
mod experiment;
mod experiment_run;
mod experiment_stimuli;
mod export;
mod focus;
mod import;
mod lab;
mod monitor;
mod play;
mod progress;
mod replay;
mod report;
mod rig;
mod run;
mod scan;
mod scene;
mod simulate;
mod sweep;
mod tradeoff;
mod wav;

#[derive(Parser)]
#[command(
    name = "metaplate",
    version,
    about = "Instrument control and measurement automation for wave-focusing tactile displays"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Aiming the beam: `aim teach` jogs galvo mirrors onto marks with the keyboard and writes the fit the hardware
    /// file's `[aim]` names (or, with --scene, the mock lab's mirrors).
    Aim {
        #[command(subcommand)]
        command: aim::AimCommand,
    },
    /// The paper's Wave Field Analysis on a dataset: wavelength, pixel area, POD, authority, refresh, driven
    /// response (JSON with --json), and its figures with --figures DIR.
    Analyze(analyze::AnalyzeArgs),
    /// The main job: run the suite end to end on the built-in simulated plates and print the paper-against-suite
    /// table.
    Demo(demo::DemoArgs),
    /// What is connected that a hardware file can name (serial ports, USB DAQs, NI-DAQmx devices, ALSA PCMs, HID
    /// keypads), per instrument; --write-hardware drafts a hardware file from it.
    Devices(devices::DevicesArgs),
    /// The pre-flight of a rig before a night's run (minutes): each instrument answers, the loopback's latency and
    /// level, the actuators' wiring, the LDV's signal, the clocks' drift, the disk against the run's size and its
    /// duration; a verdict, and exit 0 only when the run can start.
    Check(check::CheckArgs),
    /// Deconvolve a recorded WAV by its excitation (or by a loopback channel) into impulse responses.
    Deconvolve(deconvolve::DeconvolveArgs),
    /// Drive signals that focus target waveforms on virtual pixels (multichannel WAV), from a dataset.
    Focus(focus::FocusArgs),
    /// Play focused targets on the rig (mock lab or hardware) through the calibration: the onset measured on the
    /// loopback, the predicted peak velocity at each pixel; refuses drives that would clip and unfocusable pixels.
    Play(play::PlayArgs),
    /// The paper's behavioural experiments: list the built-ins; report session directories (accuracy, Wilson 95 %,
    /// exact binomial p against chance, confusion matrices; JSON, Parquet, figures).
    Experiment(experiment::ExperimentArgs),
    /// Export a dataset as a universal file (UFF 58 or 58b, with 164 units and 2411 nodes) for modal-analysis
    /// tools, streamed with a progress bar.
    Export(export::ExportArgs),
    /// Build a dataset from universal files (58/58b responses, 2411 nodes, 164 units) that analyze and focus read.
    Import(import::ImportArgs),
    /// Watch a calibration or scan (running, finished or killed) in a browser: a read-only, loopback-only page
    /// and API (`/api/state`, `/events`, `/api/point/N`) that follow its directory.
    Monitor(monitor::MonitorArgs),
    /// One self-contained HTML report on scan datasets (one plate or the pair): the paper-against-suite table,
    /// the figures, each measurement's summary with status and SNR maps, its error against the simulated truth,
    /// and its provenance.
    Report(report::ReportArgs),
    /// Write an excitation sweep (the paper's by default) as a 32-bit float WAV file.
    Sweep(sweep::SweepArgs),
    /// List the built-in scenes, or show one (or a scene file) fully resolved.
    Scene(scene::SceneArgs),
    /// Replay a recorded device session (cassette) through its driver, optionally with faults; or record one
    /// against a mock device (--record-mock).
    Replay(replay::ReplayArgs),
    /// Calibrate the actuators (mock lab or real hardware): per actuator a sweep on its magnet, a Kirkeby inverse
    /// filter and a verification through it; one commit per actuator; resumable (--resume).
    Calibrate(calibrate::CalibrateArgs),
    /// Scan the grid (mock lab or real hardware): every point, every actuator, the compensated excitation,
    /// deconvolution and quality gates; one commit per point; Ctrl-C and crash safe, resumable (--resume).
    Scan(scan::ScanArgs),
    /// Measure the scan protocols' speed/accuracy trade on the mock lab: time per point, full-scan hours, error
    /// against the ground truth, pixel area (JSON with --json, the Pareto plot with --figures DIR); the protocol
    /// names: `--help` of `--protocols`.
    Tradeoff(tradeoff::TradeoffArgs),
    /// The Green's-function error budget of a scene on the mock lab: the processing floor (every imperfection
    /// off), each imperfection alone, all on, per octave band, and whether the terms add up (JSON with --json).
    Budget(budget::BudgetArgs),
    /// Metamaterial design: a unit cell's band structure (`design band`), a search over designs (`design search`,
    /// `design merge`).
    Design {
        #[command(subcommand)]
        command: design::DesignCommand,
    },
    /// The stand-in rig (`lab serve`): a scene's mock lab behind the real instruments' links, for rehearsing.
    Lab {
        #[command(subcommand)]
        command: lab::LabCommand,
    },
    /// The simulated plate's ground truth: dispersion, Green's functions.
    Simulate {
        #[command(subcommand)]
        command: simulate::SimulateCommand,
    },
}

/// Runs the command; a failure is printed as one message (its causes after colons, never a backtrace, whatever
/// `RUST_BACKTRACE` says) and exits with 1. A `scan` or `calibrate` with `--json` prints a `failed` event first,
/// so a script reading the events learns of it on the same channel, and runs its `--notify-command`.
fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let run = match &cli.command {
        Command::Scan(args) => Some(("scan", args.run.clone())),
        Command::Calibrate(args) => Some(("calibrate", args.run.clone())),
        _ => None,
    };
    let Err(error) = dispatch(cli.command) else { return std::process::ExitCode::SUCCESS };
    // Each cause once: many errors print their source inside their own message too.
    let message = metaplate_core::error_chain::message(&*error);
    if let Some((recipe, args)) = run {
        run::report_failure(recipe, &args, &message);
    }
    eprintln!("error: {message}");
    std::process::ExitCode::FAILURE
}

fn dispatch(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Aim { command } => aim::run(&command),
        Command::Analyze(args) => analyze::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Check(args) => check::run(&args),
        Command::Devices(args) => devices::run(&args),
        Command::Deconvolve(args) => deconvolve::run(&args),
        Command::Focus(args) => focus::run(&args),
        Command::Play(args) => play::run(&args),
        Command::Experiment(args) => experiment::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Import(args) => import::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Scene(args) => scene::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Monitor(args) => monitor::run(&args),
        Command::Report(args) => report::run(&args),
        Command::Tradeoff(args) => tradeoff::run(&args),
        Command::Budget(args) => budget::run(&args),
        Command::Simulate { command } => simulate::run(&command),
        Command::Lab { command } => lab::run(&command),
        Command::Design { command } => design::run(&command),
        Command::Calibrate(args) => calibrate::run(&args),
        Command::Scan(args) => scan::run(&args),
    }
}

//! `metaplate lab serve`: the stand-in rig, a scene's mock lab behind the real instruments' links
//! (`metaplate_lab::serve`), until Ctrl-C.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Args, Subcommand};
use metaplate_core::grid::GridSubset;
use metaplate_lab::serve::{RigAim, ServeOptions, StandInRig};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::ScanPoints;

/// Subcommands of `metaplate lab`.
#[derive(Subcommand)]
pub enum LabCommand {
    /// Serve a scene's mock lab in a folder whose `hardware.toml` names it as real instruments (a Polytec
    /// controller and Zaber stages on pseudo-terminals, NI-DAQmx through its stand-in library, ALSA's `file` PCM),
    /// for `check --hardware` and `scan --hardware`, until Ctrl-C.
    Serve(ServeArgs),
}

/// Arguments of `metaplate lab serve`.
#[derive(Args)]
pub struct ServeArgs {
    /// Scene: a built-in name or a TOML file.
    #[arg(long)]
    scene: String,
    /// The folder served from (created): hardware.toml, the DAQ's socket and library, the audio FIFO.
    #[arg(long)]
    out: PathBuf,
    /// Prepare only the evenly spread NXxNY subset of the grid a scan will visit (e.g. 7x5); default: every point.
    #[arg(long)]
    grid: Option<GridSubset>,
    /// What aims the beam: `stages` (Zaber) or `galvo` (mirrors on NI outputs; teach them with `aim teach`).
    #[arg(long, default_value = "stages")]
    aim: RigAim,
    /// How many times faster than real time the DAQ acquires (0.1 to 100; the stages move in real time).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// The stand-in NI-DAQmx library (`cargo build -p metaplate-mock-nidaqmx`); default: the one beside this binary.
    #[arg(long, value_name = "FILE")]
    nidaqmx_library: Option<PathBuf>,
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
}

/// Runs `metaplate lab`.
pub fn run(command: &LabCommand) -> anyhow::Result<()> {
    let LabCommand::Serve(args) = command;
    let plate = crate::rig::Plate::resolve(&args.scene)?;
    let plan = args.grid.map(|grid| ScanPoints::of_scene(&plate.scene, Some(grid))).transpose()?;
    let points = plan.map(|plan| plan.with_driving_points(&plate.scene));
    let lab = MockLab::new(&plate.scene, &LabOptions { cache_dir: args.cache.dir(), points, ..LabOptions::default() })?;
    let options = ServeOptions::new(&args.scene, args.speed, args.nidaqmx_library.clone(), args.aim)?;
    let rig = StandInRig::start(lab, &args.out, &options)?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::Release))?;
    println!("{}", rig.summary());
    while !stop.load(Ordering::Acquire) {
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    Ok(())
}

//! `metaplate experiment run`: one participant's session on the rig (`metaplate_experiment::runner`'s); this opens
//! the rig and the console (standard input, and the hardware file's keypad).

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_experiment::builtin;
use metaplate_experiment::console::ChannelConsole;
use metaplate_experiment::runner::{Responder, SessionOutput, SessionRunner};
use metaplate_experiment::stimulus::DriveOptions;
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_recipes::play::check_playable;
use metaplate_store::Dataset;

use metaplate_lab::LabOptions;

use crate::rig::{self, Plate};
use crate::run::Source;

/// Arguments of `metaplate experiment run`.
#[derive(Args)]
pub struct RunArgs {
    /// A built-in experiment (`metaplate experiment list`) or an experiment file.
    experiment: String,
    /// The participant: an id (`P01`: the experimenter's console answers), or `sim[:opts]`, the simulated
    /// participant (`sim:seed=3`; options: seed, threshold_m_s, level_slope_db, contrast_50_db,
    /// contrast_slope_db, lapse).
    #[arg(long)]
    participant: String,
    /// Scan dataset directory (impulse responses in m/s per full-scale drive, measured through the calibration).
    #[arg(long)]
    data: PathBuf,
    /// Calibration dataset the scan was measured through: the drives go through its Kirkeby filters.
    #[arg(long)]
    calibration: PathBuf,
    /// Session directory: plan.json and journal.jsonl. An existing session there is resumed; one that another
    /// process is running is refused at once, naming that process.
    #[arg(long)]
    out: PathBuf,
    /// Where to play: --scene (mock lab) or --hardware FILE.
    #[command(flatten)]
    source: Source,
    /// Seed of the plan (the trial order) and of the stimuli's noise. Default: the file's `order.seed`.
    #[arg(long)]
    seed: Option<u64>,
    /// Playback level relative to full scale (each stimulus's drives are peak-normalised to 1, then scaled).
    #[arg(long, default_value_t = DRIVE_PEAK_FS)]
    level: f64,
    /// Resume even though the plan, the experiment file or the participant differ from the stored session's (the
    /// stored plan is kept, and the forcing journalled).
    #[arg(long)]
    force: bool,
    /// Print one JSON object per trial on stdout (and one at the end).
    #[arg(long)]
    json: bool,
    /// Mock lab only: where the plate's Green's functions are cached.
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
}

/// Runs `metaplate experiment run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let experiment = builtin::resolve(&args.experiment)?;
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let drive = DriveOptions { calibration: args.calibration.clone(), level: args.level };
    let runner = SessionRunner::new(&experiment, &args.participant, &dataset, drive, &args.out, args.seed, args.force)?;
    let (mut rig, lab, keypad) = match (&args.source.scene, &args.source.hardware) {
        (_, Some(file)) => {
            let (plate, opened) = rig::hardware_rig_and_keypad(file, metaplate_drivers::OpenPurpose::Play)?;
            check_playable(&dataset, &plate.id)?;
            (opened.rig, None, opened.keypad)
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            check_playable(&dataset, &plate.id)?;
            // Only the magnets are prepared: nothing is measured at the pixels (the beam rests where it is).
            let points = Some(plate.scene.driving_points());
            let options = LabOptions { seed: None, cache_dir: args.cache.dir(), points, ..LabOptions::default() };
            let (lab, rig) = rig::mock_rig_with(&plate, &options)?;
            (rig, Some(lab), None)
        }
        (None, None) => bail!("give --scene or --hardware"),
    };
    let mut console;
    let responder = match runner.simulated() {
        Some(sim) => Responder::Sim(sim),
        None => {
            console = ChannelConsole::spawn(std::io::BufReader::new(std::io::stdin()), keypad, |m| eprintln!("{m}"));
            Responder::Console(&mut console)
        }
    };
    let (mut stdout, mut stderr) = (std::io::stdout(), std::io::stderr());
    let mut out = SessionOutput { events: &mut stdout, json: args.json, log: &mut stderr };
    runner.run(&mut rig, lab.is_some(), responder, &mut out)?;
    Ok(())
}

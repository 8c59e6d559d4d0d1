//! `metaplate scan`: every unmasked grid point (or an evenly spread subset), every actuator, the compensated
//! excitation, deconvolution, quality gates; one commit per point, resumable after anything.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_lab::LabOptions;
use metaplate_recipes::{Calibration, RunControl, ScanConfig, ScanPoints, scan};

use crate::rig::{self, Opened};
use crate::run::{self, Reporter, RunArgs};

/// Which inverse filters drive the actuators: exactly one of `--calibration` and `--uncalibrated`.
#[derive(Args, Debug)]
#[group(required = true, multiple = false)]
pub struct Drive {
    /// Calibration dataset (from `metaplate calibrate`) whose inverse filters compensate each actuator. Its content
    /// hash is stored in the scan's configuration: resuming with another calibration is refused without --force.
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Drive the actuators with the raw excitation, uncompensated.
    #[arg(long)]
    pub uncalibrated: bool,
}

/// Arguments of `metaplate scan`.
///
/// Writes the Green's functions dataset into --out (one row per point and actuator: impulse response, SNR,
/// status valid / re-measured / overrange / dropout / failed, retries), logs to `OUT/scan.log`, and shows a
/// progress bar with the rate and the ETA in hours of the rig's clock (or --json events). Ctrl-C stops after the
/// point in flight (twice: abandons it) and prints the command that resumes.
#[derive(Args, Debug)]
#[command(after_help = run::EXIT_CODES_HELP)]
pub struct ScanArgs {
    #[command(flatten)]
    pub run: RunArgs,
    #[command(flatten)]
    pub drive: Drive,
    /// Measure an evenly spread NXxNY subset of the scene's grid (for example 7x5); default: every measurable
    /// point.
    #[arg(long)]
    pub grid: Option<GridSubset>,
    /// Excitation protocol (the list below is the excitation-protocol registry).
    #[arg(long, default_value = "paper", long_help = metaplate_dsp::excitation::help_text())]
    pub protocol: String,
}

/// Runs `metaplate scan`.
pub fn run(args: &ScanArgs) -> anyhow::Result<()> {
    let common = &args.run;
    let protocol = ExcitationProtocol::by_name(&args.protocol)?;
    run::init_log(&common.out, "scan")?;
    let Opened { plate, mut rig, lab: _lab, .. } =
        rig::open(&common.source, metaplate_drivers::OpenPurpose::Measure, |plate| {
            let plan = ScanPoints::of_scene(&plate.scene, args.grid)?;
            let points = plan.prepared_whole(&plate.scene).unwrap_or(plan.points);
            let galvo_fit = common.galvo_fit()?;
            let cache_dir = common.cache.dir();
            Ok(LabOptions { seed: common.seed, cache_dir, points: Some(points), galvo_fit, ..Default::default() })
        })?;
    let plan = ScanPoints::of_scene(&plate.scene, args.grid)?;
    let actuators = rig.wiring.actuator_channels.len();
    let load = |dir: &PathBuf| {
        Calibration::load(dir, actuators).with_context(|| format!("reading the calibration in {}", dir.display()))
    };
    let calibration = args.drive.calibration.as_ref().map(load).transpose()?;
    let config = ScanConfig { protocol, seed: common.seed.unwrap_or(plate.scene.seed), ..ScanConfig::default() };
    let control = RunControl::new();
    let mut reporter = Reporter::new("scan", "points", common);
    run::handle_ctrl_c(&control, reporter.bar())?;
    let output = common.output(plate.id.clone())?;
    let result = scan(&mut rig, &plan, calibration.as_ref(), &config, &output, &control, &mut reporter);
    let summary = run::conclude(result, common)?;
    if !common.json {
        eprintln!("{summary}; dataset in {}", common.out.display());
    }
    run::exit_if_flagged(summary.flagged_rows(), "rows");
    Ok(())
}

//! `metaplate scan`: every unmasked grid point (or an evenly spread subset), every actuator, the compensated
//! excitation, deconvolution, quality gates; one commit per point, resumable after anything.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_dsp::excitation::{ExcitationProtocol, NAMES as PROTOCOL_NAMES};
use metaplate_recipes::{Calibration, RunControl, ScanConfig, ScanPlan, scan};

use crate::rig::{self, Plate};
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
    #[arg(long, default_value = "paper", long_help = protocol_help())]
    pub protocol: String,
}

/// Runs `metaplate scan`.
pub fn run(args: &ScanArgs) -> anyhow::Result<()> {
    let common = &args.run;
    let protocol = ExcitationProtocol::by_name(&args.protocol)?;
    run::init_log(&common.out, "scan")?;
    let (plate, mut rig, _lab, plan) = match (&common.source.scene, &common.source.hardware) {
        (_, Some(file)) => {
            let (plate, rig) = rig::hardware_rig(file)?;
            let plan = plan(&plate, args.grid)?;
            (plate, rig, None, plan)
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            let plan = plan(&plate, args.grid)?;
            let points = plate.small_plan_points(&plan).unwrap_or_else(|| plan.points.clone());
            let (lab, rig) = rig::mock_rig(&plate, points, common.seed, common.cache.dir())?;
            (plate, rig, Some(lab), plan)
        }
        (None, None) => anyhow::bail!("give --scene or --hardware"),
    };
    let calibration = match &args.drive.calibration {
        Some(dir) => Some(
            Calibration::load(dir, rig.wiring.actuator_channels.len())
                .with_context(|| format!("reading the calibration in {}", dir.display()))?,
        ),
        None => None,
    };
    let config = ScanConfig { protocol, seed: common.seed.unwrap_or(plate.scene.seed), ..ScanConfig::default() };
    let control = RunControl::new();
    let mut reporter = Reporter::new("scan", "points", common);
    run::handle_ctrl_c(&control, reporter.bar())?;
    let output = common.output(plate.id.clone())?;
    let result = scan(&mut rig, &plan, calibration.as_ref(), &config, &output, &control, &mut reporter);
    let summary = run::conclude(result, common)?;
    if !common.json {
        let statuses: Vec<String> = summary.statuses.iter().map(|(s, n)| format!("{n} {s}")).collect();
        eprintln!(
            "{} of {} points committed ({} now: rows {}; {} deferred), {:.2} h on the rig's clock; dataset in {}",
            summary.committed,
            summary.total,
            summary.committed_now,
            if statuses.is_empty() { "none".to_string() } else { statuses.join(", ") },
            summary.deferred,
            summary.clock_s / 3600.0,
            common.out.display()
        );
    }
    let flagged: usize =
        summary.statuses.iter().filter(|(s, _)| ["failed", "dropout", "overrange"].contains(s)).map(|(_, n)| n).sum();
    run::exit_if_flagged(flagged, "rows");
    Ok(())
}

/// The `--protocol` help: every name of the excitation-protocol registry (`metaplate_dsp::excitation::NAMES`),
/// with what it plays.
pub fn protocol_help() -> String {
    let names: Vec<String> = PROTOCOL_NAMES.iter().map(|(name, what)| format!("  {name}: {what}")).collect();
    format!("Excitation protocol, one of:\n{}", names.join("\n"))
}

/// The scan plan over `plate`'s grid and mask, on the `subset` if given.
pub fn plan(plate: &Plate, subset: Option<GridSubset>) -> anyhow::Result<ScanPlan> {
    Ok(ScanPlan::new(plate.scene.grid, &plate.scene.grid_mask(), subset.map(Into::into))?)
}

//! `metaplate calibrate`: per actuator, the beam on its magnet, the calibration sweep, the Kirkeby inverse filter
//! and a verification through it; one commit per actuator, resumable.

use clap::Args;
use metaplate_lab::LabOptions;
use metaplate_recipes::{CalibrationConfig, RunControl, calibrate};

use crate::rig::{self, Opened};
use crate::run::{self, Reporter, RunArgs};

/// Arguments of `metaplate calibrate`.
///
/// Writes a calibration dataset into --out (one row per actuator for the filter taps, the measured response and
/// the verification response), logs to `OUT/calibrate.log`, and shows a progress bar (or --json events). Ctrl-C
/// stops after the actuator in flight (twice: abandons it) and prints the command that resumes.
#[derive(Args, Debug)]
#[command(after_help = run::EXIT_CODES_HELP)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub run: RunArgs,
}

/// Runs `metaplate calibrate`.
pub fn run(args: &CalibrateArgs) -> anyhow::Result<()> {
    let common = &args.run;
    run::init_log(&common.out, "calibrate")?;
    let Opened { plate, mut rig, lab: _lab, .. } =
        rig::open(&common.source, metaplate_drivers::OpenPurpose::Measure, |plate| {
            let points = Some(plate.scene.driving_points());
            let galvo_fit = common.galvo_fit()?;
            Ok(LabOptions {
                seed: common.seed,
                cache_dir: common.cache.dir(),
                points,
                galvo_fit,
                ..LabOptions::default()
            })
        })?;
    let config = CalibrationConfig { seed: common.seed.unwrap_or(plate.scene.seed), ..CalibrationConfig::default() };
    let control = RunControl::new();
    let mut reporter = Reporter::new("calibrate", "actuators", common);
    run::handle_ctrl_c(&control, reporter.bar())?;
    let sites = plate.scene.actuator_sites_m();
    let result = calibrate(&mut rig, &sites, &config, &common.output(plate.id.clone())?, &control, &mut reporter);
    let results = run::conclude(result, common)?;
    if !common.json {
        for r in &results {
            eprintln!("{r}");
        }
        eprintln!("calibration written to {}", common.out.display());
    }
    let flagged = results.iter().filter(|r| r.status != metaplate_store::Status::Valid).count();
    run::exit_if_flagged(flagged, "actuators");
    Ok(())
}

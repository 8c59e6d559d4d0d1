//! `metaplate experiment stimuli`: how well a scan renders an experiment's stimuli, before anyone touches the
//! plate (`metaplate_experiment::stimuli`); with `--truth`, also on the mock lab's plate the scan was made on.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_experiment::stimuli::{
    StimuliOptions, Truth, default_experiments, stimuli_report, truth_points, truth_reach,
};
use metaplate_experiment::stimulus::DriveOptions;
use metaplate_experiment::{Experiment, builtin};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::drive::DRIVE_PEAK_FS;
use metaplate_store::Dataset;

use crate::rig::Plate;
use metaplate_recipes::PREPARE_WHOLE_PLAN_POINTS;

/// Arguments of `metaplate experiment stimuli`.
#[derive(Args, Debug)]
pub struct StimuliArgs {
    /// Experiments: built-in names or experiment files (default: the paper's four).
    experiments: Vec<String>,
    /// The scan the stimuli are rendered from (measured through --calibration; the pixels snap to its points).
    #[arg(long)]
    data: PathBuf,
    /// The calibration the scan was measured through.
    #[arg(long)]
    calibration: PathBuf,
    /// Drive level relative to full scale, as `experiment run --level`.
    #[arg(long, default_value_t = DRIVE_PEAK_FS)]
    level: f64,
    /// A fingertip's reach, m: a null pixel's figure is the largest predicted peak at the measured points within
    /// this distance of it (the field at one point can be nulled while a finger resting there still feels the field
    /// beside it). The default, 5 mm, is a fingertip's contact radius: on the paper's 5 mm grid it takes the four
    /// neighbours; on a coarser scan only the point.
    #[arg(long, default_value_t = 0.005)]
    fingertip_radius_m: f64,
    /// Seed of the stimuli's noise (default: each experiment's plan seed).
    #[arg(long)]
    seed: Option<u64>,
    /// Print JSON: `{"level", "experiments": [{"name", "stimuli": [{"id", "pixels": [{"name", "role",
    /// "predicted_peak_mm_s", "within_fingertip_mm_s"}], "target_min_mm_s", "null_max_mm_s", "suppression_db"}]}]}`
    /// (`null_max_mm_s` within reach).
    #[arg(long)]
    json: bool,
    /// Also write, per experiment, `DIR/<experiment>-stimuli.png` and `.svg`: each stimulus's predicted velocity at
    /// its pixels over time (targets in colour, nulls grey, others a second colour), as the paper's Figs. S8 to S11.
    #[arg(long, value_name = "DIR")]
    figures: Option<PathBuf>,
    /// The mock lab's scene the scan was made on (a built-in's name or a scene file): each stimulus is then also
    /// played, as rendered from the scan, through that plate's true response (the ground truth: what the
    /// fingertips would feel), and the report gives the true figures beside the predicted ones.
    #[arg(long, value_name = "SCENE")]
    truth: Option<String>,
    #[command(flatten)]
    cache: crate::cache::CacheArgs,
}

/// Runs `metaplate experiment stimuli`.
pub fn run(args: &StimuliArgs) -> anyhow::Result<()> {
    let dataset = Dataset::open(&args.data).with_context(|| format!("opening dataset {}", args.data.display()))?;
    let names = if args.experiments.is_empty() { default_experiments() } else { args.experiments.clone() };
    let resolved: Vec<Experiment> = names.iter().map(|n| builtin::resolve(n)).collect::<Result<_, _>>()?;
    // The ground truth: the scan's lab (its seed draws the coils' spread), at the points within reach of the pixels.
    let lab_and_reach = match &args.truth {
        Some(scene) => {
            let plate = Plate::resolve(scene)?;
            let reach = truth_reach(&dataset, &resolved, args.fingertip_radius_m, &plate.id, scene)?;
            let points = truth_points(&dataset, &reach, PREPARE_WHOLE_PLAN_POINTS, plate.scene.driving_points());
            eprintln!("the ground truth: the plate of `{scene}` at {} points (cached once computed)", points.len());
            let (seed, cache_dir) = (Some(dataset.manifest().meta.seed), args.cache.dir());
            let options = LabOptions { seed, points: Some(points), cache_dir, ..LabOptions::default() };
            Some((MockLab::new(&plate.scene, &options)?, reach))
        }
        None => None,
    };
    let velocity = |q: usize, actuators: &[usize], drives: &[Vec<f64>], fs: f64| match &lab_and_reach {
        Some((lab, _)) => lab.true_velocity(q, actuators, drives, fs).map_err(|e| e.to_string()),
        None => Err("no ground truth".to_owned()),
    };
    let truth = lab_and_reach.as_ref().map(|(_, reach)| Truth { reach: reach.clone(), velocity: &velocity });
    let options = StimuliOptions {
        data: args.data.clone(),
        drive: DriveOptions { calibration: args.calibration.clone(), level: args.level },
        fingertip_radius_m: args.fingertip_radius_m,
        seed: args.seed,
        figures: args.figures.clone(),
    };
    let report = stimuli_report(&dataset, &resolved, &options, truth.as_ref(), &mut std::io::stderr())?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        report.write_table(&mut std::io::stdout())?;
    }
    Ok(())
}

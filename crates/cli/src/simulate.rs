//! `metaplate simulate ...`: the simulated plate's ground truth, straight from the plate model
//! (`metaplate_evaluation::simulated`).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};
use indicatif::ProgressBar;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_evaluation::simulated::{
    GroundTruthProgress, frequencies, model_dispersion, select_points, write_ground_truth,
};
use metaplate_plate::{GreensRequest, ModelOptions};

use crate::cache::CacheArgs;
use crate::progress;

/// Subcommands of `metaplate simulate`.
#[derive(Subcommand)]
pub enum SimulateCommand {
    /// Measure wavelength against frequency on the simulated plate with the paper's k-space method; with --json,
    /// print `{"points": [{"freq_hz", "wavelength_m", "a0_wavelength_m", ...}]}`.
    Dispersion(DispersionArgs),
    /// Write the scene's ground-truth Green's functions as a dataset (the format a scan produces).
    Greens(GreensArgs),
}

/// Options shared by the simulate commands.
#[derive(Args)]
pub struct ModelArgs {
    /// Scene: a built-in name (`metaplate scene list`) or a TOML file.
    #[arg(long)]
    scene: String,
    /// Plate-model lattice nodes per measurement-grid step (2: 2.5 mm on the paper's 5 mm grid).
    #[arg(long, default_value_t = ModelOptions::default().refinement)]
    refinement: usize,
}

impl ModelArgs {
    fn load(&self) -> anyhow::Result<(Scene, ModelOptions)> {
        let scene = Scene::resolve(&self.scene).with_context(|| format!("loading scene {}", self.scene))?;
        let options = ModelOptions { refinement: self.refinement, ..ModelOptions::default() };
        Ok((scene, options))
    }
}

/// Arguments of `metaplate simulate dispersion`.
#[derive(Args)]
pub struct DispersionArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Lowest frequency, Hz.
    #[arg(long, default_value_t = 75.0)]
    from_hz: f64,
    /// Highest frequency, Hz.
    #[arg(long, default_value_t = 600.0)]
    to_hz: f64,
    /// Frequency step, Hz.
    #[arg(long, default_value_t = 25.0)]
    step_hz: f64,
    /// Print one JSON object on stdout instead of a table.
    #[arg(long)]
    json: bool,
}

/// Arguments of `metaplate simulate greens`.
#[derive(Args)]
pub struct GreensArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output dataset directory.
    #[arg(long)]
    out: PathBuf,
    /// An evenly spread NXxNY subset of the scene's grid (for example 7x5); default: every measured point.
    #[arg(long)]
    grid: Option<GridSubset>,
    /// Impulse-response length, s.
    #[arg(long, default_value_t = 0.5)]
    duration_s: f64,
    /// Lowest frequency computed, Hz.
    #[arg(long, default_value_t = 50.0)]
    band_lo_hz: f64,
    /// Highest frequency computed, Hz.
    #[arg(long, default_value_t = 700.0)]
    band_hi_hz: f64,
    /// Replace an existing dataset in --out.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    cache: CacheArgs,
}

/// Runs a simulate subcommand.
pub fn run(command: &SimulateCommand) -> anyhow::Result<()> {
    match command {
        SimulateCommand::Dispersion(args) => {
            let (scene, options) = args.model.load()?;
            let freqs = frequencies(args.from_hz, args.to_hz, args.step_hz)?;
            let bar = progress::bar(freqs.len() as u64, "dispersion");
            let report = model_dispersion(&scene, &options, &freqs, &mut || bar.inc(1))?;
            bar.finish_and_clear();
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", report.table_text());
            }
        }
        SimulateCommand::Greens(args) => {
            let (scene, options) = args.model.load()?;
            let request = GreensRequest {
                points: select_points(&scene, args.grid)?,
                actuators: (0..scene.actuators.len()).collect(),
                band_hz: (args.band_lo_hz, args.band_hi_hz),
                duration_s: args.duration_s,
                sample_rate_hz: scene.daq.sample_rate_hz,
            };
            let (mut spinner, mut bar) = (None, None);
            let summary = write_ground_truth(
                &scene,
                &options,
                &request,
                &args.out,
                args.force,
                args.cache.dir().as_deref(),
                &mut |step| match step {
                    GroundTruthProgress::Computing { points, actuators } => {
                        spinner = Some(progress::spinner(format!("computing {points} points x {actuators} actuators")));
                    }
                    GroundTruthProgress::Writing { done, total } => {
                        spinner.take().inspect(ProgressBar::finish_and_clear);
                        bar.get_or_insert_with(|| progress::bar(total as u64, "writing")).set_position(done as u64);
                    }
                },
            )?;
            spinner.into_iter().chain(bar).for_each(|b| b.finish_and_clear());
            println!("{}", serde_json::to_string_pretty(&summary)?);
        }
    }
    Ok(())
}

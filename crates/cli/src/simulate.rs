//! `metaplate simulate ...`: the simulated plate's ground truth, straight from the plate model.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use metaplate_analysis::dispersion::{DispersionOptions, SceneLayout, wavelengths_at};
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_plate::{GreensFunctions, GreensRequest, ModelOptions, PlateModel};
use metaplate_store::{
    DatasetDescription, DatasetMeta, DatasetWriter, IR_UNIT_M_S_PER_N, IfExists, IrMeta, IrRecord, Status,
};
use serde_json::{Value, json};

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
            let report = dispersion(&scene, &options, &freqs)?;
            if args.json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print_dispersion(&report);
            }
            Ok(())
        }
        SimulateCommand::Greens(args) => {
            let (scene, options) = args.model.load()?;
            let points = select_points(&scene, args.grid)?;
            let request = GreensRequest {
                points,
                actuators: (0..scene.actuators.len()).collect(),
                band_hz: (args.band_lo_hz, args.band_hi_hz),
                duration_s: args.duration_s,
                sample_rate_hz: scene.daq.sample_rate_hz,
            };
            let summary =
                write_ground_truth(&scene, &options, &request, &args.out, args.force, args.cache.dir().as_deref())?;
            println!("{}", serde_json::to_string_pretty(&summary)?);
            Ok(())
        }
    }
}

fn frequencies(from_hz: f64, to_hz: f64, step_hz: f64) -> anyhow::Result<Vec<f64>> {
    if !(from_hz.is_finite()
        && to_hz.is_finite()
        && step_hz.is_finite()
        && from_hz > 0.0
        && to_hz >= from_hz
        && step_hz > 0.0)
    {
        bail!("need 0 < --from-hz <= --to-hz and --step-hz > 0, got {from_hz}, {to_hz}, {step_hz}");
    }
    let n = ((to_hz - from_hz) / step_hz + 1e-9).floor() as usize + 1;
    if n > 10_000 {
        bail!("{n} frequencies is more than 10000: use a larger --step-hz");
    }
    Ok((0..n).map(|i| from_hz + i as f64 * step_hz).collect())
}

/// The scene's measured points, or the measured points of an evenly spread NX x NY subset of its grid.
pub fn select_points(scene: &Scene, grid: Option<GridSubset>) -> anyhow::Result<Vec<usize>> {
    let mask = scene.grid_mask();
    let candidates = match grid {
        None => (0..scene.grid.len()).collect(),
        Some(subset) => subset.indices(&scene.grid).with_context(|| format!("--grid {subset}"))?,
    };
    let points: Vec<usize> = candidates.into_iter().filter(|&p| mask[p]).collect();
    if points.is_empty() {
        bail!("no measured point in the selected grid (every point is off the plate or under a support)");
    }
    Ok(points)
}

/// Per-frequency wavelength report of a scene (see `metaplate simulate dispersion`): the paper's k-space method
/// (`wavelength_m`, median over actuators, with its interquartile range and how many actuators' estimates fall outside
/// the method's resolved range), and the plate-equation estimate (`local_wavelength_m`), which resolves wavelengths as
/// long as the plate where the aperture-limited k-space method cannot.
pub fn dispersion(scene: &Scene, options: &ModelOptions, freqs: &[f64]) -> anyhow::Result<Value> {
    let model = PlateModel::from_scene(scene, options).context("discretising the plate")?;
    let layout = SceneLayout::new(scene);
    let actuators: Vec<usize> = (0..scene.actuators.len()).collect();
    let bar = progress::bar(freqs.len() as u64, "dispersion");
    let mut rows = Vec::with_capacity(freqs.len());
    for &f in freqs {
        let response = model.frequency_response(f, &actuators, &layout.points)?;
        let w = wavelengths_at(&response, actuators.len(), &layout.layout(), &DispersionOptions::default())?;
        let a0 = scene.plate.a0_wavelength_m(f)?;
        let summary = &w.k_space_summary;
        rows.push(json!({
            "freq_hz": f,
            "wavelength_m": summary.median_m,
            "iqr_m": [summary.iqr_m.0, summary.iqr_m.1],
            "actuators_flagged": summary.flagged,
            "per_actuator_m": w.k_space.iter().map(|e| e.median_m).collect::<Vec<_>>(),
            "local_wavelength_m": w.local_summary.as_ref().map(|l| l.wavelength_m),
            "a0_wavelength_m": a0,
            "a0_over_wavelength": a0 / summary.median_m,
        }));
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(json!({
        "scene": scene.name,
        "scene_hash": scene.id().hash,
        "method": "k-space (the paper's): 2-D FFT of each actuator's field over the measured grid, half-maximum region \
                   around the peak, median over actuators; local: plate-equation (biharmonic Rayleigh quotient) estimate",
        "points": rows,
    }))
}

fn print_dispersion(report: &Value) {
    println!(
        "{:>8}  {:>11}  {:>11}  {:>10}  {:>9}  k-space flagged",
        "f (Hz)", "k-space (cm)", "local (cm)", "A0 (cm)", "A0/k-space"
    );
    for p in report["points"].as_array().into_iter().flatten() {
        let cm = |k: &str| p[k].as_f64().unwrap_or(f64::NAN) * 100.0;
        println!(
            "{:>8.1}  {:>11.2}  {:>11.2}  {:>10.2}  {:>9.2}  {}",
            p["freq_hz"].as_f64().unwrap_or(f64::NAN),
            cm("wavelength_m"),
            cm("local_wavelength_m"),
            cm("a0_wavelength_m"),
            p["a0_over_wavelength"].as_f64().unwrap_or(f64::NAN),
            p["actuators_flagged"]
        );
    }
}

/// Computes the Green's functions of `request` and writes them as a dataset in `out` (status "ground-truth").
/// Returns a JSON summary.
pub fn write_ground_truth(
    scene: &Scene,
    options: &ModelOptions,
    request: &GreensRequest,
    out: &Path,
    force: bool,
    cache_dir: Option<&Path>,
) -> anyhow::Result<Value> {
    let started = std::time::Instant::now();
    let spinner =
        progress::spinner(format!("computing {} points x {} actuators", request.points.len(), request.actuators.len()));
    let greens = metaplate_plate::greens_functions(scene, options, request, cache_dir)?;
    spinner.finish_and_clear();
    let compute_s = started.elapsed().as_secs_f64();
    let config = json!({
        "band_hz": [request.band_hz.0, request.band_hz.1],
        "duration_s": request.duration_s,
        "sample_rate_hz": request.sample_rate_hz,
        "refinement": options.refinement,
        "points": request.points.len(),
        "actuators": request.actuators,
        "units": "plate normal velocity per unit actuator force, m/s/N, as a discrete-time filter",
    });
    let Value::Object(config) = config else { bail!("internal: configuration is not a JSON object") };
    let meta =
        DatasetMeta::new("simulate-greens", config, scene.id(), env!("CARGO_PKG_VERSION"), scene.seed, scene.grid)
            .with_description(DatasetDescription { ir_unit: IR_UNIT_M_S_PER_N.into(), pre_samples: 0 });
    let if_exists = if force { IfExists::Replace } else { IfExists::Refuse };
    let mut writer = DatasetWriter::create(out, meta, if_exists)
        .with_context(|| format!("creating dataset {} (use --force to replace one)", out.display()))?;
    let bar = progress::bar(greens.points.len() as u64, "writing");
    for chunk in (0..greens.points.len()).collect::<Vec<_>>().chunks(BATCH_POINTS) {
        let records = records(scene, &greens, chunk)?;
        writer.commit_batch(&records)?;
        bar.inc(chunk.len() as u64);
    }
    bar.finish_and_clear();
    let manifest = writer.finish()?;
    Ok(json!({
        "dataset": out.display().to_string(),
        "scene": scene.name,
        "points": greens.points.len(),
        "actuators": greens.actuators.len(),
        "ir_len": greens.ir_len,
        "sample_rate_hz": greens.sample_rate_hz,
        "batches": manifest.batches.len(),
        "compute_s": compute_s,
        "total_s": started.elapsed().as_secs_f64(),
    }))
}

/// Points per committed batch file: about 40 MB of f32 impulse responses at 0.5 s and 24 kHz.
const BATCH_POINTS: usize = 100;

fn records(scene: &Scene, greens: &GreensFunctions, point_ks: &[usize]) -> anyhow::Result<Vec<IrRecord>> {
    let mut out = Vec::with_capacity(point_ks.len() * greens.actuators.len());
    for &pk in point_ks {
        let (ix, iy) = scene.grid.indices(greens.points[pk]);
        for (ak, &actuator) in greens.actuators.iter().enumerate() {
            let ir = greens.ir(pk, ak).context("internal: Green's function index out of range")?;
            let mut meta = IrMeta::at_grid(
                &scene.grid,
                u32::try_from(ix)?,
                u32::try_from(iy)?,
                u16::try_from(actuator)?,
                greens.sample_rate_hz,
            )?;
            meta.status = Some(Status::GroundTruth);
            out.push(IrRecord { meta, ir: ir.iter().map(|&v| v as f32).collect() });
        }
    }
    Ok(out)
}

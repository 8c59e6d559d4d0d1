//! `metaplate demo`: the main job, on the built-in simulated plates, with no hardware and no arguments.
//!
//! For each built-in plate (metamaterial, homogeneous), on the mock lab (the real drivers over mock devices, on a
//! virtual clock, so hours of measurement take minutes):
//! 1. dispersion of the plate model by the paper's k-space method, against the paper's measured wavelengths;
//! 2. `calibrate`: the calibration recipe on all 8 actuators (sweep on each magnet, Kirkeby inverse filter,
//!    verification through it), into `DIR/<plate>/calibration`;
//! 3. `scan`: the scan recipe with that calibration over a reduced grid by default (every other point, the quick
//!    protocol) or, with `--full`, the paper's full grid and protocol, into `DIR/<plate>/scan`; the measured Green's
//!    functions are compared with the lab's ground truth (through the calibration's filters);
//! 4. the analyses of `metaplate analyze` on the scanned dataset (the same code), with their figures in
//!    `DIR/<plate>/figures` (PNG and SVG);
//! 5. a 5-pixel pattern (5 distinct targets, one of them a null), solved on the scanned dataset, compensated by the
//!    calibration's filters and peak-normalised, as `metaplate focus` renders it: `DIR/<plate>/pattern.wav`.
//!
//! It prints the paper-against-suite table (DESIGN.md section 6), writes everything in `DIR/summary.json` and the
//! same as one self-contained page in `DIR/report.html` (see `metaplate report`).
//! Progress goes to stderr.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use indicatif::ProgressBar;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_plate::ModelOptions;
use metaplate_recipes::calibrate::ActuatorCalibration;
use metaplate_recipes::{
    Calibration, CalibrationConfig, Event, Observer, Output, RunControl, ScanConfig, ScanPlan, ScanSummary, calibrate,
    scan,
};
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::cache::CacheArgs;
use crate::focus::{PixelSpec, RenderOptions, render};
use crate::{analyze, paper_table, progress, report, simulate, truth, wav};

/// Arguments of `metaplate demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Output directory (created; an earlier demo's results in it are replaced).
    #[arg(long, default_value = "metaplate-demo")]
    out: PathBuf,
    /// The paper's full 49 x 25 grid and protocol (5 x 3 s sweeps) instead of a 25 x 13 grid and the quick protocol.
    #[arg(long)]
    full: bool,
    /// Seed of the simulated lab (noise, speckle, actuator spread) and of the recipes' choices.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    cache: CacheArgs,
    /// Scan grid NXxNY (a subset of the plate's grid), for tests.
    #[arg(long, hide = true, conflicts_with = "full")]
    grid: Option<String>,
}

/// The default scan grid: every other point of the paper's 49 x 25 (1 cm spacing: 4 points per wavelength at
/// 600 Hz; the 3.5 x 3.5 cm authority domain, centred on the lattice point at the plate centre, holds 3 x 3 points).
const DEFAULT_GRID: (usize, usize) = (25, 13);

/// The pattern: positions as fractions of the measured area (-1..1 each way) and targets (`metaplate focus`
/// syntax; times in s from the start of the 1 s drive, whose focus time is 0.5 s).
const PATTERN: [((f64, f64), &str); 5] = [
    ((0.0, 0.0), "impulse"),
    ((-0.6, 0.5), "sine@200,0.4,0.2"),
    ((0.6, 0.5), "wavelets@250,3,0.42,0.5,0.58"),
    ((-0.6, -0.5), "noise@0.4,0.2,7"),
    ((0.6, -0.5), "null"),
];

/// Runs the demo.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let started = std::time::Instant::now();
    let subset = match (&args.grid, args.full) {
        // The wavelength estimate needs a two-dimensional field.
        (Some(text), _) => Some(text.parse::<GridSubset>()?.at_least(2)?.into()),
        (None, true) => None,
        (None, false) => Some(DEFAULT_GRID),
    };
    let protocol = ExcitationProtocol::by_name(if args.full { "paper" } else { "quick" })?;
    let mut plates = serde_json::Map::new();
    for name in ["metamaterial", "homogeneous"] {
        let scene = Scene::builtin(name)?;
        let dir = args.out.join(name);
        let plate = run_plate(&scene, &dir, subset, &protocol, args)?;
        plates.insert(name.into(), plate);
    }
    // Both plates on shared axes (wavelength with A0 and the paper's points; condition numbers with the paper's).
    let analyses = ["metamaterial", "homogeneous"].map(|name| (name, &plates[name]["analysis"]));
    let comparison = analyze::write_comparison_figures(&args.out.join("figures"), &analyses)?;
    let summary = json!({
        "comparison_figures": comparison.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "plates": plates,
        "scan_grid": subset.map_or_else(|| json!("full"), |(nx, ny)| json!([nx, ny])),
        "protocol": protocol.name,
        "seed": args.seed,
        "wall_time_s": started.elapsed().as_secs_f64(),
    });
    paper_table::print(&summary);
    let path = args.out.join("summary.json");
    fs::write(&path, serde_json::to_string_pretty(&summary)?).with_context(|| format!("writing {}", path.display()))?;
    let report_path = args.out.join("report.html");
    report::write(&report_path, &summary)?;
    println!("\nwrote {} and the datasets, figures and patterns under {}", path.display(), args.out.display());
    println!("the report (open it in a browser): {}", report_path.display());
    Ok(())
}

/// `NXxNY` as two counts.
/// Everything the demo does on one plate, as its part of the summary.
fn run_plate(
    scene: &Scene,
    dir: &Path,
    subset: Option<(usize, usize)>,
    protocol: &ExcitationProtocol,
    args: &DemoArgs,
) -> anyhow::Result<Value> {
    let name = scene.name.clone();
    let spinner = progress::spinner(format!("[{name}] dispersion of the plate model"));
    let dispersion = simulate::dispersion(scene, &ModelOptions::default(), &paper_table::DISPERSION_FREQS_HZ)?;
    spinner.finish_and_clear();

    let plan = ScanPlan::new(scene.grid, &scene.grid_mask(), subset)?;
    let n_act = scene.actuators.len();
    // The scanned points and the actuators' driving points (where calibration aims the beam).
    let mut points = plan.points.clone();
    points.extend((0..n_act).map(|k| scene.grid.len() + k));
    let options = LabOptions {
        seed: Some(args.seed),
        cache_dir: args.cache.dir(),
        points: Some(points),
        ..LabOptions::default()
    };
    let spinner = progress::spinner(format!(
        "[{name}] the mock lab: Green's functions of {} points x {n_act} actuators",
        plan.points.len() + n_act
    ));
    let lab = MockLab::new(scene, &options)?;
    spinner.finish_and_clear();
    let mut rig = lab.rig()?;
    let control = RunControl::new();

    let calibration_dir = fresh_dir(&dir.join("calibration"))?;
    let sites_m: Vec<(f64, f64)> = scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect();
    let cal_cfg = CalibrationConfig { seed: args.seed, ..CalibrationConfig::default() };
    let mut bar = Progress::new(format!("[{name}] calibrate"));
    let calibrated = calibrate(&mut rig, &sites_m, &cal_cfg, &output(&calibration_dir, scene), &control, &mut bar)?;
    bar.finish();
    let calibration = Calibration::load(&calibration_dir, n_act)?;

    let scan_dir = fresh_dir(&dir.join("scan"))?;
    let scan_cfg = ScanConfig { protocol: protocol.clone(), seed: args.seed, ..ScanConfig::default() };
    let mut bar = Progress::new(format!("[{name}] scan"));
    let scan_started = std::time::Instant::now();
    let summary = scan(&mut rig, &plan, Some(&calibration), &scan_cfg, &output(&scan_dir, scene), &control, &mut bar)?;
    bar.finish();
    let scan_wall_s = scan_started.elapsed().as_secs_f64();

    let spinner = progress::spinner(format!("[{name}] measured against true Green's functions"));
    let dataset = Dataset::open(&scan_dir).with_context(|| format!("opening {}", scan_dir.display()))?;
    let errors = truth::greens_errors(&lab, &dataset, Some(&calibration.filters))?;
    spinner.finish_and_clear();

    let spinner = progress::spinner(format!("[{name}] analyses and figures"));
    let analysis = analyze::analyse_dataset(&scan_dir, Some(&dir.join("figures")), None)?;
    spinner.finish_and_clear();

    let pattern = render_pattern(&dataset, &calibration_dir, &dir.join("pattern.wav"))?;
    Ok(json!({
        "dispersion": dispersion,
        "calibration": calibration_json(&calibration_dir, &calibrated),
        "scan": scan_json(&scan_dir, &summary, scan_wall_s, &errors),
        "analysis": analysis,
        "pattern": pattern,
    }))
}

/// Removes an earlier demo's dataset in `dir` (only what the demo writes there) and returns the directory.
fn fresh_dir(dir: &Path) -> anyhow::Result<PathBuf> {
    if dir.exists() {
        fs::remove_dir_all(dir).with_context(|| format!("removing the earlier {}", dir.display()))?;
    }
    Ok(dir.to_path_buf())
}

fn output(dir: &Path, scene: &Scene) -> Output {
    Output {
        dir: dir.to_path_buf(),
        scene: scene.id(),
        software_version: env!("CARGO_PKG_VERSION").into(),
        resume: false,
        force: false,
        preflight: None,
    }
}

/// A recipe observer drawing a progress bar on stderr.
struct Progress {
    label: String,
    bar: Option<ProgressBar>,
}

impl Progress {
    fn new(label: String) -> Self {
        Self { label, bar: None }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Observer for Progress {
    fn event(&mut self, event: &Event) {
        match event {
            Event::Started { total, done, .. } => {
                let bar = progress::bar(*total as u64, &self.label);
                bar.set_position(*done as u64);
                self.bar = Some(bar);
            }
            Event::Committed { done, snr_db, clock_s, .. } => {
                if let Some(bar) = &self.bar {
                    bar.set_position(*done as u64);
                    let snr = snr_db.map_or_else(String::new, |s| format!(", SNR {s:.0} dB"));
                    bar.set_message(format!("{} ({:.2} h simulated{snr})", self.label, clock_s / 3600.0));
                }
            }
            Event::Stopped { .. } | Event::Finished { .. } => self.finish(),
            Event::Retry { .. }
            | Event::Recovered { .. }
            | Event::Paused { .. }
            | Event::ReferenceChecked { .. }
            | Event::Phase { .. } => {}
        }
    }
}

fn calibration_json(dir: &Path, calibrated: &[ActuatorCalibration]) -> Value {
    json!({
        "dir": dir.display().to_string(),
        "actuators": calibrated.iter().map(|c| json!({
            "actuator": c.actuator,
            "status": c.status.as_str(),
            "attempts": c.attempts,
            "flatness_deviation_db": c.flatness.deviation_db(),
            "standard_flatness_deviation_db": c.standard_flatness.deviation_db(),
            "max_boost_db": c.filter.max_boost_db,
        })).collect::<Vec<_>>(),
    })
}

fn scan_json(dir: &Path, summary: &ScanSummary, wall_s: f64, errors: &[f64]) -> Value {
    json!({
        "dir": dir.display().to_string(),
        "points": summary.committed,
        "total": summary.total,
        "statuses": summary.statuses,
        "deferred": summary.deferred,
        "simulated_hours": summary.clock_s / 3600.0,
        "wall_s": wall_s,
        "speed_up": summary.clock_s / wall_s,
        "greens_error_db": truth::errors_json(errors),
    })
}

/// Renders the 5-pixel pattern on the scanned dataset through the calibration, writes it as a WAV file, and
/// returns what was played: the peak drive and the predicted peak velocity at each pixel.
fn render_pattern(dataset: &Dataset, calibration: &Path, wav_path: &Path) -> anyhow::Result<Value> {
    let grid = dataset.manifest().meta.grid;
    let positions: Vec<(f64, f64)> = dataset.points().iter().map(|&p| grid.position_m(p as usize)).collect();
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for &(x, y) in &positions {
        (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
    }
    let mut specs: Vec<PixelSpec> = Vec::new();
    for ((fx, fy), target) in PATTERN {
        let want = ((lo.0 + hi.0) / 2.0 + fx * (hi.0 - lo.0) / 2.0, (lo.1 + hi.1) / 2.0 + fy * (hi.1 - lo.1) / 2.0);
        // The measured point nearest the wanted position, so that the pixel is never in a gap of the scan.
        let Some(&(x_m, y_m)) = positions.iter().min_by(|a, b| {
            let d = |p: &(f64, f64)| (p.0 - want.0).powi(2) + (p.1 - want.1).powi(2);
            d(a).total_cmp(&d(b))
        }) else {
            bail!("the scanned dataset has no points");
        };
        specs.push(PixelSpec::from_text(x_m, y_m, target)?);
    }
    let rendered = render(dataset, &specs, Some(calibration), &RenderOptions::default())?;
    wav::write_f32(wav_path, dataset.sample_rate_hz(), &rendered.signals)?;
    let fields = rendered.field_at_pixels()?;
    let peak = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let pixels: Vec<Value> = specs
        .iter()
        .zip(&rendered.points)
        .zip(&fields)
        .map(|((s, p), v)| {
            json!({"x_m": s.x_m, "y_m": s.y_m, "point_index": p, "target": s.label, "peak_velocity_m_s": peak(v)})
        })
        .collect();
    Ok(json!({
        "wav": wav_path.display().to_string(),
        "channels": rendered.signals.len(),
        "samples": rendered.signals.first().map_or(0, Vec::len),
        "peak_drive": rendered.peak,
        "normalisation_factor": rendered.factor,
        "focus_s": rendered.focus_s,
        "pixels": pixels,
    }))
}

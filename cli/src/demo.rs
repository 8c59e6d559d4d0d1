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
//! It prints the paper-against-suite table (DESIGN.md section 6) and writes everything in `DIR/summary.json`.
//! Progress goes to stderr.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use indicatif::ProgressBar;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_dsp::kirkeby::KirkebyFilter;
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
use crate::{analyze, progress, simulate, wav};

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

/// Frequencies of the dispersion table, Hz: the paper's two measured points and the band between.
const DISPERSION_FREQS_HZ: [f64; 6] = [75.0, 150.0, 250.0, 400.0, 500.0, 600.0];

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
    print_table(&summary);
    let path = args.out.join("summary.json");
    fs::write(&path, serde_json::to_string_pretty(&summary)?).with_context(|| format!("writing {}", path.display()))?;
    println!("\nwrote {} and the datasets, figures and patterns under {}", path.display(), args.out.display());
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
    let dispersion = simulate::dispersion(scene, &ModelOptions::default(), &DISPERSION_FREQS_HZ)?;
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
    let errors = greens_errors(&lab, &dataset, &calibration.filters)?;
    spinner.finish_and_clear();

    let spinner = progress::spinner(format!("[{name}] analyses and figures"));
    let analysis = analyze::analyse_dataset(&scan_dir, Some(&dir.join("figures")))?;
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
            Event::Started { total, done } => {
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
            Event::Retry { .. } | Event::Recovered { .. } | Event::Paused { .. } | Event::ReferenceChecked { .. } => {}
        }
    }
}

/// Per measured row (point, actuator): the error of the measured response against the lab's truth through the
/// actuator's inverse filter ([`MockLab::response_error_db`] over [`ERROR_BAND_HZ`]), dB. Sorted ascending.
fn greens_errors(lab: &MockLab, dataset: &Dataset, filters: &[KirkebyFilter]) -> anyhow::Result<Vec<f64>> {
    let fs = dataset.sample_rate_hz();
    let mut errors = Vec::with_capacity(dataset.len());
    for &p in dataset.points() {
        for &a in dataset.actuators() {
            let Some(ir) = dataset.ir(p, a) else { continue };
            let ir: Vec<f64> = ir.iter().map(|v| f64::from(*v)).collect();
            let filter = filters.get(usize::from(a)).context("internal: no filter for an actuator")?;
            errors.push(lab.response_error_db(p as usize, usize::from(a), &ir, fs, ERROR_BAND_HZ, Some(filter))?);
        }
    }
    errors.retain(|e| e.is_finite());
    errors.sort_by(f64::total_cmp);
    Ok(errors)
}

/// The value at quantile `q` (0..=1) of sorted `values` (nearest rank), `None` when empty.
fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    sorted.get(((last as f64) * q).round() as usize).copied()
}

fn calibration_json(dir: &Path, calibrated: &[ActuatorCalibration]) -> Value {
    json!({
        "dir": dir.display().to_string(),
        "actuators": calibrated.iter().map(|c| json!({
            "actuator": c.actuator,
            "status": c.status.as_str(),
            "attempts": c.attempts,
            "flatness_deviation_db": c.flatness.deviation_db(),
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
        "greens_error_db": {
            "band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
            "rows": errors.len(),
            "median": quantile(errors, 0.5),
            "p95": quantile(errors, 0.95),
            "worst": errors.last(),
        },
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
        specs.push(PixelSpec { x_m, y_m, target: target.to_owned() });
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
            json!({"x_m": s.x_m, "y_m": s.y_m, "point_index": p, "target": s.target, "peak_velocity_m_s": peak(v)})
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

/// Prints the paper-against-suite table (DESIGN.md section 6) from the summary.
fn print_table(summary: &Value) {
    let plates = &summary["plates"];
    let disp = |plate: &str, f: f64| {
        plates[plate]["dispersion"]["points"]
            .as_array()
            .and_then(|ps| ps.iter().find(|p| p["freq_hz"].as_f64() == Some(f)))
            .and_then(|p| p["wavelength_m"].as_f64())
            .unwrap_or(f64::NAN)
    };
    let ratios: Vec<f64> =
        DISPERSION_FREQS_HZ.iter().map(|&f| disp("homogeneous", f) / disp("metamaterial", f)).collect();
    let (rmin, rmax) = ratios.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), &r| (a.min(r), b.max(r)));
    let a = |plate: &str| &plates[plate]["analysis"];
    let num = |v: &Value, digits: usize| v.as_f64().map_or_else(|| "-".to_owned(), |x| format!("{x:.digits$}"));
    let pair = |key: &str, digits: usize| {
        format!("{} / {}", num(&a("metamaterial")[key], digits), num(&a("homogeneous")[key], digits))
    };
    let keyed = |key: &str, edge: &str, digits: usize| {
        format!("{} / {}", num(&a("metamaterial")[key][edge], digits), num(&a("homogeneous")[key][edge], digits))
    };
    let row = |q: &str, paper: &str, suite: String| println!("{q:<46} {paper:>30}   {suite}");
    println!("\n{:<46} {:>30}   metaplate (metamaterial / homogeneous)", "quantity", "paper");
    row(
        "wavelength at 75 Hz, metamaterial (model)",
        "11.3 cm",
        format!("{:.1} cm", disp("metamaterial", 75.0) * 100.0),
    );
    row(
        "wavelength at 600 Hz, metamaterial (model)",
        "2.5 cm",
        format!("{:.1} cm", disp("metamaterial", 600.0) * 100.0),
    );
    row("homogeneous / metamaterial wavelength", "2.1 to 4.8", format!("{rmin:.1} to {rmax:.1}"));
    let area = |p: &str| a(p)["median_pixel_area_cm2"].as_f64();
    let ratio = match (area("metamaterial"), area("homogeneous")) {
        (Some(m), Some(h)) if m > 0.0 => format!(" ({:.1} x)", h / m),
        _ => String::new(),
    };
    row("median virtual-pixel area, cm^2", "2.74 / about 10 x", format!("{}{ratio}", pair("median_pixel_area_cm2", 2)));
    row("refresh, ms", "5 / -", pair("refresh_ms", 1));
    row("POD components for 99 %", "23 / 11", pair("pod_components_99", 0));
    // Authority depends on the lattice (how many points a domain holds): each side says its own, so that unlike
    // is not read as like. The paper's domains hold 361, 169 and 49 points of its 5 mm grid.
    let lattice = |key: &str, edge: &str| {
        let spacing_cm = a("metamaterial")["lattice"]["spacing_m"].as_f64().map_or(f64::NAN, |h| h * 100.0);
        format!("{} [{} pts, {spacing_cm:.1} cm]", keyed(key, edge, 1), a("metamaterial")["points_per_domain"][edge])
    };
    row("effective rank of G_D, d = 3.5 cm", "7.4 / 4.3 [49 pts, 0.5 cm]", lattice("effective_rank", "3.5"));
    for (edge, paper) in [
        ("9.5", "5.0 / 51.5 [361 pts, 0.5 cm]"),
        ("6.5", "10.1 / 110.6 [169 pts, 0.5 cm]"),
        ("3.5", "35.9 / 236.0 [49 pts, 0.5 cm]"),
    ] {
        row(&format!("mean condition number, d = {edge} cm"), paper, lattice("condition_number", edge));
    }
    let peak_mm_s = |p: &str| {
        plates[p]["pattern"]["pixels"]
            .as_array()
            .map(|px| px.iter().filter_map(|x| x["peak_velocity_m_s"].as_f64()).fold(0.0_f64, f64::max) * 1e3)
    };
    let show = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |x| format!("{x:.1}"));
    row(
        "peak velocity at a pixel (full-scale drive), mm/s",
        "> 10",
        format!("{} / {}", show(peak_mm_s("metamaterial")), show(peak_mm_s("homogeneous"))),
    );
    println!("\nthe measurement (mock lab, {} protocol):", summary["protocol"].as_str().unwrap_or("?"));
    for plate in ["metamaterial", "homogeneous"] {
        let s = &plates[plate]["scan"];
        let e = &s["greens_error_db"];
        let statuses = s["statuses"]
            .as_object()
            .map_or_else(String::new, |m| m.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "));
        let calibrated = plates[plate]["calibration"]["actuators"]
            .as_array()
            .map_or(0, |a| a.iter().filter(|c| c["status"] == "valid").count());
        println!(
            "  {plate}: {calibrated}/8 actuators calibrated; {} points ({statuses}), {} h simulated in {} s; Green's \
             functions against the truth: median {} dB, p95 {} dB; pattern peak drive {}",
            s["points"],
            num(&s["simulated_hours"], 2),
            num(&s["wall_s"], 0),
            num(&e["median"], 1),
            num(&e["p95"], 1),
            num(&plates[plate]["pattern"]["peak_drive"], 3),
        );
    }
}

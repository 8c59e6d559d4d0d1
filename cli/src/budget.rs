//! `metaplate budget`: the Green's-function error budget of a scene on the mock lab, per imperfection.
//!
//! For each variant of the scene that `metaplate_lab::budget::Budget::variants` lists (every imperfection off: the
//! processing floor; each imperfection alone; all on), the scan recipe runs one protocol over a subset of the grid
//! (fast-forward, raw drives, or through a calibration's filters with `--calibration DIR`), and every committed
//! Green's function is compared with the lab's ground truth over 80..600 Hz and its octave bands. The variants
//! share the plate's Green's functions (the imperfections are not the plate's), so only the first lab computes
//! them. The library does the arithmetic; this module runs the scans and prints.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_lab::budget::{BUDGET_BANDS_HZ, Budget, BudgetPart, ERROR_BAND_HZ, ErrorSummary, RowError};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPlan, scan};
use metaplate_recipes::{Calibration, RunControl, Silent};
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::cache::CacheArgs;
use crate::tradeoff::{scratch_output, tempfile_dir};

#[derive(Args)]
pub struct BudgetArgs {
    /// Built-in scene name or scene file.
    #[arg(long)]
    scene: String,
    /// The scan's excitation protocol.
    #[arg(long, default_value = "paper", long_help = crate::scan::protocol_help())]
    protocol: String,
    /// Grid subset NXxNY (evenly spread points of the scene's grid; masked points are skipped).
    #[arg(long, default_value = "5x3")]
    grid: String,
    /// Scan through this calibration's inverse filters (a `calibrate --scene` directory of the same scene), and
    /// compare with the truth through them.
    #[arg(long, conflicts_with = "uncalibrated")]
    calibration: Option<PathBuf>,
    /// Scan with raw drives (the default).
    #[arg(long)]
    uncalibrated: bool,
    /// Measure only these parts (comma-separated: `floor`, an imperfection's name such as `ldv-noise`, `all-on`);
    /// the additivity check needs the floor and all-on.
    #[arg(long)]
    only: Option<String>,
    /// Seed of the lab and the scan.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Replace the protocol's samples before time 0 of each response (the band limit's precursor; the response's
    /// length stays the same): 0 gives the one-sided responses of earlier versions (a -38 dB floor). For
    /// measuring the processing's own biases.
    #[arg(long)]
    pre_samples: Option<usize>,
    /// Replace the protocol's response length, samples (pre-samples included). For measuring the processing's own
    /// biases.
    #[arg(long)]
    ir_len: Option<usize>,
    /// Replace the protocol's deconvolution regularisation (relative to the excitation's peak power): 1e-3 was
    /// the linear sweeps' before (a -57 dB floor). For measuring the processing's own biases.
    #[arg(long)]
    regularisation: Option<f64>,
    #[command(flatten)]
    cache: CacheArgs,
    /// Print one JSON object on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
}

pub fn run(args: &BudgetArgs) -> anyhow::Result<()> {
    let scene = Scene::resolve(&args.scene).with_context(|| format!("loading scene {}", args.scene))?;
    let GridSubset { nx, ny } = args.grid.parse()?;
    let plan = ScanPlan::new(scene.grid, &scene.grid_mask(), Some((nx, ny)))?;
    let mut protocol = ExcitationProtocol::by_name(&args.protocol)?;
    if let Some(p) = args.pre_samples {
        protocol.deconv.pre_samples = p;
    }
    if let Some(n) = args.ir_len {
        protocol.deconv.ir_len = n;
    }
    if let Some(r) = args.regularisation {
        protocol.deconv.regularisation = r;
    }
    let calibration = match &args.calibration {
        Some(dir) => Some(
            Calibration::load(dir, scene.actuators.len())
                .with_context(|| format!("loading the calibration {}", dir.display()))?,
        ),
        None => None,
    };
    let mut variants = Budget::variants(&scene);
    if let Some(only) = &args.only {
        let wanted: Vec<&str> = only.split(',').map(str::trim).collect();
        if let Some(unknown) = wanted.iter().find(|w| !variants.iter().any(|(p, _)| p.name() == **w)) {
            let known: Vec<&str> = variants.iter().map(|(p, _)| p.name()).collect();
            bail!("--only: no part `{unknown}` in this scene's budget (it has {})", known.join(", "));
        }
        variants.retain(|(p, _)| wanted.contains(&p.name()));
    }
    // Each variant needs a lab of its own (a lab hands out one rig); a cache shares the plate's Green's functions.
    let scratch_cache = match args.cache.dir() {
        Some(_) => None,
        None => Some(tempfile_dir()?),
    };
    let options = LabOptions {
        seed: Some(args.seed),
        cache_dir: args.cache.dir().or_else(|| scratch_cache.clone()),
        points: Some(plan.points.clone()),
        ..LabOptions::default()
    };
    let mut parts = Vec::new();
    let total = variants.len();
    for (k, (part, variant)) in variants.into_iter().enumerate() {
        let started = std::time::Instant::now();
        let lab = MockLab::new(&variant, &options).context("building the mock lab")?;
        let rows = measure(&lab, &variant, &plan, &protocol, args.seed, calibration.as_ref())?;
        let summary = ErrorSummary::of(&rows)?;
        eprintln!(
            "budget [{}/{total}] {:<16} median {:>7.1} dB  p95 {:>7.1} dB  ({:.0} s)",
            k + 1,
            part.name(),
            summary.overall.median_db,
            summary.overall.p95_db,
            started.elapsed().as_secs_f64()
        );
        parts.push((part, rows));
    }
    if let Some(dir) = scratch_cache {
        let _ = std::fs::remove_dir_all(dir);
    }
    let out = to_json(&scene.name, &protocol.name, &plan, args.seed, calibration.is_some(), &parts)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(&out);
    }
    Ok(())
}

/// Scans `plan` with `protocol` on `lab` into a temporary directory; each committed row's error against the truth.
fn measure(
    lab: &MockLab,
    scene: &Scene,
    plan: &ScanPlan,
    protocol: &ExcitationProtocol,
    seed: u64,
    calibration: Option<&Calibration>,
) -> anyhow::Result<Vec<RowError>> {
    let (dir, out) = scratch_output(scene)?;
    let cfg = ScanConfig { protocol: protocol.clone(), seed, ..ScanConfig::default() };
    let mut rig = lab.rig()?;
    scan(&mut rig, plan, calibration, &cfg, &out, &RunControl::new(), &mut Silent)
        .with_context(|| format!("scanning {} with {}", scene.name, protocol.name))?;
    let dataset = Dataset::open(&dir)?;
    let filters: Option<&[KirkebyFilter]> = calibration.map(|c| c.filters.as_slice());
    let fs = dataset.sample_rate_hz();
    let pre_samples = dataset.manifest().meta.description.as_ref().map_or(0, |d| d.pre_samples as usize);
    let mut rows = Vec::with_capacity(dataset.len());
    for (row, meta) in dataset.rows().iter().enumerate() {
        let ir: Vec<f64> =
            dataset.row_ir(row).context("a row without its impulse response")?.iter().map(|v| f64::from(*v)).collect();
        let actuator = usize::from(meta.actuator);
        let filter = match filters {
            Some(f) => Some(f.get(actuator).context("no filter for an actuator")?),
            None => None,
        };
        rows.push(lab.row_error(meta.point_index as usize, actuator, &ir, pre_samples, fs, filter)?);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let expected = plan.points.len() * scene.actuators.len();
    if rows.len() != expected {
        bail!("{}: {} of {expected} rows measured", protocol.name, rows.len());
    }
    Ok(rows)
}

fn summary_json(s: &ErrorSummary) -> Value {
    json!({
        "median_db": s.overall.median_db,
        "p95_db": s.overall.p95_db,
        "rows": s.rows,
        "bands": BUDGET_BANDS_HZ.iter().zip(&s.bands).map(|(b, q)| json!({
            "band_hz": [b.0, b.1], "median_db": q.median_db, "p95_db": q.p95_db,
        })).collect::<Vec<_>>(),
    })
}

fn to_json(
    scene: &str,
    protocol: &str,
    plan: &ScanPlan,
    seed: u64,
    calibrated: bool,
    parts: &[(BudgetPart, Vec<RowError>)],
) -> anyhow::Result<Value> {
    let summary = |want: BudgetPart| -> anyhow::Result<Value> {
        match parts.iter().find(|(p, _)| *p == want) {
            Some((_, rows)) => Ok(summary_json(&ErrorSummary::of(rows)?)),
            None => Ok(Value::Null),
        }
    };
    let mut terms = Vec::new();
    for (part, rows) in parts {
        if let BudgetPart::Alone(_) = part {
            let mut t = summary_json(&ErrorSummary::of(rows)?);
            t["name"] = json!(part.name());
            terms.push(t);
        }
    }
    let additivity = match Budget::from_parts(parts) {
        Ok(b) => json!({
            "predicted_all_on_median_db": b.predicted_all_on_median_db(),
            "closure_db": b.closure_db(),
        }),
        Err(_) => Value::Null,
    };
    Ok(json!({
        "scene": scene,
        "protocol": protocol,
        "grid_points": plan.points.len(),
        "seed": seed,
        "calibrated": calibrated,
        "error_band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
        "floor": summary(BudgetPart::Floor)?,
        "terms": terms,
        "all_on": summary(BudgetPart::AllOn)?,
        "additivity": additivity,
    }))
}

fn print_table(out: &Value) {
    let bands: Vec<String> = BUDGET_BANDS_HZ.iter().map(|b| format!("{:.0}-{:.0} Hz", b.0, b.1)).collect();
    println!(
        "{} ({}, {} points, seed {}, {}): Green's-function error against the truth, dB (median / p95)",
        out["scene"].as_str().unwrap_or("?"),
        out["protocol"].as_str().unwrap_or("?"),
        out["grid_points"],
        out["seed"],
        if out["calibrated"].as_bool() == Some(true) { "calibrated" } else { "uncalibrated" }
    );
    println!("| part | 80-600 Hz | {} |", bands.join(" | "));
    println!("|---|---|{}", "---|".repeat(bands.len()));
    let row = |name: &str, v: &Value| {
        if v.is_null() {
            return;
        }
        let q = |v: &Value| {
            format!(
                "{:.1} / {:.1}",
                v["median_db"].as_f64().unwrap_or(f64::NAN),
                v["p95_db"].as_f64().unwrap_or(f64::NAN)
            )
        };
        let per_band: Vec<String> = v["bands"].as_array().map(|b| b.iter().map(q).collect()).unwrap_or_default();
        println!("| {name} | {} | {} |", q(v), per_band.join(" | "));
    };
    row("floor (all off)", &out["floor"]);
    for t in out["terms"].as_array().into_iter().flatten() {
        row(t["name"].as_str().unwrap_or("?"), t);
    }
    row("all on", &out["all_on"]);
    if let (Some(p), Some(c)) =
        (out["additivity"]["predicted_all_on_median_db"].as_f64(), out["additivity"]["closure_db"].as_f64())
    {
        println!("terms added as powers predict {p:.1} dB median all on; measured {c:+.1} dB from that");
    }
}

//! `metaplate budget`: the Green's-function error budget of a scene on the mock lab, per imperfection.
//!
//! For each variant of the scene that `metaplate_lab::budget::Budget::variants` lists (every imperfection off: the
//! processing floor; each imperfection alone; all on), the scan recipe runs one protocol over a subset of the grid
//! (fast-forward, raw drives, or through a calibration's filters with `--calibration DIR`), and every committed
//! Green's function is compared with the lab's ground truth over 80..600 Hz and its octave bands: the full truth,
//! and the truth as the stored window keeps it (the floor is judged by it; the truncation and, for two periods or
//! more of a periodic sweep, the aliasing are the truth's own, see `metaplate_lab::windowed_truth`). The variants
//! share the plate's Green's functions (the imperfections are not the plate's), so only the first lab computes
//! them. The library does the arithmetic; this module runs the scans and prints.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_lab::budget::{
    BUDGET_BANDS_HZ, Budget, BudgetPart, ERROR_BAND_HZ, ErrorSummary, PartErrors, Quantiles, RowError, splits,
};
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
        let summary = PartErrors::of(&rows)?;
        eprintln!(
            "budget [{}/{total}] {:<16} median {:>7.1} dB  p95 {:>7.1} dB (windowed truth {:>7.1} / {:>7.1})  ({:.0} s)",
            k + 1,
            part.name(),
            summary.full.overall.median_db,
            summary.full.overall.p95_db,
            summary.windowed.overall.median_db,
            summary.windowed.overall.p95_db,
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
    // The window the scan kept: the protocol's deconvolution (its band) at the recorder's rate, with the dataset's
    // own length and samples before time 0.
    let mut window = DeconvConfig { sample_rate_hz: fs, pre_samples, ..protocol.deconv };
    // Two periods or more are deconvolved periodically (every period a circular convolution: a response longer
    // than the period wraps its tail onto its start); one is deconvolved linearly over the whole recording, and
    // the interleaved scheme's one sweep too.
    let period_samples = match protocol.scheme {
        Scheme::Sequential | Scheme::Hadamard | Scheme::Staggered if protocol.repetitions() >= 2 => {
            Some((protocol.sweep.duration_s * fs).round() as usize)
        }
        _ => None,
    };
    let mut rows = Vec::with_capacity(dataset.len());
    for (row, meta) in dataset.rows().iter().enumerate() {
        let ir: Vec<f64> =
            dataset.row_ir(row).context("a row without its impulse response")?.iter().map(|v| f64::from(*v)).collect();
        window.ir_len = ir.len();
        let actuator = usize::from(meta.actuator);
        let filter = match filters {
            Some(f) => Some(f.get(actuator).context("no filter for an actuator")?),
            None => None,
        };
        rows.push(lab.row_error(meta.point_index as usize, actuator, &ir, &window, period_samples, filter)?);
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

fn quantiles_json(q: &Quantiles) -> Value {
    json!({"median_db": q.median_db, "p95_db": q.p95_db})
}

/// A part's summary against `main` (`"full"` or `"windowed"`), with the other truths beside it.
fn part_json(errors: &PartErrors, main_is_full: bool) -> Value {
    let (main, other, other_key) = if main_is_full {
        (&errors.full, &errors.windowed, "windowed_truth")
    } else {
        (&errors.windowed, &errors.full, "full_truth")
    };
    let mut v = summary_json(main);
    v[other_key] = summary_json(other);
    if let Some(p) = &errors.periodic {
        v["periodic_truth"] = summary_json(p);
    }
    v
}

fn to_json(
    scene: &str,
    protocol: &str,
    plan: &ScanPlan,
    seed: u64,
    calibrated: bool,
    parts: &[(BudgetPart, Vec<RowError>)],
) -> anyhow::Result<Value> {
    let summary = |want: BudgetPart, main_is_full: bool| -> anyhow::Result<Value> {
        match parts.iter().find(|(p, _)| *p == want) {
            Some((_, rows)) => Ok(part_json(&PartErrors::of(rows)?, main_is_full)),
            None => Ok(Value::Null),
        }
    };
    let floor_rows = parts.iter().find(|(p, _)| *p == BudgetPart::Floor).map(|(_, rows)| rows);
    let truncation = match floor_rows {
        Some(rows) => summary_json(&ErrorSummary::of(rows.iter().map(|r| &r.truncation))?),
        None => Value::Null,
    };
    let aliasing = match floor_rows.map(|rows| rows.iter().map(|r| r.aliasing.as_ref()).collect::<Option<Vec<_>>>()) {
        Some(Some(rows)) => summary_json(&ErrorSummary::of(rows)?),
        _ => Value::Null,
    };
    let mut terms = Vec::new();
    for (part, rows) in parts {
        if let BudgetPart::Alone(_) = part {
            let mut t = part_json(&PartErrors::of(rows)?, true);
            t["name"] = json!(part.name());
            terms.push(t);
        }
    }
    let mut additivity = match Budget::from_parts(parts) {
        Ok(b) => json!({
            "predicted_all_on_median_db": b.predicted_all_on_median_db(),
            "closure_db": b.closure_db(),
        }),
        Err(_) => json!({}),
    };
    if let Some(rows) = floor_rows {
        let (truncation_split, aliasing_split) = splits(rows)?;
        additivity["truncation_split_db"] = quantiles_json(&truncation_split);
        additivity["aliasing_split_db"] = aliasing_split.as_ref().map_or(Value::Null, quantiles_json);
    }
    Ok(json!({
        "scene": scene,
        "protocol": protocol,
        "grid_points": plan.points.len(),
        "seed": seed,
        "calibrated": calibrated,
        "error_band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
        "truths": {"floor": "windowed", "terms": "full", "all_on": "full"},
        "floor": summary(BudgetPart::Floor, false)?,
        "truncation": truncation,
        "aliasing": aliasing,
        "terms": terms,
        "all_on": summary(BudgetPart::AllOn, true)?,
        "additivity": additivity,
    }))
}

fn print_table(out: &Value) {
    let bands: Vec<String> = BUDGET_BANDS_HZ.iter().map(|b| format!("{:.0}-{:.0} Hz", b.0, b.1)).collect();
    println!(
        "{} ({}, {} points, seed {}, {}): Green's-function error, dB (median / p95)",
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
    row("floor (all off; against the windowed truth)", &out["floor"]);
    row("truncation (the truth outside the window)", &out["truncation"]);
    row("floor against the full truth", &out["floor"]["full_truth"]);
    row("aliasing (the truth wrapped by the period)", &out["aliasing"]);
    row("floor against the wrapped truth", &out["floor"]["periodic_truth"]);
    for t in out["terms"].as_array().into_iter().flatten() {
        row(t["name"].as_str().unwrap_or("?"), t);
    }
    row("all on", &out["all_on"]);
    row("all on against the windowed truth", &out["all_on"]["windowed_truth"]);
    let additivity = &out["additivity"];
    if let (Some(p), Some(c)) = (additivity["predicted_all_on_median_db"].as_f64(), additivity["closure_db"].as_f64()) {
        println!("terms added as powers predict {p:.1} dB median all on; measured {c:+.1} dB from that");
    }
    let split = |what: &str, v: &Value| {
        if let (Some(m), Some(p)) = (v["median_db"].as_f64(), v["p95_db"].as_f64()) {
            println!("{what}, row by row as powers: within {m:.2} dB median, {p:.2} dB p95");
        }
    };
    split("floor against the full truth = against the windowed truth + truncation", &additivity["truncation_split_db"]);
    split("floor against the windowed truth = against the wrapped truth + aliasing", &additivity["aliasing_split_db"]);
}

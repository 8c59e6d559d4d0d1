//! `metaplate tradeoff`: the speed/accuracy trade of the scan's excitation protocols, measured on the mock lab.
//!
//! For each protocol, the scan recipe runs on a subset of the scene's grid (fast-forward, with the scene's full
//! noise, clock drift and actuator nonlinearity, no calibration filters: raw drives), and the Green's functions
//! it commits are compared with the lab's ground truth (`MockLab::response_error_db`, band 80..600 Hz). Time per
//! point is rig-clock time as measured (beam moves, settling, playback, recording margins, re-measures), beside
//! the protocol's nominal playing time. The pixel area is the analysis crate's `pixel_area_map` on the measured
//! dataset: on a coarse subset grid most half-maximum contours reach the edge of the measured area and are not
//! counted, so it is `null` there (use a dense grid, 20 x 10 or more, for a meaningful number).
//!
//! Cost: the default (5 x 3 grid: 11 measurable points, 7 protocols) simulates about 40 minutes of rig time; in a
//! release build on 2 shared cores it took 59 s (metamaterial) and 35 s (homogeneous) with the Green's functions
//! already cached (--cache-dir), about 2 to 3 minutes when they must be computed.

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_dsp::stats::quantile;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPlan, scan};
use metaplate_recipes::{Output, RunControl, Silent};
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::cache::CacheArgs;
use crate::truth;

/// Protocols measured by default.
const DEFAULT_PROTOCOLS: &str =
    "paper,quick,sequential-exp:1x2,interleaved:2,hadamard:0.6x1,hadamard:1x2,adaptive:0.6x2@30/4";

/// Band of G(omega) for the pixel area, Hz (as `metaplate analyze`).
const G_BAND_HZ: (f64, f64) = (75.0, 400.0);

#[derive(Args)]
pub struct TradeoffArgs {
    /// Built-in scene name or scene file.
    #[arg(long)]
    scene: String,
    /// Grid subset NXxNY (evenly spread points of the scene's grid; masked points are skipped).
    #[arg(long, default_value = "5x3")]
    grid: String,
    /// Comma-separated excitation protocols (D sweep seconds >= 0.6, R periods per shot (>= 2 for adaptive), SNR
    /// dB).
    #[arg(long, default_value = DEFAULT_PROTOCOLS, long_help = crate::scan::protocol_help())]
    protocols: String,
    /// Seed of the lab and the scan.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    #[command(flatten)]
    cache: CacheArgs,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Write the time-against-error Pareto plot (PNG and SVG) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
}

/// One protocol's measured trade.
struct ProtocolTrade {
    name: String,
    time_per_point_s: f64,
    nominal_time_per_point_s: f64,
    scan_hours: f64,
    median_error_db: f64,
    p95_error_db: f64,
    median_pixel_area_cm2: Option<f64>,
    failed_rows: usize,
}

pub fn run(args: &TradeoffArgs) -> anyhow::Result<()> {
    let scene = Scene::resolve(&args.scene).with_context(|| format!("loading scene {}", args.scene))?;
    let GridSubset { nx, ny } = args.grid.parse()?;
    let mask = scene.grid_mask();
    let full_points = mask.iter().filter(|m| **m).count();
    let plan = ScanPlan::new(scene.grid, &mask, Some((nx, ny)))?;
    let protocols: Vec<ExcitationProtocol> =
        args.protocols.split(',').map(|n| ExcitationProtocol::by_name(n.trim())).collect::<Result<_, _>>()?;
    if protocols.is_empty() {
        bail!("no protocol given");
    }
    // Each protocol needs a lab of its own (a lab hands out one rig); without a cache every one would recompute the
    // same Green's functions, so a temporary cache shares them.
    let cache_dir = args.cache.dir();
    let scratch_cache = match &cache_dir {
        Some(_) => None,
        None => Some(tempfile_dir()?),
    };
    let options = LabOptions {
        seed: Some(args.seed),
        cache_dir: cache_dir.or_else(|| scratch_cache.clone()),
        points: Some(plan.points.clone()),
        ..LabOptions::default()
    };
    let mut rows = Vec::new();
    for protocol in protocols {
        let lab = MockLab::new(&scene, &options).context("building the mock lab")?;
        let m = measure(&lab, &scene, &plan, protocol, args.seed, full_points)?;
        if !args.json {
            eprintln!(
                "{:<28} {:>7.1} s/point (nominal {:>6.1})  {:>6.1} h  median {:>6.1} dB  p95 {:>6.1} dB",
                m.name, m.time_per_point_s, m.nominal_time_per_point_s, m.scan_hours, m.median_error_db, m.p95_error_db
            );
        }
        rows.push(m);
    }
    if let Some(dir) = scratch_cache {
        let _ = std::fs::remove_dir_all(dir);
    }
    let out = to_json(&scene.name, &plan, full_points, &rows);
    if let Some(dir) = &args.figures {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let points: Vec<metaplate_figures::TradeoffPoint> = rows
            .iter()
            .map(|m| metaplate_figures::TradeoffPoint {
                label: m.name.clone(),
                time_per_point_s: m.time_per_point_s,
                median_error_db: m.median_error_db,
            })
            .collect();
        let title = format!("{}: scan time against Green's-function error", scene.name);
        metaplate_figures::tradeoff(dir, "tradeoff", &points, &title)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{}", out["goal"]);
    }
    Ok(())
}

/// Scans `plan` with `protocol` on `lab` into a temporary directory and measures the result.
fn measure(
    lab: &MockLab,
    scene: &Scene,
    plan: &ScanPlan,
    protocol: ExcitationProtocol,
    seed: u64,
    full_points: usize,
) -> anyhow::Result<ProtocolTrade> {
    let (dir, out) = scratch_output(scene)?;
    let actuators = scene.actuators.len();
    let nominal = protocol.nominal_time_per_point_s(actuators);
    let name = protocol.name.clone();
    let cfg = ScanConfig { protocol, seed, ..ScanConfig::default() };
    let mut rig = lab.rig()?;
    let summary = scan(&mut rig, plan, None, &cfg, &out, &RunControl::new(), &mut Silent)
        .with_context(|| format!("scanning with {name}"))?;
    let dataset = Dataset::open(&dir)?;
    let errors = truth::greens_errors(lab, &dataset, None)?;
    if errors.len() != plan.points.len() * actuators {
        bail!("{name}: {} of {} rows compare with the truth", errors.len(), plan.points.len() * actuators);
    }
    let (Some(median_error_db), Some(p95_error_db)) =
        (quantile(&mut errors.clone(), 0.5), quantile(&mut errors.clone(), 0.95))
    else {
        bail!("{name}: no row to compare with the truth");
    };
    let failed_rows = summary.statuses.get("failed").copied().unwrap_or(0);
    let pixel = median_pixel_area(&dataset, plan);
    let time_per_point_s = summary.clock_s / plan.points.len() as f64;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(ProtocolTrade {
        name,
        time_per_point_s,
        nominal_time_per_point_s: nominal,
        scan_hours: time_per_point_s * full_points as f64 / 3600.0,
        median_error_db,
        p95_error_db,
        median_pixel_area_cm2: pixel,
        failed_rows,
    })
}

/// Median pixel area of the measured dataset, cm^2; `None` when no contour closes (coarse grids) or it fails.
fn median_pixel_area(dataset: &Dataset, plan: &ScanPlan) -> Option<f64> {
    let g = PropagationMatrices::from_dataset(dataset, G_BAND_HZ, None).ok()?;
    let mut mask = vec![false; plan.grid.len()];
    for &p in &plan.points {
        mask[p] = true;
    }
    pixel_area_map(&g, &plan.grid, &mask, &PixelAreaOptions::default()).ok()?.median_area_cm2()
}

/// A fresh run directory for a scan of `scene` on the mock lab, and the scan's output there (a new run).
pub(crate) fn scratch_output(scene: &Scene) -> anyhow::Result<(PathBuf, Output)> {
    let dir = tempfile_dir()?;
    let out = Output {
        dir: dir.clone(),
        scene: scene.id(),
        software_version: env!("CARGO_PKG_VERSION").into(),
        resume: false,
        force: false,
        preflight: None,
    };
    Ok((dir, out))
}

/// A fresh directory under the system's temporary directory.
pub(crate) fn tempfile_dir() -> anyhow::Result<PathBuf> {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let dir = std::env::temp_dir().join(format!("metaplate-tradeoff-{}-{nanos}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

fn to_json(scene: &str, plan: &ScanPlan, full_points: usize, rows: &[ProtocolTrade]) -> Value {
    let paper = rows.iter().find(|m| m.name == "paper");
    // The fastest protocol that reaches the paper's median error (within 0.5 dB: two draws of the same noise
    // differ by about that much on a small grid) in a fifth of its time per point or less.
    let goal = paper.and_then(|p| {
        rows.iter()
            .filter(|m| m.name != "paper" && m.failed_rows == 0)
            .filter(|m| m.median_error_db <= p.median_error_db + 0.5 && m.time_per_point_s * 5.0 <= p.time_per_point_s)
            .min_by(|a, b| a.time_per_point_s.total_cmp(&b.time_per_point_s))
            .map(|m| {
                let speedup = p.time_per_point_s / m.time_per_point_s;
                json!({ "protocol": m.name, "speedup": speedup, "fraction_of_8x_limit": speedup / 8.0,
                        "paper_median_error_db": p.median_error_db, "median_error_db": m.median_error_db })
            })
    });
    json!({
        "scene": scene,
        "grid_points_measured": plan.points.len(),
        "grid_points_full": full_points,
        "error_band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
        "protocols": rows.iter().map(|m| json!({
            "name": m.name,
            "time_per_point_s": m.time_per_point_s,
            "nominal_time_per_point_s": m.nominal_time_per_point_s,
            "scan_hours": m.scan_hours,
            "median_error_db": m.median_error_db,
            "p95_error_db": m.p95_error_db,
            "median_pixel_area_cm2": m.median_pixel_area_cm2,
            "failed_rows": m.failed_rows,
        })).collect::<Vec<_>>(),
        "goal": goal,
    })
}

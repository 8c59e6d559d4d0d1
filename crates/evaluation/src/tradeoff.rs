//! The speed/accuracy trade of the scan's excitation protocols, measured on the mock lab (`metaplate tradeoff`).
//!
//! For each protocol and seed, the scan recipe runs on a subset of the scene's grid (fast-forward, with the scene's
//! full noise, clock drift and actuator nonlinearity, no calibration filters: raw drives), and the Green's functions
//! it commits are compared with the lab's ground truth (`MockLab::response_error_db`, band 80..600 Hz). Time per
//! point is rig-clock time as measured (beam moves, aiming nudges, settling, playback, ring-out, recording margins,
//! re-measures after acquisition problems), beside the protocol's nominal playing time. The pixel area is the
//! analysis crate's `pixel_area_map` on the measured dataset: on a coarse subset grid most half-maximum contours
//! reach the edge of the measured area and are not counted, so it is `null` there (use a dense grid, 20 x 10 or
//! more, for a meaningful number).
//!
//! Over several seeds each figure is the mean over the seeds with a Student-t 95 % interval ([`fit`]). A series
//! (one scheme, increasing excitation time, typically doubling) gets its error's slope per doubling of excitation
//! time, step by step, and fitted over its noise-limited run (the leading steps within 1 dB of -3 dB per
//! doubling). The ratio is the paper protocol's time per point over the time per point at which the best
//! simultaneous protocol reaches the paper's median error, per seed ([`fit::time_to_reach`] along each family of
//! one simultaneous scheme; an adaptive protocol counts alone), then its mean and interval ([`report`]).
//!
//! **The scan's SNR gate is off here by default** (`min_snr_db` turns it on). The gate re-measures a row whose SNR
//! *estimate* is below 20 dB, and the estimates differ by scheme: a sequential row's is the spread of its own
//! periods, a Hadamard row's the shots' spread divided by their number, and a Hadamard protocol of one period has
//! none (never gated). On a plate where noise sets the error, the gate therefore re-measures the paper protocol's
//! weak rows and not a Hadamard protocol's equally noisy ones, adding time to one protocol and not the other, and a
//! re-measure replaces the row with a later visit's, so error and time would measure the gate rather than the
//! protocol. Without it every protocol measures each point once (re-measures after clipping or a dropout remain:
//! they strike each playback alike, so they cost every protocol the same share of its time). The aiming nudges
//! stay: they are keyed by seed, point and visit alone, so every protocol pays the same moves per point.
//!
//! Cost: the default (5 x 3 grid: 11 measurable points, 7 protocols, one seed) simulates about 40 minutes of rig
//! time; in a release build on 2 shared cores it took about a minute per scene with the Green's functions already
//! cached, 2 to 3 minutes when they must be computed. The paper protocol's scans cost the most.

pub mod families;
pub mod fit;
pub mod report;
pub mod trade;

use std::fmt;
use std::path::{Path, PathBuf};

use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_dsp::stats::quantile;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPoints, scan};
use metaplate_recipes::{RunControl, Silent};
use metaplate_store::Dataset;

use crate::error::{EvaluationError, StepExt, io_error};
use crate::scratch::{scratch_dir, scratch_output};
use crate::truth::greens_errors;
use report::TradeoffReport;
use trade::{ProtocolTrade, SeedTrade};

/// Protocols measured by default.
pub const DEFAULT_PROTOCOLS: &str =
    "paper,quick,sequential-exp:1x2,interleaved:2,hadamard:0.6x1,hadamard:1x2,adaptive:0.6x2@30/4";

/// Band of G(omega) for the pixel area, Hz (as `metaplate analyze`'s pixel area).
const G_BAND_HZ: (f64, f64) = (75.0, 400.0);

/// What a trade measures.
#[derive(Debug, Clone)]
pub struct TradeoffRequest<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The grid subset scanned.
    pub grid: GridSubset,
    /// Comma-separated protocol names.
    pub protocols: &'a str,
    /// The seeds, each protocol scanned once per seed.
    pub seeds: &'a [u64],
    /// Series: each a comma-separated family of one scheme in order of increasing excitation time (a member without
    /// a scheme takes the previous one's).
    pub series: &'a [String],
    /// The scan's SNR gate, dB (off when `None`).
    pub min_snr_db: Option<f64>,
    /// The Green's-function cache (a temporary one shared by the scans when `None`).
    pub cache_dir: Option<&'a Path>,
}

/// One scan measured, as the trade reports its progress.
#[derive(Debug, Clone)]
pub struct ScanMeasured<'a> {
    /// 1-based.
    pub index: usize,
    /// Scans to make.
    pub total: usize,
    /// The protocol.
    pub protocol: &'a str,
    /// Its nominal time per point, s.
    pub nominal_time_per_point_s: f64,
    /// What the scan measured.
    pub trade: &'a SeedTrade,
    /// Wall time of the scan and its comparison, s.
    pub elapsed_s: f64,
}

impl fmt::Display for ScanMeasured<'_> {
    /// The progress line `tradeoff [k/n] seed S protocol  .. s/point (nominal ..)  median .. dB  p95 .. dB  (.. s)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "tradeoff [{}/{}] seed {} {:<24} {:>7.1} s/point (nominal {:>6.1})  median {:>6.1} dB  p95 {:>6.1} dB  \
             ({:.0} s)",
            self.index,
            self.total,
            self.trade.seed,
            self.protocol,
            self.trade.time_per_point_s,
            self.nominal_time_per_point_s,
            self.trade.median_error_db,
            self.trade.p95_error_db,
            self.elapsed_s
        )
    }
}

/// Parses a comma-separated list of seeds.
///
/// # Errors
/// A seed that is not a number, or a repeated seed.
pub fn parse_seeds(list: &str) -> Result<Vec<u64>, EvaluationError> {
    let seeds: Vec<u64> = list
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<u64>()
                .map_err(|e| EvaluationError::Invalid(format!("--seeds: `{}` is not a seed: {e}", s.trim())))
        })
        .collect::<Result<_, _>>()?;
    let mut unique = seeds.clone();
    unique.sort_unstable();
    unique.dedup();
    if unique.len() != seeds.len() {
        return Err(EvaluationError::Invalid(format!("--seeds: a seed is repeated ({list})")));
    }
    Ok(seeds)
}

/// Expands a series' members: one without a scheme (`0.6x2`) takes the previous member's (`hadamard:`).
///
/// # Errors
/// A member without a scheme and no member before it naming one.
pub fn series_names(list: &str) -> Result<Vec<String>, EvaluationError> {
    let mut prefix: Option<String> = None;
    let mut names = Vec::new();
    for item in list.split(',').map(str::trim) {
        match item.split_once(':') {
            Some((scheme, _)) => {
                prefix = Some(scheme.to_string());
                names.push(item.to_string());
            }
            None if item.starts_with(|c: char| c.is_ascii_digit()) => match &prefix {
                Some(p) => names.push(format!("{p}:{item}")),
                None => {
                    return Err(EvaluationError::Invalid(format!(
                        "--series: `{item}` has no scheme, and no member before it names one"
                    )));
                }
            },
            None => {
                prefix = None;
                names.push(item.to_string());
            }
        }
    }
    Ok(names)
}

/// Seconds of excitation each actuator receives per point and round: its periods in the shots it plays in.
fn excitation_per_actuator_s(protocol: &ExcitationProtocol, actuators: usize) -> Result<f64, EvaluationError> {
    let shots = protocol.shots(actuators).step(|| format!("the shots of {}", protocol.name))?;
    let playing = shots.iter().filter(|s| s.gains.first().is_some_and(|g| *g != 0.0)).count();
    Ok(playing as f64 * protocol.repetitions() as f64 * protocol.sweep().duration_s)
}

/// Measures the trade: every protocol (the listed ones, then the series' members not listed) scanned once per
/// seed, `on_scan` told after each.
///
/// # Errors
/// A protocol or series that does not parse, no protocol, a grid that does not fit the scene, a scan that fails or
/// whose rows do not all compare with the truth.
pub fn measure_tradeoff(
    request: &TradeoffRequest<'_>,
    on_scan: &mut dyn FnMut(&ScanMeasured<'_>),
) -> Result<TradeoffReport, EvaluationError> {
    let scene = request.scene;
    let GridSubset { nx, ny } = request.grid;
    let mask = scene.grid_mask();
    let full_points = mask.iter().filter(|m| **m).count();
    let plan = ScanPoints::new(scene.grid, &mask, Some((nx, ny))).step(|| "planning the scan".into())?;
    let series: Vec<Vec<String>> = request.series.iter().map(|s| series_names(s)).collect::<Result<_, _>>()?;
    let mut names: Vec<String> = request.protocols.split(',').map(|n| n.trim().to_string()).collect();
    for name in series.iter().flatten() {
        if !names.contains(name) {
            names.push(name.clone());
        }
    }
    let actuators = scene.actuators.len();
    let mut trades = Vec::new();
    for name in &names {
        let protocol = ExcitationProtocol::by_name(name)?;
        trades.push(ProtocolTrade {
            excitation_s: protocol.time_per_point_s(actuators, 0.0),
            excitation_per_actuator_s: excitation_per_actuator_s(&protocol, actuators)?,
            nominal_time_per_point_s: protocol.nominal_time_per_point_s(actuators),
            protocol,
            per_seed: Vec::new(),
        });
    }
    if trades.is_empty() {
        return Err(EvaluationError::Invalid("no protocol given".into()));
    }
    // Each scan needs a lab of its own (a lab hands out one rig); without a cache every one would recompute the
    // same Green's functions, so a temporary cache shares them.
    let scratch_cache: Option<PathBuf> = match request.cache_dir {
        Some(_) => None,
        None => Some(scratch_dir()?),
    };
    let runs = request.seeds.len() * trades.len();
    let mut k = 0;
    for &seed in request.seeds {
        let options = LabOptions {
            seed: Some(seed),
            cache_dir: request.cache_dir.map(Path::to_path_buf).or_else(|| scratch_cache.clone()),
            points: Some(plan.points.clone()),
            ..LabOptions::default()
        };
        for trade in &mut trades {
            k += 1;
            let started = std::time::Instant::now();
            let lab = MockLab::new(scene, &options).step(|| "building the mock lab".into())?;
            let m = measure(&lab, scene, &plan, &trade.protocol, seed, request.min_snr_db)?;
            on_scan(&ScanMeasured {
                index: k,
                total: runs,
                protocol: trade.name(),
                nominal_time_per_point_s: trade.nominal_time_per_point_s,
                trade: &m,
                elapsed_s: started.elapsed().as_secs_f64(),
            });
            trade.per_seed.push(m);
        }
    }
    if let Some(dir) = scratch_cache {
        let _ = std::fs::remove_dir_all(dir);
    }
    let series_trades: Vec<Vec<&ProtocolTrade>> = series
        .iter()
        .map(|family| family.iter().filter_map(|n| trades.iter().find(|t| t.name() == n)).collect())
        .collect();
    Ok(TradeoffReport::of(&scene.name, &plan, full_points, request.seeds, request.min_snr_db, &trades, &series_trades))
}

/// Writes the time-against-error Pareto plot (PNG and SVG, the seeds' means) of `report` into `dir` (created).
///
/// # Errors
/// The directory cannot be created or the figure written.
pub fn write_tradeoff_figure(dir: &Path, report: &TradeoffReport) -> Result<(), EvaluationError> {
    std::fs::create_dir_all(dir).map_err(io_error("creating", dir))?;
    let points: Vec<metaplate_figures::TradeoffPoint> = report
        .protocols
        .iter()
        .map(|p| metaplate_figures::TradeoffPoint {
            label: p.name.clone(),
            time_per_point_s: p.time_per_point_s,
            median_error_db: p.median_error_db,
        })
        .collect();
    let title = format!("{}: scan time against Green's-function error", report.scene);
    metaplate_figures::tradeoff(dir, "tradeoff", &points, &title)
        .step(|| format!("writing the Pareto plot in {}", dir.display()))?;
    Ok(())
}

/// Scans `plan` with `protocol` on `lab` into a temporary directory and measures the result; the SNR gate at
/// `min_snr_db`, or off (`None`: minus infinity).
fn measure(
    lab: &MockLab,
    scene: &Scene,
    plan: &ScanPoints,
    protocol: &ExcitationProtocol,
    seed: u64,
    min_snr_db: Option<f64>,
) -> Result<SeedTrade, EvaluationError> {
    let (dir, out) = scratch_output(scene)?;
    let actuators = scene.actuators.len();
    let name = protocol.name.clone();
    let cfg = ScanConfig {
        protocol: protocol.clone(),
        seed,
        min_snr_db: min_snr_db.unwrap_or(f64::NEG_INFINITY),
        ..ScanConfig::default()
    };
    let mut rig = lab.rig().step(|| "taking the lab's rig".into())?;
    let summary = scan(&mut rig, plan, None, &cfg, &out, &RunControl::new(), &mut Silent)
        .step(|| format!("scanning with {name}"))?;
    let dataset = Dataset::open(&dir).step(|| format!("opening the scan {}", dir.display()))?;
    let errors = greens_errors(lab, &dataset, None)?;
    if errors.len() != plan.points.len() * actuators {
        return Err(EvaluationError::Incomplete(format!(
            "{name}: {} of {} rows compare with the truth",
            errors.len(),
            plan.points.len() * actuators
        )));
    }
    let (Some(median_error_db), Some(p95_error_db)) =
        (quantile(&mut errors.clone(), 0.5), quantile(&mut errors.clone(), 0.95))
    else {
        return Err(EvaluationError::Incomplete(format!("{name}: no row to compare with the truth")));
    };
    let failed_rows = summary.statuses.get("failed").copied().unwrap_or(0);
    let pixel = median_pixel_area(&dataset, plan);
    let _ = std::fs::remove_dir_all(&dir);
    Ok(SeedTrade {
        seed,
        time_per_point_s: summary.clock_s / plan.points.len() as f64,
        median_error_db,
        p95_error_db,
        median_pixel_area_cm2: pixel,
        failed_rows,
    })
}

/// Median pixel area of the measured dataset, cm^2; `None` when no contour closes (coarse grids) or it fails.
fn median_pixel_area(dataset: &Dataset, plan: &ScanPoints) -> Option<f64> {
    let g = PropagationMatrices::from_dataset(dataset, G_BAND_HZ, None).ok()?;
    let mut mask = vec![false; plan.grid.len()];
    for &p in &plan.points {
        mask[p] = true;
    }
    pixel_area_map(&g, &plan.grid, &mask, &PixelAreaOptions::default()).ok()?.median_area_cm2()
}

//! `metaplate tradeoff`: the speed/accuracy trade of the scan's excitation protocols, measured on the mock lab.
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
//! Over several seeds (`--seeds`) each figure is the mean over the seeds with a Student-t 95 % interval (`fit`). A
//! series (`--series`: one scheme, increasing excitation time, typically doubling) gets its error's slope per
//! doubling of excitation time, step by step, and fitted over its noise-limited run (the leading steps within 1 dB
//! of -3 dB per doubling). The ratio is the paper protocol's time per point over the time per point at which the
//! best simultaneous protocol reaches the paper's median error, per seed (`fit::time_to_reach` along each family
//! of one simultaneous scheme; an adaptive protocol counts alone), then its mean and interval.
//!
//! **The scan's SNR gate is off here by default** (`--min-snr-db` turns it on). The gate re-measures a row whose
//! SNR *estimate* is below 20 dB, and the estimates differ by scheme: a sequential row's is the spread of its own
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
//! cached (--cache-dir), 2 to 3 minutes when they must be computed. The paper protocol's scans cost the most.

mod fit;

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use metaplate_dsp::stats::quantile;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPlan, scan};
use metaplate_recipes::{Output, RunControl, Silent};
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::cache::CacheArgs;
use crate::truth;
use fit::{Estimate, Member, Reach};

/// Protocols measured by default.
const DEFAULT_PROTOCOLS: &str =
    "paper,quick,sequential-exp:1x2,interleaved:2,hadamard:0.6x1,hadamard:1x2,adaptive:0.6x2@30/4";

/// Band of G(omega) for the pixel area, Hz (as `metaplate analyze`).
const G_BAND_HZ: (f64, f64) = (75.0, 400.0);

/// How far above the paper's median error a protocol may be and still count as reaching it, dB: two draws of the
/// same noise differ by about that much on a small grid. Used where the error is not set by the excitation time
/// (a family's fastest member already there, an adaptive protocol, the `goal`); within a family's noise-limited
/// range the target is reached exactly, by interpolation.
const REACH_TOLERANCE_DB: f64 = 0.5;

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
    /// Seed of the lab and the scan (one seed; see --seeds).
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Several seeds, comma-separated (e.g. `7,8,9,10,11`): every protocol is scanned once per seed, and each
    /// figure is the mean over the seeds with a Student-t 95 % interval (`*_ci95` keys; per seed under
    /// `per_seed`). Replaces --seed.
    #[arg(long, conflicts_with = "seed")]
    seeds: Option<String>,
    /// A family of protocols of one scheme in order of increasing excitation time, typically doubling, e.g.
    /// `hadamard:0.6x2,0.6x4,0.6x8,0.6x16` (a member without a scheme takes the previous one's); may be repeated.
    /// Measured as --protocols are; reported: the error's slope per doubling of excitation time step by step, its
    /// noise-limited run (the leading steps within 1 dB of -3 dB per doubling), the slope fitted over that run, and
    /// the step where the error departs from it (JSON `series`, one object per --series).
    #[arg(long)]
    series: Vec<String>,
    /// Turn on the scan's SNR gate at this many dB (the scan's default is 20): rows whose SNR estimate is below it
    /// are re-measured, at most twice. Off by default: the estimates differ by scheme, so on a noisy plate the gate
    /// re-measures some protocols and not others (see `metaplate tradeoff`'s module docs and the README).
    #[arg(long)]
    min_snr_db: Option<f64>,
    #[command(flatten)]
    cache: CacheArgs,
    /// Print one JSON object on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
    /// Write the time-against-error Pareto plot (PNG and SVG, the seeds' means) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
}

/// One protocol's measured trade with one seed.
#[derive(Debug, Clone, PartialEq)]
struct SeedTrade {
    seed: u64,
    time_per_point_s: f64,
    median_error_db: f64,
    p95_error_db: f64,
    median_pixel_area_cm2: Option<f64>,
    failed_rows: usize,
}

/// One protocol's trade over every seed.
#[derive(Debug, Clone)]
struct ProtocolTrade {
    protocol: ExcitationProtocol,
    /// Seconds of excitation per point and round (every shot's periods): what the noise averages over.
    excitation_s: f64,
    /// Seconds of excitation each actuator receives per point and round (the shots it plays in).
    excitation_per_actuator_s: f64,
    nominal_time_per_point_s: f64,
    per_seed: Vec<SeedTrade>,
}

impl ProtocolTrade {
    fn name(&self) -> &str {
        &self.protocol.name
    }

    fn estimate(&self, value: impl Fn(&SeedTrade) -> f64) -> Option<Estimate> {
        Estimate::of(&self.per_seed.iter().map(value).collect::<Vec<_>>())
    }

    /// The mean of a figure over the seeds (NaN only when there is no seed, which `run` never builds).
    fn mean(&self, value: impl Fn(&SeedTrade) -> f64) -> f64 {
        self.estimate(value).map_or(f64::NAN, |e| e.mean)
    }

    fn failed_rows(&self) -> usize {
        self.per_seed.iter().map(|s| s.failed_rows).sum()
    }

    fn seed(&self, seed: u64) -> Option<&SeedTrade> {
        self.per_seed.iter().find(|s| s.seed == seed)
    }
}

/// Parses a comma-separated list of seeds.
fn parse_seeds(list: &str) -> anyhow::Result<Vec<u64>> {
    let seeds: Vec<u64> = list
        .split(',')
        .map(|s| s.trim().parse::<u64>().with_context(|| format!("--seeds: `{}` is not a seed", s.trim())))
        .collect::<Result<_, _>>()?;
    let mut unique = seeds.clone();
    unique.sort_unstable();
    unique.dedup();
    if unique.len() != seeds.len() {
        bail!("--seeds: a seed is repeated ({list})");
    }
    Ok(seeds)
}

/// Expands a series' members: one without a scheme (`0.6x2`) takes the previous member's (`hadamard:`).
fn series_names(list: &str) -> anyhow::Result<Vec<String>> {
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
                None => bail!("--series: `{item}` has no scheme, and no member before it names one"),
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
fn excitation_per_actuator_s(protocol: &ExcitationProtocol, actuators: usize) -> anyhow::Result<f64> {
    let shots = protocol.shots(actuators)?;
    let playing = shots.iter().filter(|s| s.gains.first().is_some_and(|g| *g != 0.0)).count();
    Ok(playing as f64 * protocol.repetitions() as f64 * protocol.sweep().duration_s)
}

pub fn run(args: &TradeoffArgs) -> anyhow::Result<()> {
    let scene = Scene::resolve(&args.scene).with_context(|| format!("loading scene {}", args.scene))?;
    let GridSubset { nx, ny } = args.grid.parse()?;
    let mask = scene.grid_mask();
    let full_points = mask.iter().filter(|m| **m).count();
    let plan = ScanPlan::new(scene.grid, &mask, Some((nx, ny)))?;
    let seeds = match &args.seeds {
        Some(list) => parse_seeds(list)?,
        None => vec![args.seed],
    };
    let series: Vec<Vec<String>> = args.series.iter().map(|s| series_names(s)).collect::<Result<_, _>>()?;
    let mut names: Vec<String> = args.protocols.split(',').map(|n| n.trim().to_string()).collect();
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
        bail!("no protocol given");
    }
    // Each scan needs a lab of its own (a lab hands out one rig); without a cache every one would recompute the
    // same Green's functions, so a temporary cache shares them.
    let cache_dir = args.cache.dir();
    let scratch_cache = match &cache_dir {
        Some(_) => None,
        None => Some(tempfile_dir()?),
    };
    let runs = seeds.len() * trades.len();
    let mut k = 0;
    for &seed in &seeds {
        let options = LabOptions {
            seed: Some(seed),
            cache_dir: cache_dir.clone().or_else(|| scratch_cache.clone()),
            points: Some(plan.points.clone()),
            ..LabOptions::default()
        };
        for trade in &mut trades {
            k += 1;
            let started = std::time::Instant::now();
            let lab = MockLab::new(&scene, &options).context("building the mock lab")?;
            let m = measure(&lab, &scene, &plan, &trade.protocol, seed, args.min_snr_db)?;
            eprintln!(
                "tradeoff [{k}/{runs}] seed {seed} {:<24} {:>7.1} s/point (nominal {:>6.1})  median {:>6.1} dB  \
                 p95 {:>6.1} dB  ({:.0} s)",
                trade.name(),
                m.time_per_point_s,
                trade.nominal_time_per_point_s,
                m.median_error_db,
                m.p95_error_db,
                started.elapsed().as_secs_f64()
            );
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
    let out = to_json(&scene.name, &plan, full_points, &seeds, args.min_snr_db, &trades, &series_trades);
    if let Some(dir) = &args.figures {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let points: Vec<metaplate_figures::TradeoffPoint> = trades
            .iter()
            .map(|t| metaplate_figures::TradeoffPoint {
                label: t.name().to_string(),
                time_per_point_s: t.mean(|s| s.time_per_point_s),
                median_error_db: t.mean(|s| s.median_error_db),
            })
            .collect();
        let title = format!("{}: scan time against Green's-function error", scene.name);
        metaplate_figures::tradeoff(dir, "tradeoff", &points, &title)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_text(&out);
    }
    Ok(())
}

/// Scans `plan` with `protocol` on `lab` into a temporary directory and measures the result; the SNR gate at
/// `min_snr_db`, or off (`None`: minus infinity).
fn measure(
    lab: &MockLab,
    scene: &Scene,
    plan: &ScanPlan,
    protocol: &ExcitationProtocol,
    seed: u64,
    min_snr_db: Option<f64>,
) -> anyhow::Result<SeedTrade> {
    let (dir, out) = scratch_output(scene)?;
    let actuators = scene.actuators.len();
    let name = protocol.name.clone();
    let cfg = ScanConfig {
        protocol: protocol.clone(),
        seed,
        min_snr_db: min_snr_db.unwrap_or(f64::NEG_INFINITY),
        ..ScanConfig::default()
    };
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

/// An estimate as JSON: `{"mean", "ci95": [lo, hi] | null, "n"}`.
fn estimate_json(e: Option<Estimate>) -> Value {
    match e {
        Some(e) => json!({ "mean": e.mean, "ci95": e.ci95.map(|(lo, hi)| [lo, hi]), "n": e.n }),
        None => Value::Null,
    }
}

/// The scheme's family name (`hadamard`, `interleaved`) of a non-adaptive simultaneous protocol; `None` for the
/// rest (sequential: not simultaneous; adaptive: its time is not fixed, so it counts alone).
fn simultaneous_family(protocol: &ExcitationProtocol) -> Option<&'static str> {
    if protocol.adaptive.is_some() {
        return None;
    }
    match protocol.scheme {
        Scheme::Sequential => None,
        Scheme::Hadamard => Some("hadamard"),
        Scheme::Staggered => Some("staggered"),
        Scheme::Interleaved { .. } => Some("interleaved"),
    }
}

/// The series: each step's slope per doubling of excitation time (per seed, then mean and interval), the
/// noise-limited run on the means, the slope fitted per seed over that run, and the step where it departs.
fn series_json(series: &[&ProtocolTrade], seeds: &[u64]) -> Value {
    if series.len() < 2 {
        return Value::Null;
    }
    let excitation: Vec<f64> = series.iter().map(|t| t.excitation_s).collect();
    // Per seed, the members' errors (a seed missing for a member cannot happen: every protocol runs every seed).
    let errors_of =
        |seed: u64| -> Option<Vec<f64>> { series.iter().map(|t| t.seed(seed).map(|s| s.median_error_db)).collect() };
    let per_seed_steps: Vec<Vec<f64>> =
        seeds.iter().filter_map(|&seed| fit::step_slopes(&excitation, &errors_of(seed)?)).collect();
    let step_estimates: Vec<Option<Estimate>> =
        (0..series.len() - 1).map(|i| Estimate::of(&per_seed_steps.iter().map(|s| s[i]).collect::<Vec<_>>())).collect();
    let mean_steps: Vec<f64> = step_estimates.iter().map(|e| e.map_or(f64::NAN, |e| e.mean)).collect();
    let run = fit::noise_limited_steps(&mean_steps);
    let fit_over = |members: usize| {
        let slopes: Vec<f64> = seeds
            .iter()
            .filter_map(|&seed| fit::slope_per_doubling(&excitation[..members], &errors_of(seed)?[..members]))
            .collect();
        Estimate::of(&slopes)
    };
    let doublings = |i: usize| (excitation[i + 1] / excitation[i]).log2();
    json!({
        "protocols": series.iter().map(|t| t.name()).collect::<Vec<_>>(),
        "excitation_s": excitation,
        "time_per_point_s": series.iter().map(|t| estimate_json(t.estimate(|s| s.time_per_point_s))).collect::<Vec<_>>(),
        "median_error_db": series.iter().map(|t| estimate_json(t.estimate(|s| s.median_error_db))).collect::<Vec<_>>(),
        "steps": step_estimates.iter().enumerate().map(|(i, e)| json!({
            "from": series[i].name(),
            "to": series[i + 1].name(),
            "doublings": doublings(i),
            "slope_db_per_doubling": estimate_json(*e),
            "noise_limited": i < run,
        })).collect::<Vec<_>>(),
        "expected_db_per_doubling": fit::NOISE_SLOPE_DB_PER_DOUBLING,
        "tolerance_db": fit::NOISE_SLOPE_TOLERANCE_DB,
        "noise_limited_steps": run,
        "noise_limited_doublings": (0..run).map(doublings).sum::<f64>(),
        "slope_db_per_doubling": if run >= 1 { estimate_json(fit_over(run + 1)) } else { Value::Null },
        "slope_db_per_doubling_all": estimate_json(fit_over(series.len())),
        "departs_at": (run < series.len() - 1).then(|| json!({
            "from": series[run].name(),
            "to": series[run + 1].name(),
            "slope_db_per_doubling": mean_steps[run],
        })),
    })
}

/// What reaches the paper's median error with one seed, fastest first: `(time per point s, what, how)`.
fn best_reach(trades: &[ProtocolTrade], seed: u64, target_db: f64) -> Option<(f64, String, &'static str)> {
    let mut candidates: Vec<(f64, String, &'static str)> = Vec::new();
    let mut families: BTreeMap<&'static str, Vec<(&ProtocolTrade, &SeedTrade)>> = BTreeMap::new();
    for t in trades {
        let Some(s) = t.seed(seed) else { continue };
        match simultaneous_family(&t.protocol) {
            Some(family) => families.entry(family).or_default().push((t, s)),
            None if t.protocol.adaptive.is_some() && s.median_error_db <= target_db + REACH_TOLERANCE_DB => {
                candidates.push((s.time_per_point_s, t.name().to_string(), "adaptive"));
            }
            None => {}
        }
    }
    for (family, mut members) in families {
        members.sort_by(|a, b| a.0.excitation_s.total_cmp(&b.0.excitation_s));
        // Equal excitation times measure the same thing twice: the family keeps the first.
        members.dedup_by(|b, a| b.0.excitation_s == a.0.excitation_s);
        let points: Vec<Member> = members
            .iter()
            .map(|(t, s)| Member {
                excitation_s: t.excitation_s,
                time_per_point_s: s.time_per_point_s,
                median_error_db: s.median_error_db,
            })
            .collect();
        let reach = fit::time_to_reach(&points, target_db, REACH_TOLERANCE_DB);
        let Some(time_per_point_s) = reach.time_per_point_s() else { continue };
        let (what, how) = match reach {
            Reach::Interpolated { lower, excitation_s, .. } => (
                format!(
                    "{family} at {excitation_s:.2} s of excitation per point (between {} and {})",
                    members[lower].0.name(),
                    members[lower + 1].0.name()
                ),
                "interpolated",
            ),
            Reach::Fastest { .. } | Reach::NotReached => (members[0].0.name().to_string(), "fastest member"),
        };
        candidates.push((time_per_point_s, what, how));
    }
    candidates.into_iter().min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The time per point of a family at a given excitation per actuator, by a least-squares line of time per point
/// against excitation per actuator over its members (exact but for the random re-measures: a family's time is
/// affine in its excitation). `None` for fewer than two distinct excitations.
fn time_at_excitation(members: &[(f64, f64)], excitation_per_actuator_s: f64) -> Option<f64> {
    let n = members.len() as f64;
    let (mx, mt) = (members.iter().map(|m| m.0).sum::<f64>() / n, members.iter().map(|m| m.1).sum::<f64>() / n);
    let sxx: f64 = members.iter().map(|m| (m.0 - mx).powi(2)).sum();
    let sxt: f64 = members.iter().map(|m| (m.0 - mx) * (m.1 - mt)).sum();
    (members.len() >= 2 && sxx > 1e-18).then(|| mt + sxt / sxx * (excitation_per_actuator_s - mx))
}

/// The paper protocol's time per point over the fastest simultaneous way to its median error, per seed, then the
/// mean and interval; and the same ratio at equal excitation energy per actuator (the Hadamard family's time per
/// point where each actuator gets the paper's seconds of sweep).
fn ratio_json(trades: &[ProtocolTrade], seeds: &[u64]) -> Value {
    let Some(paper) = trades.iter().find(|t| t.name() == "paper") else {
        return Value::Null;
    };
    let mut per_seed = Vec::new();
    let mut ratios = Vec::new();
    let mut not_reached = Vec::new();
    for &seed in seeds {
        let Some(p) = paper.seed(seed) else { continue };
        match best_reach(trades, seed, p.median_error_db) {
            Some((time_per_point_s, what, how)) => {
                let ratio = p.time_per_point_s / time_per_point_s;
                ratios.push(ratio);
                per_seed.push(json!({ "seed": seed, "ratio": ratio, "paper_time_per_point_s": p.time_per_point_s,
                    "paper_median_error_db": p.median_error_db, "time_per_point_s": time_per_point_s,
                    "by": what, "how": how }));
            }
            None => not_reached.push(seed),
        }
    }
    let hadamard: Vec<&ProtocolTrade> =
        trades.iter().filter(|t| simultaneous_family(&t.protocol) == Some("hadamard")).collect();
    let equal: Vec<f64> = seeds
        .iter()
        .filter_map(|&seed| {
            let members: Vec<(f64, f64)> = hadamard
                .iter()
                .filter_map(|t| t.seed(seed).map(|s| (t.excitation_per_actuator_s, s.time_per_point_s)))
                .collect();
            let t = time_at_excitation(&members, paper.excitation_per_actuator_s)?;
            Some(paper.seed(seed)?.time_per_point_s / t)
        })
        .collect();
    json!({
        "paper_time_per_point_s": estimate_json(paper.estimate(|s| s.time_per_point_s)),
        "paper_median_error_db": estimate_json(paper.estimate(|s| s.median_error_db)),
        "ratio": estimate_json(Estimate::of(&ratios)),
        "per_seed": per_seed,
        "seeds_not_reached": not_reached,
        "equal_energy_ratio": estimate_json(Estimate::of(&equal)),
        "method": "per seed: the paper protocol's time per point over the least time per point at which a \
            simultaneous protocol reaches the paper's median error. Each simultaneous scheme's non-adaptive \
            protocols form a family ordered by excitation time: its fastest member counts when it is within \
            0.5 dB of the target; otherwise the first pair of members bracketing the target is interpolated, \
            error linear in log2 of excitation time (the family's measured slope there) and time per point \
            linear in excitation time; a target beyond the slowest member is not reached (no extrapolation). \
            An adaptive protocol counts alone, within 0.5 dB. Then the mean over seeds with a Student-t 95 % \
            interval. equal_energy_ratio: the paper's time per point over the Hadamard protocols' time per \
            point (a least-squares line against excitation per actuator) where each actuator gets the paper's \
            excitation.",
    })
}

fn to_json(
    scene: &str,
    plan: &ScanPlan,
    full_points: usize,
    seeds: &[u64],
    min_snr_db: Option<f64>,
    trades: &[ProtocolTrade],
    series: &[Vec<&ProtocolTrade>],
) -> Value {
    let mean_time = |t: &ProtocolTrade| t.mean(|s| s.time_per_point_s);
    let mean_error = |t: &ProtocolTrade| t.mean(|s| s.median_error_db);
    let paper = trades.iter().find(|t| t.name() == "paper");
    // The fastest protocol that reaches the paper's median error (within REACH_TOLERANCE_DB) in a fifth of its time
    // per point or less, on the seeds' means.
    let goal = paper.and_then(|p| {
        trades
            .iter()
            .filter(|t| t.name() != "paper" && t.failed_rows() == 0)
            .filter(|t| mean_error(t) <= mean_error(p) + REACH_TOLERANCE_DB && mean_time(t) * 5.0 <= mean_time(p))
            .min_by(|a, b| mean_time(a).total_cmp(&mean_time(b)))
            .map(|t| {
                let speedup = mean_time(p) / mean_time(t);
                json!({ "protocol": t.name(), "speedup": speedup, "fraction_of_8x_limit": speedup / 8.0,
                        "paper_median_error_db": mean_error(p), "median_error_db": mean_error(t) })
            })
    });
    let ci = |e: Option<Estimate>| e.and_then(|e| e.ci95).map(|(lo, hi)| [lo, hi]);
    json!({
        "scene": scene,
        "grid_points_measured": plan.points.len(),
        "grid_points_full": full_points,
        "error_band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
        "seeds": seeds,
        "min_snr_db": min_snr_db,
        "protocols": trades.iter().map(|t| {
            let areas: Vec<f64> = t.per_seed.iter().filter_map(|s| s.median_pixel_area_cm2).collect();
            json!({
                "name": t.name(),
                "time_per_point_s": mean_time(t),
                "time_per_point_s_ci95": ci(t.estimate(|s| s.time_per_point_s)),
                "nominal_time_per_point_s": t.nominal_time_per_point_s,
                "excitation_s": t.excitation_s,
                "excitation_per_actuator_s": t.excitation_per_actuator_s,
                "scan_hours": mean_time(t) * full_points as f64 / 3600.0,
                "median_error_db": mean_error(t),
                "median_error_db_ci95": ci(t.estimate(|s| s.median_error_db)),
                "p95_error_db": t.mean(|s| s.p95_error_db),
                "median_pixel_area_cm2": Estimate::of(&areas).map(|e| e.mean),
                "failed_rows": t.failed_rows(),
                "per_seed": t.per_seed.iter().map(|s| json!({
                    "seed": s.seed, "time_per_point_s": s.time_per_point_s, "median_error_db": s.median_error_db,
                    "p95_error_db": s.p95_error_db, "median_pixel_area_cm2": s.median_pixel_area_cm2,
                    "failed_rows": s.failed_rows,
                })).collect::<Vec<_>>(),
            })
        }).collect::<Vec<_>>(),
        "series": series.iter().map(|s| series_json(s, seeds)).collect::<Vec<_>>(),
        "ratio": ratio_json(trades, seeds),
        "goal": goal,
    })
}

/// `mean [lo, hi]` of an estimate's JSON, or `mean` alone, or `-`.
fn fmt_estimate(v: &Value, decimals: usize) -> String {
    match (v["mean"].as_f64(), v["ci95"][0].as_f64(), v["ci95"][1].as_f64()) {
        (Some(m), Some(lo), Some(hi)) => format!("{m:.decimals$} [{lo:.decimals$}, {hi:.decimals$}]"),
        (Some(m), _, _) => format!("{m:.decimals$}"),
        _ => "-".into(),
    }
}

/// The report as text: the protocols (seed means and intervals), the series and the ratio.
fn print_text(out: &Value) {
    let seeds = out["seeds"].as_array().map_or(0, Vec::len);
    println!(
        "{} ({} points, {seeds} seed(s); mean [95 % interval] over seeds)",
        out["scene"].as_str().unwrap_or(""),
        out["grid_points_measured"]
    );
    println!("| protocol | s/point | scan h | median error dB | p95 dB | failed rows |");
    println!("|---|---|---|---|---|---|");
    for p in out["protocols"].as_array().into_iter().flatten() {
        let with_ci = |key: &str| {
            let ci = &p[format!("{key}_ci95")];
            fmt_estimate(&json!({ "mean": p[key], "ci95": ci }), 1)
        };
        println!(
            "| {} | {} | {:.1} | {} | {:.1} | {} |",
            p["name"].as_str().unwrap_or(""),
            with_ci("time_per_point_s"),
            p["scan_hours"].as_f64().unwrap_or(f64::NAN),
            with_ci("median_error_db"),
            p["p95_error_db"].as_f64().unwrap_or(f64::NAN),
            p["failed_rows"]
        );
    }
    for series in out["series"].as_array().into_iter().flatten().filter(|s| !s.is_null()) {
        println!("series: slope of the median error per doubling of excitation time, dB (expected -3.0 +/- 1)");
        for s in series["steps"].as_array().into_iter().flatten() {
            println!(
                "  {} -> {} ({:.2} doublings): {}{}",
                s["from"].as_str().unwrap_or(""),
                s["to"].as_str().unwrap_or(""),
                s["doublings"].as_f64().unwrap_or(f64::NAN),
                fmt_estimate(&s["slope_db_per_doubling"], 2),
                if s["noise_limited"].as_bool() == Some(true) { "" } else { "  (departs)" }
            );
        }
        println!(
            "  noise-limited over {:.1} doublings, fitted slope {} dB per doubling",
            series["noise_limited_doublings"].as_f64().unwrap_or(0.0),
            fmt_estimate(&series["slope_db_per_doubling"], 2)
        );
    }
    let ratio = &out["ratio"];
    if !ratio.is_null() {
        println!(
            "ratio (paper's time per point / the fastest simultaneous protocol's at the paper's median error): {}; \
             at equal energy per actuator: {}",
            fmt_estimate(&ratio["ratio"], 2),
            fmt_estimate(&ratio["equal_energy_ratio"], 2)
        );
    }
    if !out["goal"].is_null() {
        println!("goal: {}", out["goal"]);
    }
}

//! The trade's result ([`TradeoffReport`]): per protocol the seeds' means and intervals, per series the slope per
//! doubling of excitation time, the paper's time per point over the fastest simultaneous way to its median error,
//! and the goal; serialised as `metaplate tradeoff --json` prints it (fields in alphabetical order: the JSON's key
//! order), or as text.

use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_recipes::scan::ScanPoints;
use serde::Serialize;

use super::families::{REACH_TOLERANCE_DB, Ratio, Series, ratio, series};
use super::fit::Estimate;
use super::trade::{EstimateJson, ProtocolTrade, SeedTrade};

/// The trade, as `metaplate tradeoff --json` prints it.
#[derive(Debug, Clone, Serialize)]
pub struct TradeoffReport {
    /// The band the error is measured over, Hz.
    pub error_band_hz: [f64; 2],
    /// The fastest protocol reaching the paper's median error in a fifth of its time or less (seed means).
    pub goal: Option<Goal>,
    /// Measurable points of the full grid.
    pub grid_points_full: usize,
    /// Points scanned.
    pub grid_points_measured: usize,
    /// The SNR gate, dB (null: off).
    pub min_snr_db: Option<f64>,
    /// Per protocol.
    pub protocols: Vec<ProtocolSummary>,
    /// The paper's time per point over the fastest simultaneous way to its median error (null without `paper`).
    pub ratio: Option<Ratio>,
    /// The scene's name.
    pub scene: String,
    /// The seeds.
    pub seeds: Vec<u64>,
    /// Per series (null for a series of fewer than two members measured).
    pub series: Vec<Option<Series>>,
}

/// The goal reached.
#[derive(Debug, Clone, Serialize)]
pub struct Goal {
    /// The speed-up over 8, the limit of 8 actuators.
    pub fraction_of_8x_limit: f64,
    /// The protocol's median error, dB.
    pub median_error_db: f64,
    /// The paper protocol's, dB.
    pub paper_median_error_db: f64,
    /// The protocol.
    pub protocol: String,
    /// The paper's time per point over the protocol's.
    pub speedup: f64,
}

/// One protocol's trade: the seeds' means and intervals.
#[derive(Debug, Clone, Serialize)]
pub struct ProtocolSummary {
    /// Seconds of excitation each actuator receives per point.
    pub excitation_per_actuator_s: f64,
    /// Seconds of excitation per point.
    pub excitation_s: f64,
    /// Rows that failed, over the seeds.
    pub failed_rows: usize,
    /// Mean median error, dB.
    pub median_error_db: f64,
    /// Its 95 % interval.
    pub median_error_db_ci95: Option<[f64; 2]>,
    /// Mean of the seeds' median pixel areas where one closed, cm^2.
    pub median_pixel_area_cm2: Option<f64>,
    /// The protocol.
    pub name: String,
    /// Nominal time per point, s.
    pub nominal_time_per_point_s: f64,
    /// Mean p95 error, dB.
    pub p95_error_db: f64,
    /// Per seed.
    pub per_seed: Vec<SeedTrade>,
    /// The full grid's scan, hours at the mean time per point.
    pub scan_hours: f64,
    /// Mean time per point, s.
    pub time_per_point_s: f64,
    /// Its 95 % interval.
    pub time_per_point_s_ci95: Option<[f64; 2]>,
}

impl TradeoffReport {
    /// The report of measured trades.
    pub fn of(
        scene: &str,
        plan: &ScanPoints,
        full_points: usize,
        seeds: &[u64],
        min_snr_db: Option<f64>,
        trades: &[ProtocolTrade],
        series_trades: &[Vec<&ProtocolTrade>],
    ) -> Self {
        let mean_time = |t: &ProtocolTrade| t.mean(|s| s.time_per_point_s);
        let mean_error = |t: &ProtocolTrade| t.mean(|s| s.median_error_db);
        let paper = trades.iter().find(|t| t.name() == "paper");
        // The fastest protocol that reaches the paper's median error (within REACH_TOLERANCE_DB) in a fifth of its
        // time per point or less, on the seeds' means.
        let goal = paper.and_then(|p| {
            trades
                .iter()
                .filter(|t| t.name() != "paper" && t.failed_rows() == 0)
                .filter(|t| mean_error(t) <= mean_error(p) + REACH_TOLERANCE_DB && mean_time(t) * 5.0 <= mean_time(p))
                .min_by(|a, b| mean_time(a).total_cmp(&mean_time(b)))
                .map(|t| {
                    let speedup = mean_time(p) / mean_time(t);
                    Goal {
                        fraction_of_8x_limit: speedup / 8.0,
                        median_error_db: mean_error(t),
                        paper_median_error_db: mean_error(p),
                        protocol: t.name().to_owned(),
                        speedup,
                    }
                })
        });
        let ci = |e: Option<Estimate>| e.and_then(|e| e.ci95).map(|(lo, hi)| [lo, hi]);
        let protocols = trades
            .iter()
            .map(|t| {
                let areas: Vec<f64> = t.per_seed.iter().filter_map(|s| s.median_pixel_area_cm2).collect();
                ProtocolSummary {
                    excitation_per_actuator_s: t.excitation_per_actuator_s,
                    excitation_s: t.excitation_s,
                    failed_rows: t.failed_rows(),
                    median_error_db: mean_error(t),
                    median_error_db_ci95: ci(t.estimate(|s| s.median_error_db)),
                    median_pixel_area_cm2: Estimate::of(&areas).map(|e| e.mean),
                    name: t.name().to_owned(),
                    nominal_time_per_point_s: t.nominal_time_per_point_s,
                    p95_error_db: t.mean(|s| s.p95_error_db),
                    per_seed: t.per_seed.clone(),
                    scan_hours: mean_time(t) * full_points as f64 / 3600.0,
                    time_per_point_s: mean_time(t),
                    time_per_point_s_ci95: ci(t.estimate(|s| s.time_per_point_s)),
                }
            })
            .collect();
        Self {
            error_band_hz: [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
            goal,
            grid_points_full: full_points,
            grid_points_measured: plan.points.len(),
            min_snr_db,
            protocols,
            ratio: ratio(trades, seeds),
            scene: scene.to_owned(),
            seeds: seeds.to_vec(),
            series: series_trades.iter().map(|s| series(s, seeds)).collect(),
        }
    }

    /// The report as text: the protocols (seed means and intervals), the series and the ratio.
    pub fn text(&self) -> String {
        let mut out = format!(
            "{} ({} points, {} seed(s); mean [95 % interval] over seeds)\n",
            self.scene,
            self.grid_points_measured,
            self.seeds.len()
        );
        out.push_str("| protocol | s/point | scan h | median error dB | p95 dB | failed rows |\n");
        out.push_str("|---|---|---|---|---|---|\n");
        for p in &self.protocols {
            let with_ci = |mean: f64, ci: Option<[f64; 2]>| fmt_estimate(Some(mean), ci, 1);
            out.push_str(&format!(
                "| {} | {} | {:.1} | {} | {:.1} | {} |\n",
                p.name,
                with_ci(p.time_per_point_s, p.time_per_point_s_ci95),
                p.scan_hours,
                with_ci(p.median_error_db, p.median_error_db_ci95),
                p.p95_error_db,
                p.failed_rows
            ));
        }
        let est = |e: &Option<EstimateJson>, decimals: usize| {
            fmt_estimate(e.map(|e| e.mean), e.and_then(|e| e.ci95), decimals)
        };
        for series in self.series.iter().flatten() {
            out.push_str(
                "series: slope of the median error per doubling of excitation time, dB (expected -3.0 +/- 1)\n",
            );
            for s in &series.steps {
                out.push_str(&format!(
                    "  {} -> {} ({:.2} doublings): {}{}\n",
                    s.from,
                    s.to,
                    s.doublings,
                    est(&s.slope_db_per_doubling, 2),
                    if s.noise_limited { "" } else { "  (departs)" }
                ));
            }
            let doublings = Some(series.noise_limited_doublings).filter(|d| d.is_finite()).unwrap_or(0.0);
            out.push_str(&format!(
                "  noise-limited over {doublings:.1} doublings, fitted slope {} dB per doubling\n",
                est(&series.slope_db_per_doubling, 2)
            ));
        }
        if let Some(ratio) = &self.ratio {
            out.push_str(&format!(
                "ratio (paper's time per point / the fastest simultaneous protocol's at the paper's median error): \
                 {}; at equal energy per actuator: {}\n",
                est(&ratio.ratio, 2),
                est(&ratio.equal_energy_ratio, 2)
            ));
        }
        if let Some(goal) = &self.goal {
            let text = serde_json::to_string(goal).unwrap_or_default();
            out.push_str(&format!("goal: {text}\n"));
        }
        out
    }
}

/// `mean [lo, hi]`, or `mean` alone, or `-` (non-finite values count as missing).
fn fmt_estimate(mean: Option<f64>, ci95: Option<[f64; 2]>, decimals: usize) -> String {
    let finite = |v: f64| v.is_finite().then_some(v);
    match (mean.and_then(finite), ci95.and_then(|[lo, hi]| finite(lo).zip(finite(hi)))) {
        (Some(m), Some((lo, hi))) => format!("{m:.decimals$} [{lo:.decimals$}, {hi:.decimals$}]"),
        (Some(m), None) => format!("{m:.decimals$}"),
        _ => "-".into(),
    }
}

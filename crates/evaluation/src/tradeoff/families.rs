//! Families of protocols: a series' slope per doubling of excitation time, and the paper protocol's time per point
//! over the fastest simultaneous way to its median error (the ratio), per seed then over the seeds.

use std::collections::BTreeMap;

use serde::Serialize;

use super::fit::{self, Estimate, Member, Reach};
use super::trade::{EstimateJson, ProtocolTrade, SeedTrade, estimate_json, simultaneous_family};

/// How far above the paper's median error a protocol may be and still count as reaching it, dB: two draws of the
/// same noise differ by about that much on a small grid. Used where the error is not set by the excitation time
/// (a family's fastest member already there, an adaptive protocol, the `goal`); within a family's noise-limited
/// range the target is reached exactly, by interpolation.
pub(crate) const REACH_TOLERANCE_DB: f64 = 0.5;

/// How the ratio is computed, as the JSON states it.
const RATIO_METHOD: &str = "per seed: the paper protocol's time per point over the least time per point at which a \
            simultaneous protocol reaches the paper's median error. Each simultaneous scheme's non-adaptive \
            protocols form a family ordered by excitation time: its fastest member counts when it is within \
            0.5 dB of the target; otherwise the first pair of members bracketing the target is interpolated, \
            error linear in log2 of excitation time (the family's measured slope there) and time per point \
            linear in excitation time; a target beyond the slowest member is not reached (no extrapolation). \
            An adaptive protocol counts alone, within 0.5 dB. Then the mean over seeds with a Student-t 95 % \
            interval. equal_energy_ratio: the paper's time per point over the Hadamard protocols' time per \
            point (a least-squares line against excitation per actuator) where each actuator gets the paper's \
            excitation.";

/// A series' slopes.
#[derive(Debug, Clone, Serialize)]
pub struct Series {
    /// The step where the error departs from the noise's slope.
    pub departs_at: Option<Departure>,
    /// Seconds of excitation per point, per member.
    pub excitation_s: Vec<f64>,
    /// The noise's slope, dB per doubling.
    pub expected_db_per_doubling: f64,
    /// Per member.
    pub median_error_db: Vec<Option<EstimateJson>>,
    /// Doublings of the noise-limited run.
    pub noise_limited_doublings: f64,
    /// Steps of the noise-limited run.
    pub noise_limited_steps: usize,
    /// The members.
    pub protocols: Vec<String>,
    /// Fitted over the noise-limited run (null without one).
    pub slope_db_per_doubling: Option<EstimateJson>,
    /// Fitted over every member.
    pub slope_db_per_doubling_all: Option<EstimateJson>,
    /// Step by step.
    pub steps: Vec<Step>,
    /// Per member.
    pub time_per_point_s: Vec<Option<EstimateJson>>,
    /// How far a noise-limited step may depart from the expected slope, dB per doubling.
    pub tolerance_db: f64,
}

/// Where a series departs from the noise's slope.
#[derive(Debug, Clone, Serialize)]
pub struct Departure {
    /// The member before.
    pub from: String,
    /// The step's mean slope, dB per doubling.
    pub slope_db_per_doubling: f64,
    /// The member after.
    pub to: String,
}

/// One step of a series.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    /// Doublings of excitation time.
    pub doublings: f64,
    /// The member before.
    pub from: String,
    /// Within the noise-limited run.
    pub noise_limited: bool,
    /// The slope, dB per doubling.
    pub slope_db_per_doubling: Option<EstimateJson>,
    /// The member after.
    pub to: String,
}

/// The paper's time per point over the fastest simultaneous way to its median error.
#[derive(Debug, Clone, Serialize)]
pub struct Ratio {
    /// The same ratio at equal excitation energy per actuator.
    pub equal_energy_ratio: Option<EstimateJson>,
    /// How it is computed.
    pub method: &'static str,
    /// The paper protocol's median error, dB.
    pub paper_median_error_db: Option<EstimateJson>,
    /// The paper protocol's time per point, s.
    pub paper_time_per_point_s: Option<EstimateJson>,
    /// Per seed where reached.
    pub per_seed: Vec<SeedRatio>,
    /// Over the seeds.
    pub ratio: Option<EstimateJson>,
    /// Seeds where nothing reached the paper's error.
    pub seeds_not_reached: Vec<u64>,
}

/// The ratio with one seed.
#[derive(Debug, Clone, Serialize)]
pub struct SeedRatio {
    /// What reached it.
    pub by: String,
    /// How ("interpolated", "fastest member", "adaptive").
    pub how: &'static str,
    /// The paper's median error, dB.
    pub paper_median_error_db: f64,
    /// The paper's time per point, s.
    pub paper_time_per_point_s: f64,
    /// The ratio.
    pub ratio: f64,
    /// The seed.
    pub seed: u64,
    /// The time per point that reaches it, s.
    pub time_per_point_s: f64,
}

/// The series: each step's slope per doubling of excitation time (per seed, then mean and interval), the
/// noise-limited run on the means, the slope fitted per seed over that run, and the step where it departs.
pub(crate) fn series(series: &[&ProtocolTrade], seeds: &[u64]) -> Option<Series> {
    if series.len() < 2 {
        return None;
    }
    let excitation: Vec<f64> = series.iter().map(|t| t.excitation_s).collect();
    // Per seed, the members' errors (a seed missing for a member cannot happen: every protocol runs every seed).
    let errors_of =
        |seed: u64| -> Option<Vec<f64>> { series.iter().map(|t| t.seed(seed).map(|s| s.median_error_db)).collect() };
    let per_seed_steps: Vec<Vec<f64>> =
        seeds.iter().filter_map(|&seed| fit::step_slopes(&excitation, &errors_of(seed)?)).collect();
    let step_estimates: Vec<Option<Estimate>> = (0..series.len() - 1)
        .map(|i| Estimate::of(&per_seed_steps.iter().filter_map(|s| s.get(i).copied()).collect::<Vec<_>>()))
        .collect();
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
    Some(Series {
        departs_at: (run < series.len() - 1).then(|| Departure {
            from: series[run].name().to_owned(),
            slope_db_per_doubling: mean_steps[run],
            to: series[run + 1].name().to_owned(),
        }),
        excitation_s: excitation.clone(),
        expected_db_per_doubling: fit::NOISE_SLOPE_DB_PER_DOUBLING,
        median_error_db: series.iter().map(|t| estimate_json(t.estimate(|s| s.median_error_db))).collect(),
        noise_limited_doublings: (0..run).map(doublings).sum::<f64>(),
        noise_limited_steps: run,
        protocols: series.iter().map(|t| t.name().to_owned()).collect(),
        slope_db_per_doubling: if run >= 1 { estimate_json(fit_over(run + 1)) } else { None },
        slope_db_per_doubling_all: estimate_json(fit_over(series.len())),
        steps: step_estimates
            .iter()
            .enumerate()
            .map(|(i, e)| Step {
                doublings: doublings(i),
                from: series[i].name().to_owned(),
                noise_limited: i < run,
                slope_db_per_doubling: estimate_json(*e),
                to: series[i + 1].name().to_owned(),
            })
            .collect(),
        time_per_point_s: series.iter().map(|t| estimate_json(t.estimate(|s| s.time_per_point_s))).collect(),
        tolerance_db: fit::NOISE_SLOPE_TOLERANCE_DB,
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
pub(crate) fn ratio(trades: &[ProtocolTrade], seeds: &[u64]) -> Option<Ratio> {
    let paper = trades.iter().find(|t| t.name() == "paper")?;
    let mut per_seed = Vec::new();
    let mut ratios = Vec::new();
    let mut not_reached = Vec::new();
    for &seed in seeds {
        let Some(p) = paper.seed(seed) else { continue };
        match best_reach(trades, seed, p.median_error_db) {
            Some((time_per_point_s, by, how)) => {
                let ratio = p.time_per_point_s / time_per_point_s;
                ratios.push(ratio);
                per_seed.push(SeedRatio {
                    by,
                    how,
                    paper_median_error_db: p.median_error_db,
                    paper_time_per_point_s: p.time_per_point_s,
                    ratio,
                    seed,
                    time_per_point_s,
                });
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
    Some(Ratio {
        equal_energy_ratio: estimate_json(Estimate::of(&equal)),
        method: RATIO_METHOD,
        paper_median_error_db: estimate_json(paper.estimate(|s| s.median_error_db)),
        paper_time_per_point_s: estimate_json(paper.estimate(|s| s.time_per_point_s)),
        per_seed,
        ratio: estimate_json(Estimate::of(&ratios)),
        seeds_not_reached: not_reached,
    })
}

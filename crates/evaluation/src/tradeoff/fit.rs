//! The arithmetic of `metaplate tradeoff` over seeds and over families of protocols: a mean over seeds with its
//! Student-t 95 % interval, the error's slope per doubling of excitation time, and the time per point at which a
//! family of protocols reaches a target error. Pure functions on numbers, tested on synthetic ones.

/// The slope a noise-limited error follows, dB per doubling of excitation time: the noise's energy in a response
/// falls as 1 / (excitation energy), i.e. -10 log10(2) = -3.01 dB per doubling.
pub const NOISE_SLOPE_DB_PER_DOUBLING: f64 = -3.010_299_956_639_812;

/// How far a step of a family may depart from [`NOISE_SLOPE_DB_PER_DOUBLING`] and still count as noise-limited,
/// dB per doubling (issue 20's "within 1 dB").
pub const NOISE_SLOPE_TOLERANCE_DB: f64 = 1.0;

/// Two-sided 95 % quantile of Student's t with `df` degrees of freedom.
///
/// Valid range: `df >= 1`. Tabulated to three decimals for 1 to 30; beyond, the Cornish-Fisher expansion to
/// order 1/df^2 (2.042 at 30, within 5e-4 of the table there, tending to 1.960). `df = 0` gives infinity (no
/// interval from one value).
pub fn student_t_975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
        2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::INFINITY,
        1..=30 => TABLE[df - 1],
        _ => {
            let z: f64 = 1.959_963_984_540_054;
            let n = df as f64;
            z + (z.powi(3) + z) / (4.0 * n) + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * n * n)
        }
    }
}

/// A mean over seeds and its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The mean.
    pub mean: f64,
    /// Student-t 95 % interval of the mean, `mean -/+ t(n-1) s / sqrt(n)` (s the sample standard deviation);
    /// `None` from a single value.
    pub ci95: Option<(f64, f64)>,
    /// How many values.
    pub n: usize,
}

impl Estimate {
    /// The mean and its interval of `values` (one per seed; the seeds' draws are independent).
    ///
    /// Valid range: finite values. `None` for no value or a non-finite one.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() || values.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n as f64;
        let ci95 = (n >= 2).then(|| {
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            let half = student_t_975(n - 1) * (var / n as f64).sqrt();
            (mean - half, mean + half)
        });
        Some(Self { mean, ci95, n })
    }
}

/// Each step's slope of a family ordered by excitation time: `(e[i+1] - e[i]) / log2(s[i+1] / s[i])`, dB per
/// doubling of excitation time `s` (seconds of sweep per point).
///
/// Valid range: positive, finite, strictly increasing times; finite errors; equal lengths. `None` otherwise, or
/// for fewer than two members.
pub fn step_slopes(excitation_s: &[f64], error_db: &[f64]) -> Option<Vec<f64>> {
    if excitation_s.len() != error_db.len() || excitation_s.len() < 2 {
        return None;
    }
    if excitation_s.iter().any(|s| !(s.is_finite() && *s > 0.0)) || error_db.iter().any(|e| !e.is_finite()) {
        return None;
    }
    if excitation_s.windows(2).any(|w| w[1] <= w[0]) {
        return None;
    }
    Some(excitation_s.windows(2).zip(error_db.windows(2)).map(|(s, e)| (e[1] - e[0]) / (s[1] / s[0]).log2()).collect())
}

/// The least-squares slope of error against log2 of excitation time, dB per doubling.
///
/// Valid range: positive finite times, not all equal; finite errors; equal lengths, at least two. `None`
/// otherwise.
pub fn slope_per_doubling(excitation_s: &[f64], error_db: &[f64]) -> Option<f64> {
    if excitation_s.len() != error_db.len() || excitation_s.len() < 2 {
        return None;
    }
    if excitation_s.iter().any(|s| !(s.is_finite() && *s > 0.0)) || error_db.iter().any(|e| !e.is_finite()) {
        return None;
    }
    let x: Vec<f64> = excitation_s.iter().map(|s| s.log2()).collect();
    let n = x.len() as f64;
    let (mx, me) = (x.iter().sum::<f64>() / n, error_db.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    let sxe: f64 = x.iter().zip(error_db).map(|(v, e)| (v - mx) * (e - me)).sum();
    // Equal times (up to rounding) give no slope rather than a huge one.
    (sxx > 1e-18).then(|| sxe / sxx)
}

/// How many leading steps of `slopes` (dB per doubling) lie within [`NOISE_SLOPE_TOLERANCE_DB`] of
/// [`NOISE_SLOPE_DB_PER_DOUBLING`]: the family's noise-limited run; the step after it is where the error departs
/// from the noise's slope (towards the next-largest term). A non-finite slope ends the run.
pub fn noise_limited_steps(slopes: &[f64]) -> usize {
    slopes.iter().take_while(|s| (*s - NOISE_SLOPE_DB_PER_DOUBLING).abs() <= NOISE_SLOPE_TOLERANCE_DB).count()
}

/// One protocol of a family, measured with one seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member {
    /// Seconds of excitation per point (shots x periods x sweep): what the noise averages over.
    pub excitation_s: f64,
    /// Measured time per point, s (playing, ring-out, moves, re-measures).
    pub time_per_point_s: f64,
    /// Median Green's-function error, dB.
    pub median_error_db: f64,
}

/// How a family reaches a target error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reach {
    /// Its fastest member is already within the tolerance of the target (the error is not set by the excitation
    /// time there): that member's time.
    Fastest {
        /// That member's time per point, s.
        time_per_point_s: f64,
    },
    /// Between members `lower` and `lower + 1`: the error interpolated linearly in log2 of excitation time (at
    /// the family's measured slope between them) reaches the target at `excitation_s`, and the time per point
    /// there is interpolated linearly in excitation time (a family's time per point is affine in it: a fixed
    /// ring-out and moves per shot and point).
    Interpolated {
        /// The member below the crossing (index into the family).
        lower: usize,
        /// Seconds of excitation per point at the crossing.
        excitation_s: f64,
        /// Time per point at the crossing, s.
        time_per_point_s: f64,
    },
    /// No member reaches the target (not even the slowest): no time can be given without extrapolating.
    NotReached,
}

impl Reach {
    /// The time per point, s, when reached.
    pub fn time_per_point_s(&self) -> Option<f64> {
        match self {
            Reach::Fastest { time_per_point_s } | Reach::Interpolated { time_per_point_s, .. } => {
                Some(*time_per_point_s)
            }
            Reach::NotReached => None,
        }
    }
}

/// The time per point at which a family of protocols (`members` ordered by strictly increasing excitation time)
/// first reaches `target_db`: its fastest member if that is within `tolerance_db` above the target, else the
/// first crossing of the target going up the family, interpolated as [`Reach::Interpolated`] says.
///
/// Valid range: finite values, positive strictly increasing excitation times, `tolerance_db >= 0`; anything else
/// gives [`Reach::NotReached`].
pub fn time_to_reach(members: &[Member], target_db: f64, tolerance_db: f64) -> Reach {
    let valid = members.iter().all(|m| {
        m.excitation_s.is_finite()
            && m.excitation_s > 0.0
            && m.time_per_point_s.is_finite()
            && m.median_error_db.is_finite()
    }) && members.windows(2).all(|w| w[1].excitation_s > w[0].excitation_s);
    if !valid || !target_db.is_finite() || tolerance_db.is_nan() || tolerance_db < 0.0 {
        return Reach::NotReached;
    }
    let Some(first) = members.first() else { return Reach::NotReached };
    if first.median_error_db <= target_db + tolerance_db {
        return Reach::Fastest { time_per_point_s: first.time_per_point_s };
    }
    for (lower, w) in members.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        if a.median_error_db > target_db && b.median_error_db <= target_db {
            // a's error is above the target and b's at or below it, so the division is by a positive number.
            let frac = (a.median_error_db - target_db) / (a.median_error_db - b.median_error_db);
            let (la, lb) = (a.excitation_s.log2(), b.excitation_s.log2());
            let excitation_s = (la + frac * (lb - la)).exp2();
            let along = (excitation_s - a.excitation_s) / (b.excitation_s - a.excitation_s);
            let time_per_point_s = a.time_per_point_s + along * (b.time_per_point_s - a.time_per_point_s);
            return Reach::Interpolated { lower, excitation_s, time_per_point_s };
        }
    }
    Reach::NotReached
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    #[test]
    fn t_quantiles_match_the_table_and_the_normal_limit() {
        assert_eq!(student_t_975(1), 12.706);
        assert_eq!(student_t_975(4), 2.776);
        assert!(student_t_975(0).is_infinite());
        // The expansion continues the table: 2.042 at 30, 2.021 at 40 (tables), and tends to z = 1.960.
        assert!((student_t_975(31) - 2.040).abs() < 1e-3, "{}", student_t_975(31));
        assert!((student_t_975(40) - 2.021).abs() < 1e-3, "{}", student_t_975(40));
        assert!((student_t_975(1_000_000) - 1.960).abs() < 1e-3);
    }

    #[test]
    fn estimate_is_the_mean_with_a_student_interval() {
        // Five values 1..5: mean 3, s = sqrt(2.5), half-width 2.776 * sqrt(2.5 / 5) = 1.963.
        let e = Estimate::of(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(e.mean, 3.0);
        let (lo, hi) = e.ci95.unwrap();
        assert!((hi - 3.0 - 2.776 * 0.5f64.sqrt()).abs() < 1e-12 && (3.0 - lo - (hi - 3.0)).abs() < 1e-12);
        // One value: a mean, no interval; equal values: a zero-width one.
        assert_eq!(Estimate::of(&[7.0]).unwrap().ci95, None);
        assert_eq!(Estimate::of(&[2.0, 2.0]).unwrap().ci95, Some((2.0, 2.0)));
        assert_eq!(Estimate::of(&[]), None);
        assert_eq!(Estimate::of(&[1.0, f64::NAN]), None);
    }

    /// A noise-limited family over a floor: error = 10 log10(10^(-(10 + 10 log10(s))/10) + 10^(floor/10)),
    /// i.e. noise at -10 dB for 1 s of excitation falling 3.01 dB per doubling, plus a floor's power.
    fn family(floor_db: f64, excitation_s: &[f64]) -> Vec<f64> {
        excitation_s
            .iter()
            .map(|s| {
                let noise = -10.0 - 10.0 * s.log10();
                10.0 * (10f64.powf(noise / 10.0) + 10f64.powf(floor_db / 10.0)).log10()
            })
            .collect()
    }

    #[test]
    fn slopes_follow_the_noise_until_the_floor() {
        let s = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];
        // Far below the noise, the floor changes nothing: every step is -3.01 dB, and so is the fit.
        let e = family(-200.0, &s);
        let steps = step_slopes(&s, &e).unwrap();
        assert!(steps.iter().all(|d| (d - NOISE_SLOPE_DB_PER_DOUBLING).abs() < 1e-9), "{steps:?}");
        assert!((slope_per_doubling(&s, &e).unwrap() - NOISE_SLOPE_DB_PER_DOUBLING).abs() < 1e-9);
        assert_eq!(noise_limited_steps(&steps), 6);
        // A floor at -25 dB: the noise meets it at 32 s (-25.05 dB), and the steps flatten into it (-2.88, -2.76,
        // -2.55, -2.21, -1.75, -1.24 dB per doubling); the run ends at the first step more than 1 dB off -3.01, from
        // 16 to 32 s, after four doublings.
        let e = family(-25.0, &s);
        let steps = step_slopes(&s, &e).unwrap();
        assert_eq!(noise_limited_steps(&steps), 4, "{steps:?}");
        assert!((steps[3] + 2.21).abs() < 0.01 && (steps[4] + 1.75).abs() < 0.01, "{steps:?}");
        // The fit over the whole family is shallower than the noise's slope, over the run alone close to it.
        let all = slope_per_doubling(&s, &e).unwrap();
        let run = slope_per_doubling(&s[..5], &e[..5]).unwrap();
        assert!(all > run && (run - NOISE_SLOPE_DB_PER_DOUBLING).abs() < 0.5, "{all} {run}");
        // Steps of other lengths are per doubling: 1 s to 4 s is two doublings.
        let steps = step_slopes(&[1.0, 4.0], &[-10.0, -16.0]).unwrap();
        assert_eq!(steps, vec![-3.0]);
    }

    #[test]
    fn slopes_refuse_what_has_no_slope() {
        assert_eq!(step_slopes(&[1.0], &[0.0]), None);
        assert_eq!(step_slopes(&[1.0, 1.0], &[0.0, -1.0]), None);
        assert_eq!(step_slopes(&[2.0, 1.0], &[0.0, -1.0]), None);
        assert_eq!(step_slopes(&[0.0, 1.0], &[0.0, -1.0]), None);
        assert_eq!(step_slopes(&[1.0, 2.0], &[0.0, f64::NAN]), None);
        assert_eq!(slope_per_doubling(&[3.0, 3.0], &[0.0, -1.0]), None);
        assert_eq!(slope_per_doubling(&[1.0, 2.0], &[0.0]), None);
        assert_eq!(noise_limited_steps(&[f64::NAN, -3.0]), 0);
    }

    fn members(excitation_s: &[f64], error_db: &[f64]) -> Vec<Member> {
        // Hadamard-like times: 8 shots, each the excitation's share plus 0.5 s of ring-out, and 1 s of moves.
        excitation_s
            .iter()
            .zip(error_db)
            .map(|(&s, &e)| Member { excitation_s: s, time_per_point_s: s + 8.0 * 0.5 + 1.0, median_error_db: e })
            .collect()
    }

    #[test]
    fn a_family_reaches_a_target_by_interpolation_in_log_time() {
        let s = [4.8, 9.6, 19.2, 38.4];
        let e = [-30.0, -33.0, -36.0, -39.0];
        let m = members(&s, &e);
        // -34.5 dB lies half way (in log2) between 9.6 and 19.2 s: 9.6 * sqrt(2) = 13.58 s of excitation, and the
        // time per point there is affine in it: 13.58 + 5 = 18.58 s.
        let Reach::Interpolated { lower, excitation_s, time_per_point_s } = time_to_reach(&m, -34.5, 0.5) else {
            panic!()
        };
        assert_eq!(lower, 1);
        assert!((excitation_s - 9.6 * 2f64.sqrt()).abs() < 1e-9);
        assert!((time_per_point_s - (9.6 * 2f64.sqrt() + 5.0)).abs() < 1e-9);
        // Exactly on a member: that member's time.
        assert!((time_to_reach(&m, -36.0, 0.5).time_per_point_s().unwrap() - 24.2).abs() < 1e-9);
        // The fastest member within the tolerance (a floor the family cannot go below): its own time.
        assert_eq!(time_to_reach(&m, -30.4, 0.5), Reach::Fastest { time_per_point_s: 9.8 });
        // Beyond the slowest: not reached, no extrapolation.
        assert_eq!(time_to_reach(&m, -40.0, 0.5), Reach::NotReached);
        // Refused input: unordered, non-finite, negative tolerance, empty.
        let mut bad = m.clone();
        bad.swap(0, 1);
        assert_eq!(time_to_reach(&bad, -34.5, 0.5), Reach::NotReached);
        assert_eq!(time_to_reach(&m, f64::NAN, 0.5), Reach::NotReached);
        assert_eq!(time_to_reach(&m, -34.5, -1.0), Reach::NotReached);
        assert_eq!(time_to_reach(&[], -34.5, 0.5), Reach::NotReached);
    }

    #[test]
    fn the_ratio_and_its_interval_over_seeds() {
        // Three seeds of a paper protocol at 125 s and a family whose error is offset by a seed's draw: the ratio
        // is 125 / the interpolated time, per seed, then a mean with its t interval (t(2) = 4.303).
        let s = [4.8, 9.6, 19.2, 38.4];
        let ratios: Vec<f64> = [-0.3, 0.0, 0.3]
            .iter()
            .map(|offset| {
                let e: Vec<f64> = [-30.0, -33.0, -36.0, -39.0].iter().map(|e| e + offset).collect();
                125.0 / time_to_reach(&members(&s, &e), -34.5, 0.5).time_per_point_s().unwrap()
            })
            .collect();
        // A worse draw (+0.3 dB) needs more time: 2^(0.1) more excitation than the middle seed.
        assert!(ratios[2] < ratios[1] && ratios[1] < ratios[0]);
        assert!((ratios[1] - 125.0 / (9.6 * 2f64.sqrt() + 5.0)).abs() < 1e-9);
        let est = Estimate::of(&ratios).unwrap();
        let (lo, hi) = est.ci95.unwrap();
        assert!(lo < ratios[1] && ratios[1] < hi && est.n == 3);
    }
}

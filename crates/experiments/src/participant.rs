//! The simulated participant: answers follow a psychometric model of the predicted field at the pixels, so that a
//! badly focused stimulus is answered worse.
//!
//! # The model
//! The runner gives, per trial, the predicted peak velocity at the stimulus's target pixels (the ones the answer
//! is about, [`crate::file::Stimulus::target_pixels`]) and at the others. For an odd-one-out stimulus the runner
//! predicts the odd pattern alone (the others as null targets), so that the contrast says how well the distinct
//! pattern stays at its pixel. With
//! - level `L = 20 log10(v_target / threshold)` dB above the vibrotactile threshold (`v_target`: the weakest target
//!   pixel's peak) and
//! - contrast `C = 20 log10(v_target / v_other)` dB (`v_other`: the strongest other pixel's peak; `+inf` with no
//!   other pixel or silence there),
//!
//! the participant perceives the answer with probability `q = (1 - lapse) F(L; 0, level_slope_db)
//! F(C; contrast_50_db, contrast_slope_db)`, `F(x; x50, s) = 1 / (1 + exp(-(x - x50) / s))` a logistic
//! psychometric function, and otherwise guesses uniformly among the response options: `P(correct) = q + (1 - q) / n`
//! for `n` options. Every draw comes from `SplitMix64` keyed by the seed and the trial's index, so a resumed session
//! answers exactly as an uninterrupted one.
//!
//! Defaults ([`SimParams::default`]): threshold 0.2 mm/s (Verrillo's Pacinian threshold near 250 Hz, about 0.1 um of
//! displacement, is 0.16 mm/s; thresholds rise away from it), level slope 2 dB, contrast midpoint 6 dB (the active
//! pixel twice the others' peak), contrast slope 2 dB, lapse rate 2 %. Response times: 1.5 s plus a uniform 0 to
//! 1.5 s, plus 2 s when the stimulus is explored (until-response).
//!
//! # Options
//! `sim` alone, or `sim:` followed by comma-separated `key=value` pairs: `seed` (integer), `threshold_m_s`,
//! `level_slope_db`, `contrast_50_db`, `contrast_slope_db`, `lapse` (0 to 1), for example `sim:seed=3,lapse=0.05`.

use metaplate_core::rng::{SplitMix64, mix64};

use crate::error::ExperimentError;

/// Stream of the participant's draws.
const PARTICIPANT_STREAM: u64 = 0x7061_7274_6963; // "partic"

/// Parameters of the simulated participant (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimParams {
    /// Seed of its draws.
    pub seed: u64,
    /// Vibrotactile detection threshold, peak velocity, m/s.
    pub threshold_m_s: f64,
    /// Logistic slope of detection over the level above threshold, dB.
    pub level_slope_db: f64,
    /// Contrast at which localisation is half way, dB.
    pub contrast_50_db: f64,
    /// Logistic slope over contrast, dB.
    pub contrast_slope_db: f64,
    /// Probability of a lapse (a guess whatever the stimulus), 0 to 1.
    pub lapse: f64,
}

impl Default for SimParams {
    fn default() -> Self {
        Self {
            seed: 0,
            threshold_m_s: 2e-4,
            level_slope_db: 2.0,
            contrast_50_db: 6.0,
            contrast_slope_db: 2.0,
            lapse: 0.02,
        }
    }
}

/// What the participant feels in one trial: predicted peak velocities, m/s.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldAtPixels {
    /// Peak velocity at each target pixel.
    pub target_peak_m_s: Vec<f64>,
    /// Peak velocity at each other pixel.
    pub other_peak_m_s: Vec<f64>,
}

/// A simulated participant.
#[derive(Debug, Clone, PartialEq)]
pub struct SimParticipant {
    params: SimParams,
}

impl SimParticipant {
    /// A participant with `params`.
    ///
    /// # Errors
    /// [`ExperimentError::InvalidArgument`] for a non-positive threshold or slope, or a lapse outside 0 to 1.
    pub fn new(params: SimParams) -> Result<Self, ExperimentError> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ExperimentError::invalid_argument(name, format!("must be finite and positive, got {v}")))
            }
        };
        positive("threshold_m_s", params.threshold_m_s)?;
        positive("level_slope_db", params.level_slope_db)?;
        positive("contrast_slope_db", params.contrast_slope_db)?;
        if !params.contrast_50_db.is_finite() {
            return Err(ExperimentError::invalid_argument("contrast_50_db", "must be finite"));
        }
        if !(0.0..=1.0).contains(&params.lapse) {
            return Err(ExperimentError::invalid_argument("lapse", format!("must be 0 to 1, got {}", params.lapse)));
        }
        Ok(Self { params })
    }

    /// Parses `sim` or `sim:key=value,...` (see the module docs).
    ///
    /// # Errors
    /// [`ExperimentError::InvalidArgument`] naming the option: not `sim`, an unknown key, a value that is not a
    /// number, or a value out of range.
    pub fn parse(spec: &str) -> Result<Self, ExperimentError> {
        let rest = match spec.strip_prefix("sim") {
            Some("") => "",
            Some(rest) => rest.strip_prefix(':').ok_or_else(|| {
                ExperimentError::invalid_argument(
                    "participant",
                    format!("`{spec}`: write `sim` or `sim:key=value,...`"),
                )
            })?,
            None => {
                return Err(ExperimentError::invalid_argument(
                    "participant",
                    format!("`{spec}` is not a simulated participant (`sim`, `sim:seed=3`)"),
                ));
            }
        };
        let mut p = SimParams::default();
        for pair in rest.split(',').filter(|s| !s.trim().is_empty()) {
            let (key, value) = pair.split_once('=').ok_or_else(|| {
                ExperimentError::invalid_argument("participant", format!("`{pair}` is not key=value"))
            })?;
            let (key, value) = (key.trim(), value.trim());
            let number = |name: &'static str| {
                value
                    .parse::<f64>()
                    .map_err(|_| ExperimentError::invalid_argument(name, format!("`{value}` is not a number")))
            };
            match key {
                "seed" => {
                    p.seed = value.parse().map_err(|_| {
                        ExperimentError::invalid_argument("seed", format!("`{value}` is not a non-negative integer"))
                    })?;
                }
                "threshold_m_s" => p.threshold_m_s = number("threshold_m_s")?,
                "level_slope_db" => p.level_slope_db = number("level_slope_db")?,
                "contrast_50_db" => p.contrast_50_db = number("contrast_50_db")?,
                "contrast_slope_db" => p.contrast_slope_db = number("contrast_slope_db")?,
                "lapse" => p.lapse = number("lapse")?,
                other => {
                    return Err(ExperimentError::invalid_argument(
                        "participant",
                        format!(
                            "unknown option `{other}` (seed, threshold_m_s, level_slope_db, contrast_50_db, \
                             contrast_slope_db, lapse)"
                        ),
                    ));
                }
            }
        }
        Self::new(p)
    }

    /// The parameters.
    pub fn params(&self) -> SimParams {
        self.params
    }

    /// The probability of perceiving the answer, `q` of the module docs (0 to 1).
    ///
    /// # Errors
    /// [`ExperimentError::InvalidArgument`] when there is no target pixel or a velocity is negative or not finite.
    pub fn perceived_probability(&self, field: &FieldAtPixels) -> Result<f64, ExperimentError> {
        let all = field.target_peak_m_s.iter().chain(&field.other_peak_m_s);
        if let Some(v) = all.clone().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(ExperimentError::invalid_argument(
                "peak velocity",
                format!("must be finite and >= 0, got {v}"),
            ));
        }
        let target = field.target_peak_m_s.iter().copied().fold(f64::INFINITY, f64::min);
        if !target.is_finite() {
            return Err(ExperimentError::invalid_argument("target_peak_m_s", "no target pixel"));
        }
        let other = field.other_peak_m_s.iter().copied().fold(0.0, f64::max);
        let p = &self.params;
        let level_db = 20.0 * (target / p.threshold_m_s).log10();
        let detect = logistic(level_db, 0.0, p.level_slope_db);
        let locate = if other > 0.0 {
            logistic(20.0 * (target / other).log10(), p.contrast_50_db, p.contrast_slope_db)
        } else if target > 0.0 {
            1.0
        } else {
            0.0
        };
        Ok((1.0 - p.lapse) * detect * locate)
    }

    /// The answer to trial `trial` (its plan index): `correct` with the model's probability, else a uniform guess
    /// among `labels`.
    ///
    /// # Errors
    /// As [`SimParticipant::perceived_probability`]; [`ExperimentError::InvalidArgument`] when `labels` is empty.
    pub fn answer<'a>(
        &self,
        trial: u32,
        correct: &'a str,
        labels: &'a [String],
        field: &FieldAtPixels,
    ) -> Result<&'a str, ExperimentError> {
        if labels.is_empty() {
            return Err(ExperimentError::invalid_argument("labels", "no response options"));
        }
        let q = self.perceived_probability(field)?;
        let mut rng = self.rng(trial);
        if rng.uniform() < q {
            return Ok(correct);
        }
        Ok(labels[rng.in_range(0, labels.len() as u64 - 1) as usize].as_str())
    }

    /// The time the participant takes to answer trial `trial`, s (see the module docs).
    pub fn response_time_s(&self, trial: u32, explored: bool) -> f64 {
        let mut rng = self.rng(trial);
        // Skip the two draws the answer uses, so time and answer are independent.
        rng.next_u64();
        rng.next_u64();
        1.5 + 1.5 * rng.uniform() + if explored { 2.0 } else { 0.0 }
    }

    fn rng(&self, trial: u32) -> SplitMix64 {
        SplitMix64::new(self.params.seed ^ mix64(u64::from(trial)), PARTICIPANT_STREAM)
    }
}

fn logistic(x: f64, x50: f64, slope: f64) -> f64 {
    if x == f64::INFINITY {
        return 1.0;
    }
    if x == f64::NEG_INFINITY {
        return 0.0;
    }
    1.0 / (1.0 + (-(x - x50) / slope).exp())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    fn accuracy(sim: &SimParticipant, field: &FieldAtPixels) -> f64 {
        let labels: Vec<String> = ["a", "b", "c", "d", "e"].iter().map(|s| (*s).to_owned()).collect();
        let n = 4000;
        let correct = (0..n).filter(|&t| sim.answer(t, "c", &labels, field).unwrap() == "c").count();
        correct as f64 / f64::from(n)
    }

    #[test]
    fn a_badly_focused_stimulus_is_answered_worse() {
        let sim = SimParticipant::parse("sim:seed=3").unwrap();
        let focused = FieldAtPixels { target_peak_m_s: vec![5e-3], other_peak_m_s: vec![5e-4, 3e-4, 2e-4, 1e-4] };
        let blurred = FieldAtPixels { target_peak_m_s: vec![5e-3], other_peak_m_s: vec![4e-3, 3e-3, 2e-3, 1e-3] };
        let faint = FieldAtPixels { target_peak_m_s: vec![1e-4], other_peak_m_s: vec![0.0; 4] };
        let (good, bad, weak) = (accuracy(&sim, &focused), accuracy(&sim, &blurred), accuracy(&sim, &faint));
        // Focused: 20 dB contrast, 28 dB above threshold: q = 0.98 x ~1 x ~1, P = q + (1 - q) / 5 = 0.984.
        assert!((good - 0.984).abs() < 0.01, "{good}");
        // Blurred: 1.9 dB contrast: q = 0.98 x 0.114, P = 0.29.
        assert!((bad - 0.289).abs() < 0.03, "{bad}");
        // Below threshold (-6 dB): q = 0.98 x 0.047, P = 0.24.
        assert!(weak < 0.3, "{weak}");
        assert!(good > bad + 0.5);
    }

    #[test]
    fn answers_are_a_function_of_seed_and_trial() {
        let labels: Vec<String> = ["l", "r"].iter().map(|s| (*s).to_owned()).collect();
        let field = FieldAtPixels { target_peak_m_s: vec![2e-4], other_peak_m_s: vec![2e-4] };
        let a = SimParticipant::parse("sim:seed=1").unwrap();
        let b = SimParticipant::parse("sim:seed=2").unwrap();
        let answers =
            |s: &SimParticipant| (0..64).map(|t| s.answer(t, "l", &labels, &field).unwrap()).collect::<Vec<_>>();
        assert_eq!(answers(&a), answers(&a));
        assert_ne!(answers(&a), answers(&b));
        let t = a.response_time_s(4, true);
        assert!((3.5..5.0).contains(&t));
    }

    #[test]
    fn options_parse_with_typed_errors() {
        let p = SimParticipant::parse("sim:seed=3, lapse=0.1,threshold_m_s=1e-4").unwrap().params();
        assert_eq!((p.seed, p.lapse, p.threshold_m_s), (3, 0.1, 1e-4));
        assert_eq!(SimParticipant::parse("sim").unwrap().params(), SimParams::default());
        for (spec, name) in [
            ("P01", "participant"),
            ("simon", "participant"),
            ("sim:colour=red", "participant"),
            ("sim:seed=-1", "seed"),
            ("sim:lapse=x", "lapse"),
            ("sim:lapse=2", "lapse"),
            ("sim:threshold_m_s=0", "threshold_m_s"),
        ] {
            match SimParticipant::parse(spec) {
                Err(ExperimentError::InvalidArgument { name: n, .. }) => assert_eq!(n, name, "{spec}"),
                other => panic!("{spec}: {other:?}"),
            }
        }
        let sim = SimParticipant::parse("sim").unwrap();
        let nan = FieldAtPixels { target_peak_m_s: vec![f64::NAN], other_peak_m_s: vec![] };
        assert!(sim.perceived_probability(&nan).is_err());
        let none = FieldAtPixels { target_peak_m_s: vec![], other_peak_m_s: vec![1.0] };
        assert!(sim.perceived_probability(&none).is_err());
    }
}

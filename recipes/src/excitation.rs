//! Scan protocols by name: how the actuators are played at each grid point, with the settings a trade-off study
//! sweeps.
//!
//! Syntax: `NAME` or `NAME:SETTINGS`, names in kebab-case. `D` is the sweep's duration in seconds (0.6 s at
//! least: the 0.5 s responses must fit one period), `R` the periods per shot (at least 1).
//!
//! | name | what is played | assumptions |
//! |---|---|---|
//! | `paper` | each actuator alone, a 3 s linear sweep 62..625 Hz, 5 periods (120 s of sweeps per point) | responses shorter than one period (0.5 s); nothing else |
//! | `quick` | each actuator alone, a 1 s linear sweep, 2 periods | as `paper` |
//! | `sequential:DxR` | each actuator alone, linear sweeps | as `paper` |
//! | `sequential-exp:DxR` | each actuator alone, exponential sweeps; the harmonics land before time 0 of the periodic response and are cut away (harmonic separation) | harmonic `k`'s advance `L ln k` (`L = D / ln(f2/f1)`) at least the response length beyond which the window stops, i.e. `D - 0.5 s >= L ln 2` for the second harmonic |
//! | `hadamard:DxR` | all actuators at once, 8 shots signed by the 8 x 8 Hadamard matrix, decoded by its transpose (8 x the energy per actuator per unit time) | linearity and superposition at the plate; odd-order distortion flips with the sign and stays with its actuator (as sequentially); even-order does not flip, so it can only land in actuator 0's (all-ones) column |
//! | `interleaved:D` | all actuators in one shot, one exponential sweep each, staggered by a slot (the multiple exponential sweep method) | linearity; slot >= response (0.5 s) + the third harmonic's advance `L ln 3`, else refused; one period: no SNR estimate, no averaging; **no clock-drift correction**: actuator `k`'s response is cut at `k` slots on the recorder's clock, off by `k x slot x drift` (12 samples for actuator 7 at 50 ppm with 1.43 s slots), which costs it most of its accuracy at the top of the band (measured median error -10 dB on the mock lab, against -37 dB for the others) |
//! | `adaptive:DxR@SNR[/ROUNDS]` (R >= 2) | Hadamard rounds (`hadamard:DxR`) averaged until every actuator's SNR reaches `SNR` dB, at most `ROUNDS` (default 8) | as `hadamard`; the SNR estimate is the spread of the periods; when the target is not met in `ROUNDS` rounds the rows are committed with status `failed` and the reason |
//!
//! Every protocol keeps the paper's deconvolution ([`DeconvConfig::paper`]: 0.5 s responses, band 62..625 Hz);
//! exponential sweeps use regularisation 1e-5 (their power falls 10 dB across the band, see
//! [`DeconvConfig::paper`]).

use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::protocol::Protocol;
use metaplate_dsp::sweep::SweepSpec;

use crate::error::RecipeError;

/// The excitation and its processing.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanProtocol {
    /// Name recorded in the manifest (`paper`, `quick`).
    pub name: String,
    /// One period of the excitation (its `sample_rate_hz` is replaced by the DAQ's).
    pub sweep: SweepSpec,
    /// Periods played back to back.
    pub repetitions: usize,
    /// Deconvolution (its `sample_rate_hz` is replaced by the DAQ's).
    pub deconv: DeconvConfig,
    /// How the actuators are played (one at a time, or all at once).
    pub excitation: Excitation,
    /// Averaging until a target SNR (simultaneous protocols only); `None`: one round.
    pub adaptive: Option<Adaptive>,
}

impl ScanProtocol {
    /// The paper's: a 3 s linear sweep 62..625 Hz, 5 repetitions, [`DeconvConfig::paper`] (0.5 s responses).
    pub fn paper() -> Self {
        Self {
            name: "paper".into(),
            sweep: SweepSpec::default(),
            repetitions: 5,
            deconv: DeconvConfig::paper(),
            excitation: Excitation::Sequential,
            adaptive: None,
        }
    }

    /// For tests and quick looks: a 1 s sweep 62..625 Hz, 2 repetitions, the paper's deconvolution (0.5 s
    /// responses fit the 1 s period). 7.5 times less playing than the paper's; the SNR drops by about 10 dB (the
    /// sweep energy per period falls 3 times and 2 periods are averaged instead of 5).
    pub fn quick() -> Self {
        Self {
            name: "quick".into(),
            sweep: SweepSpec { duration_s: 1.0, ..SweepSpec::default() },
            repetitions: 2,
            deconv: DeconvConfig::paper(),
            excitation: Excitation::Sequential,
            adaptive: None,
        }
    }

    /// A protocol by name: `paper`, `quick`, or one with settings such as `hadamard:1x2` (the syntax and every
    /// protocol's assumptions: [`crate::excitation`]).
    ///
    /// # Errors
    /// [`RecipeError::Config`] for an unknown name or bad settings.
    pub fn by_name(name: &str) -> Result<Self, RecipeError> {
        parse(name)
    }

    /// Seconds of playback per actuator and point (repetitions and tail), at nominal rates.
    pub fn seconds_per_actuator(&self) -> f64 {
        self.repetitions as f64 * self.sweep.duration_s + self.deconv.ir_len as f64 / self.deconv.sample_rate_hz
    }
}

/// How the actuators are played at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Excitation {
    /// One actuator at a time (the paper's).
    Sequential,
    /// All at once, Hadamard-coded shots.
    Hadamard,
    /// All at once, exponential sweeps staggered by `slot_s` seconds.
    Interleaved {
        /// Delay between consecutive actuators' starts, s.
        slot_s: f64,
    },
}

/// Averaging rounds until a target SNR.
///
/// Valid range: finite `target_snr_db`; `max_rounds >= 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    /// Every actuator's SNR must reach this, dB.
    pub target_snr_db: f64,
    /// Rounds (each one full set of shots) at most; then the point is committed, its short rows flagged.
    pub max_rounds: usize,
}

/// Regularisation for exponential sweeps (see [`DeconvConfig::paper`]).
const EXP_REGULARISATION: f64 = 1e-5;
/// Shortest sweep, s: one period must hold the 0.5 s responses plus the periodic pipeline's guard for the clock
/// drift (tens of samples).
const MIN_SWEEP_S: f64 = 0.6;
/// Longest sweep, s (a sanity bound: the paper's is 3 s).
const MAX_SWEEP_S: f64 = 60.0;
/// Most periods per shot (a sanity bound).
const MAX_REPETITIONS: usize = 100;
/// Default and largest number of adaptive rounds.
const DEFAULT_ROUNDS: usize = 8;
const MAX_ROUNDS: usize = 64;
/// Slot margin beyond the response and the third harmonic's advance, s: a few periods of the band's lowest
/// frequency, for the band-limit's ringing.
const SLOT_MARGIN_S: f64 = 0.05;

/// The names [`parse`] knows, with a one-line description each (for help texts).
pub const NAMES: &[(&str, &str)] = &[
    ("paper", "sequential linear sweeps, 3 s x 5 (the paper's)"),
    ("quick", "sequential linear sweeps, 1 s x 2"),
    ("sequential:DxR", "sequential linear sweeps, D s x R"),
    ("sequential-exp:DxR", "sequential exponential sweeps with harmonic separation"),
    ("hadamard:DxR", "all 8 actuators at once, Hadamard-coded linear sweeps (8 shots)"),
    ("interleaved:D", "interleaved exponential sweeps (multiple exponential sweep method), one shot"),
    ("adaptive:DxR@SNR[/ROUNDS]", "Hadamard rounds averaged until SNR dB per actuator, at most ROUNDS"),
];

/// The protocol called `name` (see the module's table).
///
/// # Errors
/// [`RecipeError::Config`] naming what is wrong: an unknown name, malformed or out-of-range settings.
pub fn parse(name: &str) -> Result<ScanProtocol, RecipeError> {
    let (kind, settings) = match name.split_once(':') {
        Some((k, s)) => (k, Some(s)),
        None => (name, None),
    };
    let bad = |why: &str| RecipeError::Config(format!("protocol `{name}`: {why}"));
    fn need<'a>(s: Option<&'a str>, name: &str) -> Result<&'a str, RecipeError> {
        s.ok_or_else(|| RecipeError::Config(format!("protocol `{name}`: needs settings after `:`")))
    }
    let linear = |duration_s: f64| SweepSpec { duration_s, ..SweepSpec::default() };
    let base = |sweep: SweepSpec, repetitions: usize, excitation: Excitation| {
        let deconv = match sweep.exp_rate_s() {
            Some(_) => DeconvConfig { regularisation: EXP_REGULARISATION, ..DeconvConfig::paper() },
            None => DeconvConfig::paper(),
        };
        ScanProtocol { name: name.to_string(), sweep, repetitions, deconv, excitation, adaptive: None }
    };
    let protocol = match (kind, settings) {
        ("paper", None) => ScanProtocol::paper(),
        ("quick", None) => ScanProtocol::quick(),
        ("paper" | "quick", Some(_)) => return Err(bad("takes no settings")),
        ("sequential", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d), r, Excitation::Sequential)
        }
        ("sequential-exp", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d).as_exponential(), r, Excitation::Sequential)
        }
        ("hadamard", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d), r, Excitation::Hadamard)
        }
        ("interleaved", s) => {
            let d = number(need(s, name)?, "duration").map_err(|e| bad(&e))?;
            check_duration(d).map_err(|e| bad(&e))?;
            let sweep = linear(d).as_exponential();
            let ir_s = DeconvConfig::paper().ir_len as f64 / DeconvConfig::paper().sample_rate_hz;
            let advance_s = sweep.exp_rate_s().map_or(0.0, |l| l * 3f64.ln());
            // Whole milliseconds: a whole number of samples at both 24 and 48 kHz (see `Protocol::Interleaved`).
            let slot_s = ((ir_s + advance_s + SLOT_MARGIN_S) * 1000.0).ceil() / 1000.0;
            base(sweep, 1, Excitation::Interleaved { slot_s })
        }
        ("adaptive", s) => {
            let s = need(s, name)?;
            let (dr, rest) = s.split_once('@').ok_or_else(|| bad("expected DxR@SNR[/ROUNDS]"))?;
            let (d, r) = duration_by_reps(dr).map_err(|e| bad(&e))?;
            if r < 2 {
                // The SNR estimate is the spread of the periods: one period has none.
                return Err(bad("adaptive averaging needs at least 2 periods per shot (its SNR estimate)"));
            }
            let (snr, rounds) = match rest.split_once('/') {
                Some((snr, rounds)) => (snr, Some(rounds)),
                None => (rest, None),
            };
            let target_snr_db = number(snr, "SNR").map_err(|e| bad(&e))?;
            let max_rounds = match rounds {
                Some(r) => r.parse::<usize>().map_err(|_| bad(&format!("rounds `{r}` is not a whole number")))?,
                None => DEFAULT_ROUNDS,
            };
            if !(1..=MAX_ROUNDS).contains(&max_rounds) {
                return Err(bad(&format!("rounds {max_rounds} must be 1 to {MAX_ROUNDS}")));
            }
            let adaptive = Some(Adaptive { target_snr_db, max_rounds });
            ScanProtocol { adaptive, ..base(linear(d), r, Excitation::Hadamard) }
        }
        (other, _) => {
            let known: Vec<&str> = NAMES.iter().map(|(n, _)| *n).collect();
            return Err(RecipeError::Config(format!("unknown protocol `{other}` (known: {})", known.join(", "))));
        }
    };
    Ok(protocol)
}

/// `DxR`: a duration in seconds and a repetition count.
fn duration_by_reps(s: &str) -> Result<(f64, usize), String> {
    let (d, r) = s.split_once('x').ok_or_else(|| format!("`{s}`: expected DxR (seconds x repetitions)"))?;
    let d = number(d, "duration")?;
    check_duration(d)?;
    let r: usize = r.parse().map_err(|_| format!("repetitions `{r}` is not a whole number"))?;
    if !(1..=MAX_REPETITIONS).contains(&r) {
        return Err(format!("repetitions {r} must be 1 to {MAX_REPETITIONS}"));
    }
    Ok((d, r))
}

fn number(s: &str, what: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{what} `{s}` is not a finite number")),
    }
}

fn check_duration(d: f64) -> Result<(), String> {
    if (MIN_SWEEP_S..=MAX_SWEEP_S).contains(&d) {
        Ok(())
    } else {
        Err(format!(
            "sweep duration {d} s must be {MIN_SWEEP_S} to {MAX_SWEEP_S} s (a period holds the 0.5 s response)"
        ))
    }
}

impl ScanProtocol {
    /// The DSP protocol this scan protocol plays (sweep at its nominal rate; the scan replaces the rate).
    pub fn dsp(&self) -> Protocol {
        match self.excitation {
            Excitation::Sequential => Protocol::Sequential { sweep: self.sweep, repetitions: self.repetitions },
            Excitation::Hadamard => Protocol::Hadamard { sweep: self.sweep, repetitions: self.repetitions },
            Excitation::Interleaved { slot_s } => Protocol::Interleaved { sweep: self.sweep, slot_s },
        }
    }

    /// Whether every actuator plays in every shot (shots are then measured and retried as a whole point).
    pub fn is_simultaneous(&self) -> bool {
        !matches!(self.excitation, Excitation::Sequential)
    }

    /// Nominal playing time per point and round for `actuators` actuators, s: every shot's playback and the
    /// response's ring-out (beam moves, settling and the recording margin are not included; the scan measures
    /// them). Adaptive protocols take between one and `max_rounds` times this.
    pub fn nominal_time_per_point_s(&self, actuators: usize) -> f64 {
        self.dsp().time_per_point_s(actuators, self.deconv.ir_len as f64 / self.deconv.sample_rate_hz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_to_their_protocols() {
        let p = parse("paper").unwrap();
        assert_eq!(p, ScanProtocol::paper());
        assert_eq!(parse("quick").unwrap(), ScanProtocol::quick());
        let h = parse("hadamard:1x2").unwrap();
        assert_eq!((h.excitation, h.repetitions, h.sweep.duration_s), (Excitation::Hadamard, 2, 1.0));
        // 8 shots of 2 s plus 0.5 s ring-out each: 20 s, against the paper's 124 s.
        assert!((h.nominal_time_per_point_s(8) - 20.0).abs() < 1e-9);
        assert!((p.nominal_time_per_point_s(8) - 124.0).abs() < 1e-9);
        let e = parse("sequential-exp:2x1").unwrap();
        assert!(e.sweep.exp_rate_s().is_some() && e.deconv.regularisation == EXP_REGULARISATION);
        let i = parse("interleaved:2").unwrap();
        let Excitation::Interleaved { slot_s } = i.excitation else { panic!("{i:?}") };
        // The slot the DSP protocol requires for 0.5 s responses must be met.
        assert!(i.dsp().validate(8, 0.5).is_ok(), "slot {slot_s}");
        let a = parse("adaptive:0.6x2@40/3").unwrap();
        assert_eq!(a.adaptive, Some(Adaptive { target_snr_db: 40.0, max_rounds: 3 }));
        assert_eq!(parse("adaptive:0.6x2@40").unwrap().adaptive.map(|a| a.max_rounds), Some(DEFAULT_ROUNDS));
    }

    #[test]
    fn bad_names_and_settings_are_refused_with_the_reason() {
        for (name, needle) in [
            ("nope", "unknown protocol"),
            ("hadamard", "needs settings"),
            ("hadamard:0.1x2", "duration"),
            ("hadamard:1x0", "repetitions"),
            ("hadamard:1", "DxR"),
            ("paper:1x1", "no settings"),
            ("adaptive:1x2@x", "SNR"),
            ("adaptive:1x1@30", "at least 2 periods"),
            ("adaptive:1x2@30/0", "rounds"),
            ("interleaved:inf", "finite"),
        ] {
            let err = parse(name).unwrap_err().to_string();
            assert!(err.contains(needle), "{name}: {err}");
        }
    }
}

//! The registry of protocol names: `NAME` or `NAME:SETTINGS` parsed into an [`ExcitationProtocol`], and the names
//! with a line of help each (the module docs of `excitation` have the table).

use super::{
    Adaptive, AdaptiveTarget, DEFAULT_ROUNDS, ExcitationProtocol, MAX_REPETITIONS, MAX_ROUNDS, MAX_SWEEP_S,
    MIN_SWEEP_S, SLOT_MARGIN_S, Scheme,
};
use crate::deconv::DeconvConfig;
use crate::sweep::SweepSpec;

/// Why a protocol name was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolNameError {
    /// No protocol of that name.
    #[error("unknown protocol `{name}` (known: {known})")]
    Unknown {
        /// The name given.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// A known name with malformed or out-of-range settings.
    #[error("protocol `{name}`: {reason}")]
    Settings {
        /// The whole name given.
        name: String,
        /// What is wrong.
        reason: String,
    },
}

/// The names [`parse`] knows, with a one-line description each (for help texts).
pub const NAMES: &[(&str, &str)] = &[
    ("paper", "sequential linear sweeps, 3 s x 5 (the paper's)"),
    ("quick", "sequential linear sweeps, 1 s x 2"),
    ("sequential:DxR", "sequential linear sweeps, D s x R"),
    ("sequential-exp:DxR", "sequential exponential sweeps with harmonic separation"),
    ("hadamard:DxR", "all 8 actuators at once, Hadamard-coded linear sweeps (8 shots)"),
    (
        "staggered:DxR",
        "all 8 actuators in one shot, the D s linear sweep circularly shifted by D/8 s per actuator, R periods",
    ),
    ("interleaved:D", "interleaved exponential sweeps (multiple exponential sweep method), one shot"),
    ("adaptive:DxR@SNR[/ROUNDS]", "Hadamard rounds averaged until SNR dB per actuator, at most ROUNDS"),
    (
        "adaptive-error:DxR@DB[/ROUNDS]",
        "Hadamard rounds averaged until every actuator's estimated error is DB dB or less, at most ROUNDS",
    ),
    (
        "staggered-adaptive:DxR@DB[/ROUNDS]",
        "staggered shots (staggered:DxR) averaged until every actuator's estimated error is DB dB or less",
    ),
    (
        "sequential-adaptive:DxR@DB[/ROUNDS]",
        "each actuator alone until its own estimated error is DB dB or less: R periods, then the periods predicted",
    ),
];

/// The protocol called `name` (see the module's table).
///
/// # Errors
/// [`ProtocolNameError::Unknown`] for an unknown name; [`ProtocolNameError::Settings`] naming what is wrong with
/// malformed or out-of-range settings.
pub fn parse(name: &str) -> Result<ExcitationProtocol, ProtocolNameError> {
    let (kind, settings) = match name.split_once(':') {
        Some((k, s)) => (k, Some(s)),
        None => (name, None),
    };
    let bad = |why: &str| ProtocolNameError::Settings { name: name.to_string(), reason: why.to_string() };
    fn need<'a>(s: Option<&'a str>, name: &str) -> Result<&'a str, ProtocolNameError> {
        s.ok_or_else(|| ProtocolNameError::Settings {
            name: name.to_string(),
            reason: "needs settings after `:`".into(),
        })
    }
    let linear = |duration_s: f64| SweepSpec { duration_s, ..SweepSpec::default() };
    let base = |sweep: SweepSpec, repetitions: usize, scheme: Scheme| {
        ExcitationProtocol::new(name, scheme, sweep, repetitions)
    };
    let protocol = match (kind, settings) {
        ("paper", None) => ExcitationProtocol::paper(),
        ("quick", None) => ExcitationProtocol::quick(),
        ("paper" | "quick", Some(_)) => return Err(bad("takes no settings")),
        ("sequential", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d), r, Scheme::Sequential)
        }
        ("sequential-exp", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d).as_exponential(), r, Scheme::Sequential)
        }
        ("hadamard", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            base(linear(d), r, Scheme::Hadamard)
        }
        ("staggered", s) => {
            let (d, r) = duration_by_reps(need(s, name)?).map_err(|e| bad(&e))?;
            if r < 2 {
                return Err(bad("a staggered protocol needs at least 2 periods (its drift and SNR estimates)"));
            }
            base(linear(d), r, Scheme::Staggered)
        }
        ("interleaved", s) => {
            let d = number(need(s, name)?, "duration").map_err(|e| bad(&e))?;
            check_duration(d).map_err(|e| bad(&e))?;
            let sweep = linear(d).as_exponential();
            let ir_s = DeconvConfig::paper().ir_len as f64 / DeconvConfig::paper().sample_rate_hz;
            let advance_s = sweep.exp_rate_s().map_or(0.0, |l| l * 3f64.ln());
            // Whole milliseconds: a whole number of samples at both 24 and 48 kHz (see `Scheme::Interleaved`).
            let slot_s = ((ir_s + advance_s + SLOT_MARGIN_S) * 1000.0).ceil() / 1000.0;
            base(sweep, 1, Scheme::Interleaved { slot_s })
        }
        (kind @ ("adaptive" | "adaptive-error" | "sequential-adaptive" | "staggered-adaptive"), s) => {
            let s = need(s, name)?;
            let quantity = if kind == "adaptive" { "SNR" } else { "error" };
            let (dr, rest) =
                s.split_once('@').ok_or_else(|| bad(&format!("expected DxR@{}[/ROUNDS]", quantity.to_uppercase())))?;
            let (d, r) = duration_by_reps(dr).map_err(|e| bad(&e))?;
            if r < 2 {
                // The SNR and the error estimate are the spread of the periods: one period has none.
                return Err(bad("adaptive averaging needs at least 2 periods per shot (its SNR estimate)"));
            }
            let (value, rounds) = match rest.split_once('/') {
                Some((value, rounds)) => (value, Some(rounds)),
                None => (rest, None),
            };
            let value = number(value, quantity).map_err(|e| bad(&e))?;
            let target = if kind == "adaptive" { AdaptiveTarget::SnrDb(value) } else { AdaptiveTarget::ErrorDb(value) };
            let max_rounds = match rounds {
                Some(r) => r.parse::<usize>().map_err(|_| bad(&format!("rounds `{r}` is not a whole number")))?,
                None => DEFAULT_ROUNDS,
            };
            if !(1..=MAX_ROUNDS).contains(&max_rounds) {
                return Err(bad(&format!("rounds {max_rounds} must be 1 to {MAX_ROUNDS}")));
            }
            let adaptive = Some(Adaptive { target, max_rounds });
            let scheme = match kind {
                "sequential-adaptive" => Scheme::Sequential,
                "staggered-adaptive" => Scheme::Staggered,
                _ => Scheme::Hadamard,
            };
            ExcitationProtocol { adaptive, ..base(linear(d), r, scheme) }
        }
        (other, _) => {
            let known: Vec<&str> = NAMES.iter().map(|(n, _)| *n).collect();
            return Err(ProtocolNameError::Unknown { name: other.to_string(), known: known.join(", ") });
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

/// The help text of a `--protocol` option: every name of [`NAMES`] with what it plays, one per line.
pub fn help_text() -> String {
    let names: Vec<String> = NAMES.iter().map(|(name, what)| format!("  {name}: {what}")).collect();
    format!("Excitation protocol, one of:\n{}", names.join("\n"))
}

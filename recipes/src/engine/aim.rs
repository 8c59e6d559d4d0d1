//! Aiming the beam at a point, with small deterministic nudges when speckle leaves too little signal.

use metaplate_core::rng::{mix64, unit_open};

use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::events::{Observer, RunControl};

/// How to aim: the signal level wanted and how far and how often to nudge for it.
///
/// Valid range: `0 <= min_signal_level <= 1`; finite `nudge_m >= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AimPolicy {
    /// Lowest acceptable signal level, 0 to 1 (below about 0.2 a recording risks dropouts).
    pub min_signal_level: f64,
    /// Nudge distance, m: small beside the grid spacing, large beside a speckle grain.
    pub nudge_m: f64,
    /// Nudges tried before measuring at the best spot found.
    pub max_nudges: u32,
}

impl Default for AimPolicy {
    /// Level 0.2, nudges of 0.3 mm (6 % of the paper's 5 mm spacing), up to 4.
    fn default() -> Self {
        Self { min_signal_level: 0.2, nudge_m: 3e-4, max_nudges: 4 }
    }
}

/// Where the beam ended up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aimed {
    /// Beam position, m.
    pub x_m: f64,
    /// Beam position, m.
    pub y_m: f64,
    /// Signal level there, 0 to 1.
    pub level: f64,
}

/// Offset of nudge `k` on visit `visit` of `unit`, m: zero for the first spot of the first visit, otherwise
/// `nudge_m` in a direction drawn from `(seed, unit, visit, k)` alone, so a resumed run aims exactly where an
/// uninterrupted one did.
pub fn nudge_offset_m(seed: u64, unit: u64, visit: u32, k: u32, nudge_m: f64) -> (f64, f64) {
    if visit == 0 && k == 0 {
        return (0.0, 0.0);
    }
    let key = mix64(mix64(mix64(seed) ^ unit) ^ (u64::from(visit) << 32 | u64::from(k)));
    let angle = std::f64::consts::TAU * unit_open(key);
    (nudge_m * angle.cos(), nudge_m * angle.sin())
}

/// Aims at (`x_m`, `y_m`), nudging up to `policy.max_nudges` times while the level is below the minimum; ends on
/// the best spot seen.
pub(crate) fn aim(
    instruments: &mut Instruments<'_>,
    (x_m, y_m): (f64, f64),
    (seed, unit, visit): (u64, u64, u32),
    policy: &AimPolicy,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<Aimed, RecipeError> {
    let mut best: Option<Aimed> = None;
    for k in 0..=policy.max_nudges {
        let (dx, dy) = nudge_offset_m(seed, unit, visit, k, policy.nudge_m);
        let spot = (x_m + dx, y_m + dy);
        let level = instruments.with_recovery(control, observer, |i| i.aim(spot.0, spot.1))?;
        let here = Aimed { x_m: spot.0, y_m: spot.1, level };
        if level >= policy.min_signal_level {
            return Ok(here);
        }
        tracing::debug!(unit, visit, k, level, "low signal level, nudging");
        if best.is_none_or(|b| level > b.level) {
            best = Some(here);
        }
    }
    let best = best.unwrap_or(Aimed { x_m, y_m, level: 0.0 });
    if (best.x_m, best.y_m) != instruments_beam(instruments) {
        instruments.with_recovery(control, observer, |i| i.aim(best.x_m, best.y_m))?;
    }
    Ok(best)
}

fn instruments_beam(instruments: &Instruments<'_>) -> (f64, f64) {
    instruments.beam().unwrap_or((f64::NAN, f64::NAN))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nudges_are_keyed_and_of_the_stated_length() {
        assert_eq!(nudge_offset_m(1, 2, 0, 0, 1e-3), (0.0, 0.0));
        let a = nudge_offset_m(1, 2, 0, 1, 1e-3);
        assert_eq!(a, nudge_offset_m(1, 2, 0, 1, 1e-3));
        assert_ne!(a, nudge_offset_m(1, 2, 1, 1, 1e-3));
        assert_ne!(a, nudge_offset_m(1, 3, 0, 1, 1e-3));
        // Length exactly nudge_m up to rounding of cos/sin.
        assert!(((a.0 * a.0 + a.1 * a.1).sqrt() - 1e-3).abs() < 1e-15);
    }
}

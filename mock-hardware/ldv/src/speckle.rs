//! The signal level at a beam spot: the scene's speckle model, drawn deterministically per point and seed.

use metaplate_core::scene::LdvSpec;

/// Signal level reported during a dropout, % (well under the class's 20 % dropout-risk mark).
pub const DROPOUT_LEVEL_PERCENT: u8 = 2;

/// Speckle: the level at a point is `mean x (1 + spread x n)`, clamped to 0..1, with `n` a standard normal draw
/// that depends only on the seed and the point (in whole micrometres), so revisiting a point gives its level again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeckleModel {
    mean_level: f64,
    spread: f64,
    seed: u64,
}

impl SpeckleModel {
    /// The model of `spec` (its `speckle_mean_level` and `speckle_spread`, valid as
    /// [`metaplate_core::scene::Scene::validate`] checks them) under `seed`. Out-of-range values are clamped: the
    /// mean to 0..1, the spread to at least 0 (NaN counts as 0), so the model never yields NaN.
    pub fn new(spec: &LdvSpec, seed: u64) -> Self {
        let finite_or_zero = |v: f64| if v.is_finite() { v } else { 0.0 };
        Self {
            mean_level: finite_or_zero(spec.speckle_mean_level).clamp(0.0, 1.0),
            spread: finite_or_zero(spec.speckle_spread).max(0.0),
            seed,
        }
    }

    /// The level at (`x_um`, `y_um`), integer % from 0 to 100.
    pub fn level_percent(&self, x_um: i32, y_um: i32) -> u8 {
        // Two independent uniforms in (0, 1) from the point, then Box-Muller.
        let key = (u64::from(x_um as u32) << 32) | u64::from(y_um as u32);
        let u1 = unit(mix(self.seed ^ mix(key)));
        let u2 = unit(mix(self.seed.wrapping_add(1) ^ mix(key ^ 0xA5A5_A5A5_A5A5_A5A5)));
        let normal = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        let level = (self.mean_level * (1.0 + self.spread * normal)).clamp(0.0, 1.0);
        // 0..=100 after the clamp, so the cast cannot truncate.
        (level * 100.0).round() as u8
    }
}

pub(crate) use metaplate_core::rng::{mix64 as mix, unit_open as unit};

/// A quiet, undisturbed vibrometer for demos and tests of the controller alone: 1 um/s noise, speckle around 0.7
/// (spread 0.2), no dropouts, no aim error, 0.25 m/s full scale.
pub fn quiet_spec() -> LdvSpec {
    LdvSpec {
        noise_rms_m_s: 1e-6,
        speckle_mean_level: 0.7,
        speckle_spread: 0.2,
        dropout_probability: 0.0,
        max_velocity_m_s: 0.25,
        aim_error_rms_m: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(mean: f64, spread: f64) -> LdvSpec {
        LdvSpec {
            noise_rms_m_s: 0.0,
            speckle_mean_level: mean,
            speckle_spread: spread,
            dropout_probability: 0.0,
            max_velocity_m_s: 1.0,
            aim_error_rms_m: 0.0,
        }
    }

    #[test]
    fn levels_are_repeatable_and_follow_the_mean() {
        let model = SpeckleModel::new(&spec(0.6, 0.2), 7);
        let points: Vec<(i32, i32)> = (0..2000).map(|i| (i * 5000 - 5_000_000 / 2, (i % 37) * 5000)).collect();
        let levels: Vec<u8> = points.iter().map(|&(x, y)| model.level_percent(x, y)).collect();
        let again: Vec<u8> = points.iter().map(|&(x, y)| model.level_percent(x, y)).collect();
        assert_eq!(levels, again);
        let mean = levels.iter().map(|&l| f64::from(l)).sum::<f64>() / levels.len() as f64;
        // Standard error of the mean: 12 % / sqrt(2000) = 0.27 %; 1.5 % is over 5 of them plus rounding.
        assert!((mean - 60.0).abs() < 1.5, "mean level {mean} %");
        // Another seed gives another pattern.
        let other = SpeckleModel::new(&spec(0.6, 0.2), 8);
        assert_ne!(levels, points.iter().map(|&(x, y)| other.level_percent(x, y)).collect::<Vec<_>>());
    }

    #[test]
    fn extremes_stay_in_range() {
        for (mean, spread) in [(0.0, 0.0), (1.0, 0.0), (1.0, 100.0), (f64::NAN, f64::INFINITY), (2.0, -1.0)] {
            let model = SpeckleModel::new(&spec(mean, spread), 1);
            for (x, y) in [(i32::MIN, i32::MAX), (0, 0), (500_000, -500_000)] {
                assert!(model.level_percent(x, y) <= 100, "mean {mean} spread {spread}");
            }
        }
        // No spread: exactly the mean everywhere.
        assert_eq!(SpeckleModel::new(&spec(1.0, 0.0), 3).level_percent(12, 34), 100);
        assert_eq!(SpeckleModel::new(&spec(0.0, 5.0), 3).level_percent(12, 34), 0);
    }
}

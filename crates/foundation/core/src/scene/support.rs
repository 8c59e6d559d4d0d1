//! Supports: the compliant pads the plate rests on.

use serde::{Deserialize, Serialize};

use super::outline::EDGE_TOLERANCE_M;

/// One support pad under the plate: a square foam block, modelled as a damped spring to ground.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): the whole pad on the plate, finite `size_m > 0`,
/// `stiffness_n_per_m > 0`, `loss_factor >= 0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    /// Centre x, m.
    pub x_m: f64,
    /// Centre y, m.
    pub y_m: f64,
    /// Edge of the square pad, m.
    pub size_m: f64,
    /// Vertical stiffness of the pad, N/m.
    pub stiffness_n_per_m: f64,
    /// Loss factor of the pad material (dimensionless).
    pub loss_factor: f64,
}

impl SupportSpec {
    /// True when `(x_m, y_m)` (m) lies on the pad's square, edge included (within [`EDGE_TOLERANCE_M`]).
    pub fn covers(&self, x_m: f64, y_m: f64) -> bool {
        let h = self.size_m / 2.0 + EDGE_TOLERANCE_M;
        (x_m - self.x_m).abs() <= h && (y_m - self.y_m).abs() <= h
    }
}

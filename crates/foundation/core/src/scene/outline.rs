//! The plate's outline: a Bunimovich stadium or a rectangle, centred on the origin, long axis along x.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

/// How far outside an edge a point may be and still count as on it, m. Coordinates built from decimal millimetres
/// carry rounding errors of ~1e-17 m; without this, a grid point exactly on the edge (the stadium's 3-4-5 points,
/// such as (0.095, 0.06) m) would fall on either side by chance. A nanometre is far below any physical length.
pub const EDGE_TOLERANCE_M: f64 = 1e-9;

/// The shape of the plate seen from above.
///
/// TOML: `outline = { shape = "stadium", straight_length_m = 0.10, radius_m = 0.075 }` or
/// `outline = { shape = "rectangle", width_m = 0.25, height_m = 0.15 }`.
///
/// Valid range: stadium `straight_length_m >= 0` (0 is a disc), `radius_m > 0`; rectangle `width_m, height_m > 0`;
/// all finite (checked by [`crate::scene::Scene::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Outline {
    /// Two half-discs of radius `radius_m` joined by straight edges of length `straight_length_m` (the paper's
    /// l = 0.10 m, r = 0.075 m: 0.25 x 0.15 m). Its billiard is ergodic, which spreads the plate's modes.
    Stadium {
        /// Length of each straight edge, m (the distance between the two half-discs' centres).
        straight_length_m: f64,
        /// Radius of the half-discs, m (half the plate's width).
        radius_m: f64,
    },
    /// An axis-aligned rectangle.
    Rectangle {
        /// Extent along x, m.
        width_m: f64,
        /// Extent along y, m.
        height_m: f64,
    },
}

impl Outline {
    /// Signed distance from `(x_m, y_m)` to the nearest edge, m: positive inside, zero on the edge, negative
    /// outside. Exact for both shapes (both are convex).
    pub fn distance_inside_m(&self, x_m: f64, y_m: f64) -> f64 {
        match *self {
            Outline::Stadium { straight_length_m, radius_m } => {
                // A stadium is the set of points within radius_m of its central segment.
                let dx = (x_m.abs() - straight_length_m / 2.0).max(0.0);
                radius_m - dx.hypot(y_m)
            }
            Outline::Rectangle { width_m, height_m } => {
                let ex = x_m.abs() - width_m / 2.0;
                let ey = y_m.abs() - height_m / 2.0;
                if ex <= 0.0 && ey <= 0.0 { -(ex.max(ey)) } else { -(ex.max(0.0).hypot(ey.max(0.0))) }
            }
        }
    }

    /// True when `(x_m, y_m)` (m) is on the plate, edge included (within [`EDGE_TOLERANCE_M`]).
    pub fn contains(&self, x_m: f64, y_m: f64) -> bool {
        self.distance_inside_m(x_m, y_m) >= -EDGE_TOLERANCE_M
    }

    /// True when the whole axis-aligned square of edge `size_m` (m) centred on `(x_m, y_m)` is on the plate. The
    /// outlines are convex, so checking the four corners is enough.
    pub fn contains_square(&self, x_m: f64, y_m: f64, size_m: f64) -> bool {
        let h = size_m / 2.0;
        [(-h, -h), (-h, h), (h, -h), (h, h)].iter().all(|&(dx, dy)| self.contains(x_m + dx, y_m + dy))
    }

    /// `(x_min, x_max, y_min, y_max)`, m.
    pub fn bounding_box_m(&self) -> (f64, f64, f64, f64) {
        let (half_x, half_y) = match *self {
            Outline::Stadium { straight_length_m, radius_m } => (straight_length_m / 2.0 + radius_m, radius_m),
            Outline::Rectangle { width_m, height_m } => (width_m / 2.0, height_m / 2.0),
        };
        (-half_x, half_x, -half_y, half_y)
    }

    /// Area, m^2.
    pub fn area_m2(&self) -> f64 {
        match *self {
            Outline::Stadium { straight_length_m, radius_m } => {
                2.0 * radius_m * straight_length_m + PI * radius_m.powi(2)
            }
            Outline::Rectangle { width_m, height_m } => width_m * height_m,
        }
    }

    /// Radius of the largest disc that fits inside, m: no point is farther than this from the edge.
    pub fn inradius_m(&self) -> f64 {
        match *self {
            Outline::Stadium { radius_m, .. } => radius_m,
            Outline::Rectangle { width_m, height_m } => width_m.min(height_m) / 2.0,
        }
    }
}

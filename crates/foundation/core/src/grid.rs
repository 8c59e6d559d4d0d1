//! Rectangular measurement grids: where the vibrometer looks.
//!
//! Coordinates are in metres, centred on the plate centre, x along the plate's long axis. Point `(ix, iy)` lies at
//! `(origin_x_m + ix * spacing_m, origin_y_m + iy * spacing_m)` and has the flat index `iy * nx + ix` (row-major, rows
//! along x). Whether a point is on the plate is the scene's business ([`crate::scene::Scene::grid_mask`]).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The largest grid accepted: 10^6 points (the paper's has 1225; a million already means weeks of scanning).
pub const MAX_GRID_POINTS: usize = 1_000_000;

/// Why a grid or a grid subset was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// A grid parameter lies outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Field name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// A subset asked for more points along an axis than the grid has, or for none.
    #[error("a {nx_sub} x {ny_sub} subset does not fit a {nx} x {ny} grid (each side must be 1 ..= the grid's)")]
    BadSubset {
        /// Requested points along x.
        nx_sub: usize,
        /// Requested points along y.
        ny_sub: usize,
        /// The grid's points along x.
        nx: usize,
        /// The grid's points along y.
        ny: usize,
    },
    /// Positions that do not lie on a regular grid (see [`snap_to_grid`]).
    #[error("the positions do not form a regular grid: {reason}")]
    NotRegular {
        /// Why, naming a position where it helps.
        reason: String,
    },
    /// A grid-subset text (`NXxNY`) that could not be read, or asks for fewer points than its use needs.
    #[error("grid subset `{text}`: {reason}")]
    BadSubsetText {
        /// The text as given.
        text: String,
        /// What was wrong and what is accepted.
        reason: String,
    },
}

/// An evenly spread `nx` x `ny` subset of a grid, as a command line writes it: `NXxNY` (for example `7x5`; `X` is
/// accepted for `x`, spaces around the numbers are ignored). Both sides are whole numbers of at least 1; whether it
/// fits a given grid is checked by [`GridSubset::indices`] ([`GridSpec::subset`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct GridSubset {
    /// Points along x.
    pub nx: usize,
    /// Points along y.
    pub ny: usize,
}

impl GridSubset {
    /// The subset, if each side has at least `min_side` points (a use that needs a two-dimensional field, for
    /// example a wavenumber estimate, asks for 2).
    ///
    /// # Errors
    /// [`GridError::BadSubsetText`] when a side is smaller.
    pub fn at_least(self, min_side: usize) -> Result<Self, GridError> {
        if self.nx < min_side || self.ny < min_side {
            return Err(GridError::BadSubsetText {
                text: self.to_string(),
                reason: format!("each side must be at least {min_side} here"),
            });
        }
        Ok(self)
    }

    /// The subset's flat indices in `grid` ([`GridSpec::subset`]).
    ///
    /// # Errors
    /// [`GridError::BadSubset`] when the subset is larger than the grid along a side.
    pub fn indices(self, grid: &GridSpec) -> Result<Vec<usize>, GridError> {
        grid.subset(self.nx, self.ny)
    }
}

impl From<GridSubset> for (usize, usize) {
    fn from(s: GridSubset) -> Self {
        (s.nx, s.ny)
    }
}

impl fmt::Display for GridSubset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.nx, self.ny)
    }
}

impl FromStr for GridSubset {
    type Err = GridError;

    fn from_str(text: &str) -> Result<Self, GridError> {
        let bad = |reason: String| GridError::BadSubsetText { text: text.to_owned(), reason };
        let Some((a, b)) = text.split_once(['x', 'X']) else {
            return Err(bad("expected NXxNY, for example 7x5".to_owned()));
        };
        let side = |s: &str, axis: &str| -> Result<usize, GridError> {
            let s = s.trim();
            if s.is_empty() {
                return Err(bad(format!(
                    "the number of points along {axis} is missing (expected NXxNY, for example 7x5)"
                )));
            }
            let n: usize = s.parse().map_err(|_| bad(format!("`{s}` (points along {axis}) is not a whole number")))?;
            if n == 0 {
                return Err(bad(format!("the number of points along {axis} must be at least 1")));
            }
            Ok(n)
        };
        Ok(Self { nx: side(a, "x")?, ny: side(b, "y")? })
    }
}

/// A uniform rectangular grid of measurement points.
///
/// Valid range (see [`GridSpec::validate`]): `nx, ny >= 1`, `nx * ny <=` [`MAX_GRID_POINTS`], finite
/// `spacing_m > 0`, finite origin.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Points along x.
    pub nx: usize,
    /// Points along y.
    pub ny: usize,
    /// Distance between neighbouring points, m.
    pub spacing_m: f64,
    /// x of point (0, 0), m.
    pub origin_x_m: f64,
    /// y of point (0, 0), m.
    pub origin_y_m: f64,
}

impl GridSpec {
    /// An `nx` x `ny` grid with spacing `spacing_m` (m) whose centre is the origin of coordinates.
    ///
    /// Not validated here: call [`GridSpec::validate`] before trusting it.
    pub fn centred(nx: usize, ny: usize, spacing_m: f64) -> Self {
        let half_extent = |n: usize| -(n.saturating_sub(1) as f64) * spacing_m / 2.0;
        Self { nx, ny, spacing_m, origin_x_m: half_extent(nx), origin_y_m: half_extent(ny) }
    }

    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`GridError::InvalidParameter`] naming the offending field.
    pub fn validate(&self) -> Result<(), GridError> {
        let invalid = |name: &'static str, reason: String| Err(GridError::InvalidParameter { name, reason });
        if self.nx == 0 || self.ny == 0 {
            let name = if self.nx == 0 { "nx" } else { "ny" };
            return invalid(name, format!("the grid is empty ({} x {} points)", self.nx, self.ny));
        }
        match self.nx.checked_mul(self.ny) {
            Some(n) if n <= MAX_GRID_POINTS => {}
            _ => {
                return invalid(
                    "nx",
                    format!("{} x {} points exceed the limit of {MAX_GRID_POINTS}", self.nx, self.ny),
                );
            }
        }
        if !(self.spacing_m.is_finite() && self.spacing_m > 0.0) {
            return invalid("spacing_m", format!("must be finite and positive, got {}", self.spacing_m));
        }
        for (name, v) in [("origin_x_m", self.origin_x_m), ("origin_y_m", self.origin_y_m)] {
            if !v.is_finite() {
                return invalid(name, format!("must be finite, got {v}"));
            }
        }
        Ok(())
    }

    /// Number of points, `nx * ny` (saturating, so an absurd unvalidated grid cannot overflow).
    pub fn len(&self) -> usize {
        self.nx.saturating_mul(self.ny)
    }

    /// True when the grid has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of point `(ix, iy)`: `iy * nx + ix` (saturating). Not range-checked: `ix >= nx` aliases into the
    /// next row, as the formula says.
    pub fn index(&self, ix: usize, iy: usize) -> usize {
        iy.saturating_mul(self.nx).saturating_add(ix)
    }

    /// Grid indices `(ix, iy)` of flat index `index`, the inverse of [`GridSpec::index`]. An index beyond
    /// [`GridSpec::len`] gives `iy >= ny`; a grid with `nx == 0` (invalid) gives `(0, index)` rather than dividing
    /// by zero.
    pub fn indices(&self, index: usize) -> (usize, usize) {
        let nx = self.nx.max(1);
        (index % nx, index / nx)
    }

    /// Position `(x_m, y_m)` of flat index `index`, m. An index beyond [`GridSpec::len`] gives the position the
    /// formula extrapolates to.
    pub fn position_m(&self, index: usize) -> (f64, f64) {
        let (ix, iy) = self.indices(index);
        (self.origin_x_m + ix as f64 * self.spacing_m, self.origin_y_m + iy as f64 * self.spacing_m)
    }

    /// An evenly spread `nx_sub` x `ny_sub` subset of the grid's flat indices, row by row (iy outer, ix inner,
    /// both ascending); for `--grid 7x5`.
    ///
    /// Along each axis the grid is cut into `n_sub` equal bins and the point nearest each bin's centre is taken:
    /// the subset is centred and symmetric, avoids the corners (usually off a round plate), and is the whole grid
    /// when `n_sub == n`.
    ///
    /// # Errors
    /// [`GridError::BadSubset`] when a side is 0 or larger than the grid's.
    pub fn subset(&self, nx_sub: usize, ny_sub: usize) -> Result<Vec<usize>, GridError> {
        if nx_sub == 0 || ny_sub == 0 || nx_sub > self.nx || ny_sub > self.ny {
            return Err(GridError::BadSubset { nx_sub, ny_sub, nx: self.nx, ny: self.ny });
        }
        let xs = spread(self.nx, nx_sub);
        let ys = spread(self.ny, ny_sub);
        Ok(ys.iter().flat_map(|&iy| xs.iter().map(move |&ix| (ix, iy))).map(|(ix, iy)| self.index(ix, iy)).collect())
    }

    /// The scan path through `indices`: row by row with ascending `iy`, alternating direction (the first row
    /// visited runs towards +x, the next towards -x, ...), so the beam never flies back across the plate.
    /// Duplicates are dropped; indices are not range-checked.
    pub fn serpentine_order(&self, indices: &[usize]) -> Vec<usize> {
        let mut cells: Vec<(usize, usize)> = indices.iter().map(|&i| self.indices(i)).collect();
        cells.sort_unstable_by_key(|&(ix, iy)| (iy, ix));
        cells.dedup();
        let mut out = Vec::with_capacity(cells.len());
        // Alternate by the ordinal of the row among the rows present, not by iy's parity: a subset may skip rows.
        for (row, chunk) in cells.chunk_by(|a, b| a.1 == b.1).enumerate() {
            let row_indices = chunk.iter().map(|&(ix, iy)| self.index(ix, iy));
            if row % 2 == 0 { out.extend(row_indices) } else { out.extend(row_indices.rev()) }
        }
        out
    }
}

/// `n_sub` indices in `0..n`, nearest the centres of `n_sub` equal bins. Requires `1 <= n_sub <= n`: the bin width
/// is then >= 1, so the rounded centres are distinct and ascending.
fn spread(n: usize, n_sub: usize) -> Vec<usize> {
    let bin = n as f64 / n_sub as f64;
    (0..n_sub).map(|k| (((k as f64 + 0.5) * bin - 0.5).round() as usize).min(n - 1)).collect()
}

/// Distance within which two coordinates are the same and a position lies on a grid node in [`snap_to_grid`], m
/// (1 µm: far below any scanning vibrometer's positioning, far above the rounding of coordinates written with 17
/// digits).
pub const SNAP_TOLERANCE_M: f64 = 1e-6;

/// The regular grid that `positions_m` (x, y in m, from an untrusted file) lie on, and each position's flat index
/// in it: the spacing is the largest step that every difference between distinct x and y coordinates is a whole
/// multiple of (within [`SNAP_TOLERANCE_M`]), the origin is the smallest x and y, and the grid spans the positions.
///
/// # Errors
/// [`GridError::NotRegular`] saying why: no position, a non-finite one, a single distinct position (no spacing),
/// a spacing below a sixteenth of the smallest difference (positions that are not a grid, only noisy ones), two
/// positions on one node, a grid of more than [`MAX_GRID_POINTS`].
pub fn snap_to_grid(positions_m: &[(f64, f64)]) -> Result<(GridSpec, Vec<usize>), GridError> {
    let refuse = |reason: String| Err(GridError::NotRegular { reason });
    if positions_m.is_empty() {
        return refuse("no position".into());
    }
    if let Some((i, p)) = positions_m.iter().enumerate().find(|(_, p)| !(p.0.is_finite() && p.1.is_finite())) {
        return refuse(format!("position {i} is not finite: {p:?}"));
    }
    let tol = SNAP_TOLERANCE_M;
    // Differences between neighbouring distinct coordinates, along both axes.
    let mut gaps = Vec::new();
    for axis in [0, 1] {
        let mut values: Vec<f64> = positions_m.iter().map(|p| if axis == 0 { p.0 } else { p.1 }).collect();
        values.sort_unstable_by(f64::total_cmp);
        gaps.extend(values.windows(2).map(|w| w[1] - w[0]).filter(|&g| g > tol));
    }
    let Some(min_gap) = gaps.iter().copied().reduce(f64::min) else {
        return refuse("all positions are one point: there is no spacing to find".into());
    };
    // Approximate greatest common divisor of the gaps (Euclid, remainders within the tolerance count as zero).
    let mut spacing_m = min_gap;
    for &gap in &gaps {
        let (mut a, mut b) = (gap.max(spacing_m), gap.min(spacing_m));
        while b > tol && a / b < 1e9 {
            let r = a % b;
            let r = if b - r <= tol { 0.0 } else { r };
            (a, b) = (b, r);
        }
        spacing_m = a;
        if spacing_m < min_gap / 16.0 {
            return refuse(format!(
                "the coordinates' differences have no common step of at least a sixteenth of the smallest one                  ({:.4} mm): they are not the nodes of a grid",
                min_gap * 1e3
            ));
        }
    }
    let x0 = positions_m.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let y0 = positions_m.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    // The longest span over its number of steps: the spacing to the positions' own precision, not Euclid's.
    let span_m = positions_m.iter().map(|p| (p.0 - x0).max(p.1 - y0)).fold(0.0, f64::max);
    let span_steps = (span_m / spacing_m).round();
    if span_steps >= 1.0 {
        spacing_m = span_m / span_steps;
    }
    let steps = |v: f64, v0: f64| ((v - v0) / spacing_m).round();
    let (mut nx, mut ny) = (1.0f64, 1.0f64);
    for &(x, y) in positions_m {
        nx = nx.max(steps(x, x0) + 1.0);
        ny = ny.max(steps(y, y0) + 1.0);
    }
    if nx * ny > MAX_GRID_POINTS as f64 {
        return refuse(format!(
            "a {nx} x {ny} grid at {:.4} mm spacing exceeds the limit of {MAX_GRID_POINTS} points",
            spacing_m * 1e3
        ));
    }
    // Both at most MAX_GRID_POINTS (checked above), so the conversions are exact.
    let grid = GridSpec { nx: nx as usize, ny: ny as usize, spacing_m, origin_x_m: x0, origin_y_m: y0 };
    let mut taken = vec![usize::MAX; grid.len()];
    let mut indices = Vec::with_capacity(positions_m.len());
    for (i, &(x, y)) in positions_m.iter().enumerate() {
        let (ix, iy) = (steps(x, x0), steps(y, y0));
        let off_m = (x - x0 - ix * spacing_m).hypot(y - y0 - iy * spacing_m);
        if off_m > tol.max(spacing_m * 1e-6) {
            return refuse(format!(
                "position {i} ({x} m, {y} m) lies {:.4} mm from the nearest node of the {} x {} grid at {:.4} mm",
                off_m * 1e3,
                grid.nx,
                grid.ny,
                spacing_m * 1e3
            ));
        }
        let index = grid.index(ix as usize, iy as usize);
        match taken.get_mut(index) {
            Some(slot) if *slot == usize::MAX => *slot = i,
            Some(slot) => return refuse(format!("positions {} and {i} lie on the same node ({x} m, {y} m)", *slot)),
            None => return refuse(format!("position {i} falls outside the grid")),
        }
        indices.push(index);
    }
    grid.validate()?;
    Ok((grid, indices))
}

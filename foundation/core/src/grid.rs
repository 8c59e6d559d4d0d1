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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_subset_reads_nx_by_ny() {
        assert_eq!("7x5".parse(), Ok(GridSubset { nx: 7, ny: 5 }));
        assert_eq!(" 7 X 5 ".parse(), Ok(GridSubset { nx: 7, ny: 5 }));
        assert_eq!("1x1".parse(), Ok(GridSubset { nx: 1, ny: 1 }));
        assert_eq!(GridSubset { nx: 7, ny: 5 }.to_string(), "7x5");
        assert_eq!(<(usize, usize)>::from(GridSubset { nx: 7, ny: 5 }), (7, 5));
    }

    #[test]
    fn grid_subset_refuses_bad_text_with_the_reason() {
        let reason = |text: &str| match text.parse::<GridSubset>() {
            Err(GridError::BadSubsetText { text: t, reason }) if t == text => reason,
            other => panic!("`{text}`: {other:?}"),
        };
        assert!(reason("0x5").contains("along x must be at least 1"));
        assert!(reason("5x0").contains("along y must be at least 1"));
        assert!(reason("5x").contains("along y is missing"));
        assert!(reason("x5").contains("along x is missing"));
        assert!(reason("axb").contains("`a` (points along x) is not a whole number"));
        assert!(reason("7x5x3").contains("`5x3`"));
        assert!(reason("-1x5").contains("not a whole number"));
        assert!(reason("75").contains("expected NXxNY"));
        assert!(reason("").contains("expected NXxNY"));
        assert!(reason("99999999999999999999999x1").contains("not a whole number"));
    }

    #[test]
    fn grid_subset_checks_its_use_and_the_grid() {
        let one: GridSubset = "1x1".parse().unwrap();
        assert!(matches!(one.at_least(2), Err(GridError::BadSubsetText { .. })));
        let two: GridSubset = "2x3".parse().unwrap();
        assert_eq!(two.at_least(2), Ok(two));
        let g = GridSpec::centred(7, 5, 0.01);
        assert_eq!("7x5".parse::<GridSubset>().unwrap().indices(&g).unwrap().len(), 35);
        assert_eq!(one.indices(&g).unwrap(), vec![g.index(3, 2)]);
        assert!(matches!(
            "8x5".parse::<GridSubset>().unwrap().indices(&g),
            Err(GridError::BadSubset { nx_sub: 8, ny_sub: 5, nx: 7, ny: 5 })
        ));
    }

    #[test]
    fn centred_paper_grid() {
        let g = GridSpec::centred(49, 25, 0.005);
        // Exact multiples of 5 mm up to rounding of the products: 1e-15 m is far below any physical length.
        assert!((g.origin_x_m + 0.12).abs() < 1e-15 && (g.origin_y_m + 0.06).abs() < 1e-15);
        assert_eq!(g.len(), 1225);
        let (x, y) = g.position_m(g.index(48, 24));
        assert!((x - 0.12).abs() < 1e-15 && (y - 0.06).abs() < 1e-15);
        assert_eq!(g.indices(g.index(17, 9)), (17, 9));
    }
}

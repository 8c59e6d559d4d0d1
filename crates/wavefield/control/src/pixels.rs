//! Where a pixel can be focused: on the plate, and close enough to a measured point that the focus lands where it
//! was asked. `metaplate focus` and `metaplate play` snap their pixels here.
//!
//! The plate's outline is the built-in scene's when the dataset was made on an unchanged built-in scene (same name
//! and content hash); otherwise the measured grid's bounds widened by half a spacing. A pixel snaps to the nearest
//! measured point, and is refused when that point is more than half the measured lattice's step away along either
//! axis (a gap of the scan: a support, a masked point, or outside the measured points' hull).
//!
//! Scattered points (`metaplate_store::ScatteredPoints`, an imported scan mesh) have no outline and no lattice: a
//! pixel snaps to the nearest point (by their positions in the points' plane), refused when farther than
//! [`SCATTERED_REACH`] of that point's distance to its own nearest neighbour (the corner of its cell on a square
//! mesh; `√3/3` on a triangular one, which it covers).
//!
//! [`PointSelection`] leaves out the points whose Green's functions are estimated too inaccurate (each row's
//! `estimated_error_db`, from the spread of its repetitions): `analyze` and `focus` use only the points it keeps.

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::Scene;
use metaplate_store::Dataset;

use crate::error::ControlError;

/// How far from a scattered point a pixel snaps to it, in that point's nearest-neighbour distances: `√2/2`.
pub const SCATTERED_REACH: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The plate's outline test of `dataset`, as the module documentation says: `(x_m, y_m) -> on the plate`.
pub fn on_plate(dataset: &Dataset) -> impl Fn(f64, f64) -> bool + use<> {
    let meta = &dataset.manifest().meta;
    let scene = Scene::builtin(&meta.scene.name).ok().filter(|s| s.id() == meta.scene);
    let grid = meta.grid;
    let scattered = meta.scattered.is_some();
    move |x_m, y_m| match &scene {
        Some(scene) => scene.plate.outline.contains(x_m, y_m),
        // No outline: the distance to the points decides (`snap_pixel`).
        None if scattered => true,
        None => {
            let h = grid.spacing_m / 2.0;
            let (x1, y1) = grid.position_m(grid.index(grid.nx - 1, grid.ny - 1));
            (grid.origin_x_m - h..=x1 + h).contains(&x_m) && (grid.origin_y_m - h..=y1 + h).contains(&y_m)
        }
    }
}

/// Spacing of the measured points along one axis: the smallest positive gap between their coordinates, or the
/// grid's spacing when all share one coordinate.
fn lattice_step_m(coords: impl Iterator<Item = f64>, grid: &GridSpec) -> f64 {
    let mut c: Vec<f64> = coords.collect();
    c.sort_unstable_by(f64::total_cmp);
    // Gaps below a micrometre are the same grid column (rounding of the positions).
    let step = c.windows(2).map(|w| w[1] - w[0]).filter(|&d| d > 1e-6).fold(f64::INFINITY, f64::min);
    if step.is_finite() { step } else { grid.spacing_m }
}

/// The measured point (grid flat index) a pixel at `(x_m, y_m)` snaps to, with `on_plate` the outline test (from
/// [`on_plate`]).
///
/// # Errors
/// [`ControlError::PixelOffPlate`] outside the outline (or non-finite coordinates), [`ControlError::PixelInGap`]
/// farther than half the measured step from the nearest measured point ([`ControlError::PixelOffPoints`] beyond
/// a scattered point's reach), [`ControlError::Empty`] for a dataset without points.
pub fn snap_pixel(
    dataset: &Dataset,
    x_m: f64,
    y_m: f64,
    on_plate: &impl Fn(f64, f64) -> bool,
) -> Result<u32, ControlError> {
    if !(x_m.is_finite() && y_m.is_finite() && on_plate(x_m, y_m)) {
        return Err(ControlError::PixelOffPlate { x_m, y_m });
    }
    let meta = &dataset.manifest().meta;
    let grid = meta.grid;
    let positions: Vec<(u32, (f64, f64))> =
        dataset.points().iter().map(|&p| (p, meta.position_m(p as usize).unwrap_or((f64::NAN, f64::NAN)))).collect();
    if meta.scattered.is_some() {
        return snap_scattered(&positions, (x_m, y_m));
    }
    let step_x = lattice_step_m(positions.iter().map(|p| p.1.0), &grid);
    let step_y = lattice_step_m(positions.iter().map(|p| p.1.1), &grid);
    let at = (x_m, y_m);
    let Some(&(point, (px, py))) = positions.iter().min_by(|a, b| dist2(a.1, at).total_cmp(&dist2(b.1, at))) else {
        return Err(ControlError::Empty { input: "the dataset's measured points" });
    };
    // Half a step of the measured lattice each way, with a little slack for coordinates typed in decimal.
    let slack = 1.0 + 1e-9;
    if (px - x_m).abs() > step_x / 2.0 * slack || (py - y_m).abs() > step_y / 2.0 * slack {
        return Err(ControlError::PixelInGap {
            x_m,
            y_m,
            distance_mm: dist2((px, py), at).sqrt() * 1e3,
            nearest_m: (px, py),
            step_mm: (step_x * 1e3, step_y * 1e3),
        });
    }
    Ok(point)
}

/// The scattered point of `positions` (index, position, m) a pixel at `at` snaps to (see the module documentation).
fn snap_scattered(positions: &[(u32, (f64, f64))], at: (f64, f64)) -> Result<u32, ControlError> {
    let nearest_to = |q: (f64, f64), skip: Option<u32>| {
        positions.iter().filter(|p| Some(p.0) != skip).min_by(|a, b| dist2(a.1, q).total_cmp(&dist2(b.1, q))).copied()
    };
    let Some((point, p)) = nearest_to(at, None) else {
        return Err(ControlError::Empty { input: "the dataset's measured points" });
    };
    // A lone point reaches as far as nothing measures: only the pixel on it.
    let reach_m = nearest_to(p, Some(point)).map_or(0.0, |(_, q)| dist2(p, q).sqrt() * SCATTERED_REACH);
    let distance_m = dist2(p, at).sqrt();
    if distance_m > reach_m * (1.0 + 1e-9) + 1e-12 {
        return Err(ControlError::PixelOffPoints {
            x_m: at.0,
            y_m: at.1,
            distance_mm: distance_m * 1e3,
            nearest_m: p,
            limit_mm: reach_m * 1e3,
        });
    }
    Ok(point)
}

fn dist2(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)
}

/// Which of a dataset's points to use, by their rows' estimated errors (the `estimated_error_db` column).
#[derive(Debug, Clone, PartialEq)]
pub struct PointSelection {
    /// The limit, dB: a point is left out when any of its rows' estimated error exceeds it.
    pub max_error_db: f64,
    /// The points kept, ascending (grid flat indices).
    pub kept: Vec<u32>,
    /// The points left out, ascending, each with its worst row's estimated error, dB.
    pub excluded: Vec<(u32, f64)>,
    /// Kept points with at least one row that has no estimate (a simulation, one period per shot): nothing says
    /// they are worse than the limit.
    pub without_estimate: usize,
}

impl PointSelection {
    /// Selects the points of `dataset` whose every row's estimated error is at most `max_error_db`.
    ///
    /// Valid range: `max_error_db` not NaN (infinite keeps every point).
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for a NaN limit; [`ControlError::Empty`] when no point is kept.
    pub fn by_estimated_error(dataset: &Dataset, max_error_db: f64) -> Result<PointSelection, ControlError> {
        if max_error_db.is_nan() {
            return Err(ControlError::InvalidParameter { name: "max_error_db", reason: "is NaN".into() });
        }
        let mut worst: std::collections::BTreeMap<u32, (Option<f64>, bool)> = std::collections::BTreeMap::new();
        for row in dataset.rows() {
            let entry = worst.entry(row.point_index).or_insert((None, false));
            match row.estimated_error_db {
                Some(e) => entry.0 = Some(entry.0.map_or(e, |w: f64| w.max(e))),
                None => entry.1 = true,
            }
        }
        let mut selection =
            PointSelection { max_error_db, kept: Vec::new(), excluded: Vec::new(), without_estimate: 0 };
        for (point, (error_db, unestimated)) in worst {
            match error_db {
                Some(e) if e > max_error_db => selection.excluded.push((point, e)),
                _ => {
                    selection.kept.push(point);
                    selection.without_estimate += usize::from(unestimated);
                }
            }
        }
        if selection.kept.is_empty() {
            return Err(ControlError::Empty { input: "the points within the estimated-error limit" });
        }
        Ok(selection)
    }

    /// Refuses a pixel whose point (from [`snap_pixel`]) was left out.
    ///
    /// # Errors
    /// [`ControlError::PixelExcluded`] naming the point and its estimated error.
    pub fn check_pixel(&self, x_m: f64, y_m: f64, point_index: u32) -> Result<(), ControlError> {
        match self.excluded.binary_search_by_key(&point_index, |e| e.0) {
            Ok(i) => Err(ControlError::PixelExcluded {
                x_m,
                y_m,
                point_index,
                error_db: self.excluded[i].1,
                max_error_db: self.max_error_db,
            }),
            Err(_) => Ok(()),
        }
    }
}

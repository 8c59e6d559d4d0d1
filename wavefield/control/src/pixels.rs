//! Where a pixel can be focused: on the plate, and close enough to a measured point that the focus lands where it
//! was asked. `metaplate focus` and `metaplate play` snap their pixels here.
//!
//! The plate's outline is the built-in scene's when the dataset was made on an unchanged built-in scene (same name
//! and content hash); otherwise the measured grid's bounds widened by half a spacing. A pixel snaps to the nearest
//! measured point, and is refused when that point is more than half the measured lattice's step away along either
//! axis (a gap of the scan: a support, a masked point, or outside the measured points' hull).

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::Scene;
use metaplate_store::Dataset;

use crate::error::ControlError;

/// The plate's outline test of `dataset`, as the module documentation says: `(x_m, y_m) -> on the plate`.
pub fn on_plate(dataset: &Dataset) -> impl Fn(f64, f64) -> bool + use<> {
    let meta = &dataset.manifest().meta;
    let scene = Scene::builtin(&meta.scene.name).ok().filter(|s| s.id() == meta.scene);
    let grid = meta.grid;
    move |x_m, y_m| match &scene {
        Some(scene) => scene.plate.outline.contains(x_m, y_m),
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
/// farther than half the measured step from the nearest measured point, [`ControlError::Empty`] for a dataset
/// without points.
pub fn snap_pixel(
    dataset: &Dataset,
    x_m: f64,
    y_m: f64,
    on_plate: &impl Fn(f64, f64) -> bool,
) -> Result<u32, ControlError> {
    if !(x_m.is_finite() && y_m.is_finite() && on_plate(x_m, y_m)) {
        return Err(ControlError::PixelOffPlate { x_m, y_m });
    }
    let grid = dataset.manifest().meta.grid;
    let positions: Vec<(u32, (f64, f64))> =
        dataset.points().iter().map(|&p| (p, grid.position_m(p as usize))).collect();
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

fn dist2(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)
}

//! Virtual-pixel area: the half-maximum contour around a focused pixel, and its map over the plate.
//!
//! As in the paper's Wave Field Analysis: for each point `x0`, focus a band-limited impulse on `x0` (single-pixel
//! inverse filter, closed form), take the field at focus time, and measure the area enclosed by the contour at
//! `threshold` (0.5: half maximum) of the field's value at `x0`. The contour is found by marching squares with
//! linear interpolation along cell edges, restricted to the closed ring that holds the peak: the region of grid
//! points at or above the level that is 4-connected to `x0`. Its area is the sum, over the cells it touches, of the
//! exact area of the interpolated polygon in each cell (shoelace).
//!
//! Unmeasured grid points are of two kinds, told apart by the mask alone: those 4-connected (through unmeasured
//! points) to the grid's border lie off the plate or beyond the scanned area, and those enclosed by measured points
//! are holes in the scan (the support pads, where the plate is still there but is not measured). A region that
//! reaches the grid's border or has an off-plate point among its 8 neighbours has no closed contour on the data:
//! it is [`PixelOutcome::ReachesEdge`], and its area is `None`, not counted in the median (the issue's "contours
//! that touch the plate edge are flagged, not counted"). A region next to a hole is still closed by the plate around
//! the hole: its contour is drawn half-way between the last measured point above the level and the hole (the
//! crossing lies somewhere in that one grid step), the region does not extend into the hole, and it is counted as
//! [`PixelOutcome::ClosedAtSupport`], so its area is an estimate good to about one grid step along that stretch.

use metaplate_control::PropagationMatrices;
use metaplate_control::focal::single_pixel_focal_fields;
use metaplate_control::solve::{Method, Regularisation};
use metaplate_control::target::TargetBand;
use metaplate_core::grid::GridSpec;

use crate::bands::OPERATING_BAND_HZ;
use crate::error::AnalysisError;
use crate::lattice::Lattice;

/// How the pixel-area map is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelAreaOptions {
    /// Band of the focusing, Hz: the target is a band-limited impulse over the bins of `g` inside it (the paper's
    /// operating band, 75 to 400 Hz, by default; a dataset loaded over a wider band is cut to it).
    pub band_hz: (f64, f64),
    /// Regularisation of the single-pixel inverse filter.
    pub regularisation: Regularisation,
    /// Inverse filtering (the paper's) or time reversal (its Fig. S5).
    pub method: Method,
    /// Band-limiting of the impulse target.
    pub target_band: TargetBand,
    /// Contour level as a fraction of the peak, in (0, 1); 0.5 is the half maximum.
    pub threshold: f64,
    /// Threads for the focal-field GEMM (>= 1).
    pub threads: usize,
}

impl Default for PixelAreaOptions {
    fn default() -> Self {
        Self {
            band_hz: OPERATING_BAND_HZ,
            regularisation: Regularisation::default(),
            method: Method::InverseFilter,
            target_band: TargetBand::default(),
            threshold: 0.5,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

/// What became of one pixel's half-maximum region.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PixelOutcome {
    /// Closed on measured data: the area is exact up to the marching-squares interpolation.
    Closed,
    /// Closed, but part of the contour runs next to a hole in the scan (a support pad): there it is drawn half-way
    /// into the gap. Counted.
    ClosedAtSupport,
    /// The region reaches the grid's border or a point off the plate: no closed contour. Not counted.
    ReachesEdge,
    /// The field at the target at focus time is not positive (nothing was focused there). Not counted.
    NoFocus,
}

impl PixelOutcome {
    /// True when the pixel's area is counted (the contour is closed).
    pub fn is_counted(self) -> bool {
        matches!(self, Self::Closed | Self::ClosedAtSupport)
    }
}

/// Pixel areas for every point of the propagation matrices, in their point order.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelAreaMap {
    /// Grid points (flat indices), as in the propagation matrices.
    pub points: Vec<u32>,
    /// Area of the half-maximum region, cm^2; `None` when not counted (see [`PixelOutcome::is_counted`]).
    pub area_cm2: Vec<Option<f64>>,
    /// What became of each pixel's region.
    pub outcome: Vec<PixelOutcome>,
    /// Field at the target at focus time (the peak the level is relative to), units of `G` per unit target gain.
    pub peak: Vec<f64>,
}

impl PixelAreaMap {
    /// Median of the areas that are not flagged, cm^2 (mean of the two middle ones for an even count); `None` when
    /// every point is flagged.
    pub fn median_area_cm2(&self) -> Option<f64> {
        let mut areas: Vec<f64> = self.area_cm2.iter().flatten().copied().collect();
        if areas.is_empty() {
            return None;
        }
        areas.sort_unstable_by(f64::total_cmp);
        let mid = areas.len() / 2;
        Some(if areas.len() % 2 == 1 { areas[mid] } else { 0.5 * (areas[mid - 1] + areas[mid]) })
    }

    /// Fraction of points flagged (not counted: no closed contour, or no focus), 0..=1.
    pub fn flagged_fraction(&self) -> f64 {
        let flagged = self.area_cm2.iter().filter(|a| a.is_none()).count();
        flagged as f64 / self.area_cm2.len().max(1) as f64
    }

    /// Number of pixels with outcome `outcome`.
    pub fn count(&self, outcome: PixelOutcome) -> usize {
        self.outcome.iter().filter(|&&o| o == outcome).count()
    }
}

/// The pixel-area map over every point of `g`, laid on `grid` with `mask` (per grid point, true when measured;
/// points of `g` must be masked in).
///
/// Valid range: a valid grid, `mask.len() == grid.len()`, every point of `g` inside the grid and masked in,
/// `0 < threshold < 1`, `threads >= 1`, `band_hz` holding at least one of `g`'s bins, the regularisation as
/// [`Regularisation`]. Cost: dominated by the focal fields, `4 N K M^2` flops (`K` bins in the band) (see [`single_pixel_focal_fields`]); the areas are `O(M x grid)`.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for options, grid, mask or points outside that range (or a control error,
/// rendered as its message), [`AnalysisError::LengthMismatch`] for the mask.
pub fn pixel_area_map(
    g: &PropagationMatrices,
    grid: &GridSpec,
    mask: &[bool],
    options: &PixelAreaOptions,
) -> Result<PixelAreaMap, AnalysisError> {
    grid.validate().map_err(|e| AnalysisError::InvalidParameter { name: "grid", reason: e.to_string() })?;
    if mask.len() != grid.len() {
        return Err(AnalysisError::LengthMismatch { what: "mask against grid points", a: mask.len(), b: grid.len() });
    }
    if !(options.threshold > 0.0 && options.threshold < 1.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "threshold",
            reason: format!("must lie in (0, 1), got {}", options.threshold),
        });
    }
    if options.threads == 0 {
        return Err(AnalysisError::InvalidParameter { name: "threads", reason: "must be at least 1".into() });
    }
    if let Some(lattice) = Lattice::of_points(grid, g.points())
        && lattice.stride > 1
    {
        // A regular subset (every s-th point, as `scan --grid` takes): the unmeasured points between would
        // read as off the plate and flag every contour, so the map is computed on the subset's own, coarser grid.
        let relabelled = g
            .with_points(lattice.indices.clone())
            .map_err(|e| AnalysisError::InvalidParameter { name: "points", reason: e.to_string() })?;
        let mut map = pixel_area_map(&relabelled, &lattice.grid, &lattice.mask(), options)?;
        map.points = g.points().to_vec();
        return Ok(map);
    }
    // Grid index -> row of g (the first, for duplicated points); unknown where not measured.
    let mut row_of = vec![usize::MAX; grid.len()];
    for (row, &p) in g.points().iter().enumerate() {
        let p = p as usize;
        if p >= grid.len() || !mask[p] {
            return Err(AnalysisError::InvalidParameter {
                name: "points",
                reason: format!("grid point {p} is outside the {} x {} grid or masked out", grid.nx, grid.ny),
            });
        }
        if row_of[p] == usize::MAX {
            row_of[p] = row;
        }
    }
    let control = |e: metaplate_control::ControlError| AnalysisError::InvalidParameter {
        name: "focusing",
        reason: e.to_string(),
    };
    let in_band = g
        .select_band(options.band_hz)
        .map_err(|e| AnalysisError::InvalidParameter { name: "band_hz", reason: e.to_string() })?;
    let g = &in_band;
    let gains = options.target_band.gains(g).map_err(control)?;
    let targets: Vec<usize> = (0..g.n_points()).collect();
    let fields =
        single_pixel_focal_fields(g, &targets, &gains, options.regularisation, options.method, options.threads)
            .map_err(control)?;
    let mut contour = ContourWork::new(grid, &row_of);
    let mut map = PixelAreaMap {
        points: g.points().to_vec(),
        area_cm2: Vec::with_capacity(targets.len()),
        outcome: Vec::with_capacity(targets.len()),
        peak: Vec::with_capacity(targets.len()),
    };
    let cell_area_cm2 = grid.spacing_m * grid.spacing_m * 1e4;
    for (t, &row) in targets.iter().enumerate() {
        let field = fields.field(t).ok_or(AnalysisError::NonFiniteResult { what: "focal field" })?;
        let target = g.points()[row] as usize;
        let peak = field[row];
        let (area, outcome) = if peak.is_nan() || peak <= 0.0 {
            (None, PixelOutcome::NoFocus)
        } else {
            match contour.region_area_cells(field, target, options.threshold * peak) {
                Region::Closed { cells, at_hole } => (
                    Some(cells * cell_area_cm2),
                    if at_hole { PixelOutcome::ClosedAtSupport } else { PixelOutcome::Closed },
                ),
                Region::ReachesEdge => (None, PixelOutcome::ReachesEdge),
            }
        };
        map.area_cm2.push(area);
        map.outcome.push(outcome);
        map.peak.push(peak);
    }
    Ok(map)
}

/// The half-maximum region of one field.
enum Region {
    /// Closed; its area in units of one grid cell (spacing^2), and whether it borders a hole of the scan.
    Closed { cells: f64, at_hole: bool },
    /// Reaches the grid border or an off-plate point.
    ReachesEdge,
}

/// Per grid point: measured, a hole in the scan (unmeasured, enclosed by measured points), or outside (unmeasured
/// and 4-connected through unmeasured points to the grid's border).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Site {
    Measured,
    Hole,
    Outside,
}

/// Classifies every grid point of an `nx x ny` grid from `measured` (flood fill from the border's unmeasured points).
fn classify_sites(nx: usize, ny: usize, measured: impl Fn(usize) -> bool) -> Vec<Site> {
    let mut sites: Vec<Site> = (0..nx * ny).map(|i| if measured(i) { Site::Measured } else { Site::Hole }).collect();
    let mut stack: Vec<usize> = (0..nx * ny)
        .filter(|&i| {
            let (ix, iy) = (i % nx, i / nx);
            (ix == 0 || iy == 0 || ix + 1 == nx || iy + 1 == ny) && sites[i] == Site::Hole
        })
        .collect();
    for &i in &stack {
        sites[i] = Site::Outside;
    }
    while let Some(i) = stack.pop() {
        let (ix, iy) = (i % nx, i / nx);
        let neighbours = [
            (ix > 0).then(|| i - 1),
            (ix + 1 < nx).then(|| i + 1),
            (iy > 0).then(|| i - nx),
            (iy + 1 < ny).then(|| i + nx),
        ];
        for j in neighbours.into_iter().flatten() {
            if sites[j] == Site::Hole {
                sites[j] = Site::Outside;
                stack.push(j);
            }
        }
    }
    sites
}

/// Reusable buffers for the contour of many fields on one grid (no allocation per field or per cell).
struct ContourWork<'a> {
    nx: usize,
    ny: usize,
    row_of: &'a [usize],
    sites: Vec<Site>,
    /// `stamp[i] == current` marks grid point `i` as in the region of the current field.
    stamp: Vec<u32>,
    current: u32,
    stack: Vec<usize>,
    region: Vec<usize>,
    cells: Vec<usize>,
}

impl<'a> ContourWork<'a> {
    fn new(grid: &GridSpec, row_of: &'a [usize]) -> Self {
        Self {
            nx: grid.nx,
            ny: grid.ny,
            row_of,
            sites: classify_sites(grid.nx, grid.ny, |i| row_of[i] != usize::MAX),
            stamp: vec![0; grid.len()],
            current: 0,
            stack: Vec::new(),
            region: Vec::new(),
            cells: Vec::new(),
        }
    }

    /// The value of `field` (indexed by rows of g) at grid point `i`, or `None` when unmeasured.
    fn value(&self, field: &[f64], i: usize) -> Option<f64> {
        let row = self.row_of[i];
        (row != usize::MAX).then(|| field[row])
    }

    fn region_area_cells(&mut self, field: &[f64], target: usize, level: f64) -> Region {
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.fill(0);
            self.current = 1;
        }
        let (nx, ny, current) = (self.nx, self.ny, self.current);
        self.stack.clear();
        self.region.clear();
        self.stamp[target] = current;
        self.stack.push(target);
        let mut at_hole = false;
        // Flood fill (4-connected) over measured points at or above the level.
        while let Some(i) = self.stack.pop() {
            self.region.push(i);
            let (ix, iy) = (i % nx, i / nx);
            if ix == 0 || iy == 0 || ix + 1 == nx || iy + 1 == ny {
                return Region::ReachesEdge;
            }
            // An unmeasured point among the 8 neighbours: off the plate, the contour runs through missing data;
            // in a hole, it is closed half-way into the gap (see the module documentation).
            for dy in [-1_isize, 0, 1] {
                for dx in [-1_isize, 0, 1] {
                    let j = (iy as isize + dy) as usize * nx + (ix as isize + dx) as usize;
                    match self.sites[j] {
                        Site::Measured => {}
                        Site::Hole => at_hole = true,
                        Site::Outside => return Region::ReachesEdge,
                    }
                }
            }
            for j in [i - 1, i + 1, i - nx, i + nx] {
                if self.stamp[j] != current && self.value(field, j).is_some_and(|v| v >= level) {
                    self.stamp[j] = current;
                    self.stack.push(j);
                }
            }
        }
        // Cells (by lower-left corner) with a corner in the region; every corner is measured or a hole (checked
        // above). A hole corner has no value (NaN): the crossing towards it goes at mid-edge.
        self.cells.clear();
        for &i in &self.region {
            self.cells.extend_from_slice(&[i, i - 1, i - nx, i - nx - 1]);
        }
        self.cells.sort_unstable();
        self.cells.dedup();
        let mut area = 0.0;
        for &c in &self.cells {
            let corners = [c, c + 1, c + nx + 1, c + nx];
            let mut f = [0.0; 4];
            let mut inside = [false; 4];
            for (q, &i) in corners.iter().enumerate() {
                f[q] = self.value(field, i).unwrap_or(f64::NAN);
                inside[q] = self.stamp[i] == current;
            }
            area += cell_polygon_area(&f, &inside, level);
        }
        Region::Closed { cells: area, at_hole }
    }
}

/// Area (in cell units) of the part of a unit cell inside the region, by marching squares: walk the corners
/// counter-clockwise ((0,0), (1,0), (1,1), (0,1)), keep the inside corners, and insert the linearly interpolated
/// level crossing on every edge whose ends differ; the shoelace formula gives the polygon's area.
fn cell_polygon_area(f: &[f64; 4], inside: &[bool; 4], level: f64) -> f64 {
    const CORNERS: [(f64, f64); 4] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let mut poly = [(0.0, 0.0); 8];
    let mut n = 0;
    for q in 0..4 {
        let r = (q + 1) % 4;
        if inside[q] {
            poly[n] = CORNERS[q];
            n += 1;
        }
        if inside[q] != inside[r] {
            // A corner counted outside although above the level (not connected to the peak), or with no value (a
            // hole in the scan), has no crossing on the data: split the edge at its middle.
            let t = (level - f[q]) / (f[r] - f[q]);
            let t = if t.is_finite() && (0.0..=1.0).contains(&t) { t } else { 0.5 };
            let (a, b) = (CORNERS[q], CORNERS[r]);
            poly[n] = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            n += 1;
        }
    }
    let mut twice = 0.0;
    for q in 0..n {
        let (a, b) = (poly[q], poly[(q + 1) % n]);
        twice += a.0 * b.1 - b.0 * a.1;
    }
    0.5 * twice.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holes_are_told_from_the_outside() {
        // 6 x 5 grid: the left column unmeasured (outside, on the border), a 2-point hole inside ((2, 2) and
        // (3, 2)), and an unmeasured point at (4, 3) that touches the hole only diagonally and reaches the top
        // border through (4, 4): outside, while the hole stays a hole.
        let unmeasured = [0, 6, 12, 18, 24, 14, 15, 22, 28];
        let sites = classify_sites(6, 5, |i| !unmeasured.contains(&i));
        for i in [0, 6, 12, 18, 24, 22, 28] {
            assert_eq!(sites[i], Site::Outside, "point {i}");
        }
        assert_eq!((sites[14], sites[15], sites[7]), (Site::Hole, Site::Hole, Site::Measured));
    }

    #[test]
    fn a_peak_next_to_a_hole_is_counted_and_one_next_to_the_outside_is_not() {
        // 7 x 7 grid, field 1 at the centre (24) and 0 elsewhere: the region is the centre alone, area 4 triangles
        // of 1/8 cell = 0.5 cell. With (24 + 1) a hole, the crossing on that edge is at mid-edge, as for a measured
        // 0 there: the same 0.5 cell, flagged as at a support. With the whole right half unmeasured (connected to
        // the border) the region has an outside neighbour: not counted.
        let grid = GridSpec { nx: 7, ny: 7, spacing_m: 0.01, origin_x_m: 0.0, origin_y_m: 0.0 };
        let mut field = vec![0.0; 49];
        field[24] = 1.0;
        let row_of: Vec<usize> = (0..49).collect();
        let mut work = ContourWork::new(&grid, &row_of);
        assert!(matches!(work.region_area_cells(&field, 24, 0.5), Region::Closed { cells, at_hole: false }
            if (cells - 0.5).abs() < 1e-12));
        let mut holed = row_of.clone();
        holed[25] = usize::MAX;
        let mut work = ContourWork::new(&grid, &holed);
        assert!(matches!(work.region_area_cells(&field, 24, 0.5), Region::Closed { cells, at_hole: true }
            if (cells - 0.5).abs() < 1e-12));
        let cut: Vec<usize> = (0..49).map(|i| if i % 7 >= 4 { usize::MAX } else { i }).collect();
        let mut work = ContourWork::new(&grid, &cut);
        assert!(matches!(work.region_area_cells(&field, 24, 0.5), Region::ReachesEdge));
    }

    #[test]
    fn cell_area_cases() {
        // All inside: the whole cell; one corner inside with crossings at mid-edges: a triangle of 1/8.
        assert!((cell_polygon_area(&[1.0; 4], &[true; 4], 0.5) - 1.0).abs() < 1e-15);
        let f = [1.0, 0.0, 0.0, 0.0];
        assert!((cell_polygon_area(&f, &[true, false, false, false], 0.5) - 0.125).abs() < 1e-15);
        // Two adjacent corners inside, crossings at 1/4 up both vertical edges: a strip of height 1/4.
        let f = [1.0, 1.0, -2.0, -2.0];
        assert!((cell_polygon_area(&f, &[true, true, false, false], 0.25) - 0.25).abs() < 1e-15);
    }
}

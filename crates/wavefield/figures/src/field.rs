//! A field measured on a lattice, sampled anywhere as an image: bilinear interpolation between measured points,
//! no extrapolation beyond half a lattice step, masking by a polygon outline (row by row), and the level line of
//! the sampled image (marching squares).

use metaplate_core::grid::GridSpec;

/// What the image shows at one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sample {
    /// An interpolated value.
    Value(f64),
    /// Nearest a point that was measured but has no value (for example no closed half-maximum contour).
    NoValue,
    /// Not measured: farther than half a lattice step from every measured point.
    Unmeasured,
}

/// Values on a lattice (`grid`), one per point: `Some` where measured with a value, `None` elsewhere; `measured`
/// tells a measured point without value ([`Sample::NoValue`]) from an unmeasured one.
pub(crate) struct LatticeField<'a> {
    pub grid: &'a GridSpec,
    pub values: &'a [Option<f64>],
    pub measured: &'a [bool],
}

/// Lower corner and fraction of a fractional lattice coordinate `f` on an axis of `n` points: `(i0, i1, t)` with
/// the position `(1 - t) i0 + t i1`; `t` clamped so that the half step beyond the ends repeats the end point.
fn axis_cell(f: f64, n: usize) -> (usize, usize, f64) {
    if n <= 1 {
        return (0, 0, 0.0);
    }
    let i0 = (f.floor().max(0.0) as usize).min(n - 2);
    (i0, i0 + 1, (f - i0 as f64).clamp(0.0, 1.0))
}

impl LatticeField<'_> {
    /// The image at `(x_m, y_m)`, m: bilinear interpolation between the four surrounding lattice points, over those
    /// of them with a value (weights renormalised), where the nearest lattice point has a value; what the nearest
    /// point is otherwise. Beyond half a lattice step outside the lattice, [`Sample::Unmeasured`].
    pub fn at(&self, x_m: f64, y_m: f64) -> Sample {
        let g = self.grid;
        if !(g.spacing_m.is_finite() && g.spacing_m > 0.0 && g.nx > 0 && g.ny > 0) {
            return Sample::Unmeasured;
        }
        let fx = (x_m - g.origin_x_m) / g.spacing_m;
        let fy = (y_m - g.origin_y_m) / g.spacing_m;
        let inside = |f: f64, n: usize| f.is_finite() && f >= -0.5 && f <= n as f64 - 0.5;
        if !(inside(fx, g.nx) && inside(fy, g.ny)) {
            return Sample::Unmeasured;
        }
        let nearest = |f: f64, n: usize| (f.round().max(0.0) as usize).min(n - 1);
        let near = g.index(nearest(fx, g.nx), nearest(fy, g.ny));
        match (self.measured.get(near).copied().unwrap_or(false), self.values.get(near).copied().flatten()) {
            (false, _) => return Sample::Unmeasured,
            (true, None) => return Sample::NoValue,
            (true, Some(_)) => {}
        }
        let (x0, x1, tx) = axis_cell(fx, g.nx);
        let (y0, y1, ty) = axis_cell(fy, g.ny);
        let (mut sum, mut weight) = (0.0, 0.0);
        for (ix, iy, w) in
            [(x0, y0, (1.0 - tx) * (1.0 - ty)), (x1, y0, tx * (1.0 - ty)), (x0, y1, (1.0 - tx) * ty), (x1, y1, tx * ty)]
        {
            if let Some(v) = self.values.get(g.index(ix, iy)).copied().flatten()
                && v.is_finite()
            {
                sum += w * v;
                weight += w;
            }
        }
        // The nearest point has a value and at least a quarter of the weight, so `weight` is positive.
        if weight > 0.0 { Sample::Value(sum / weight) } else { Sample::NoValue }
    }
}

/// Where the horizontal line at `y` crosses `polygon`'s edges (vertices in order, closed implicitly), x ascending:
/// `(x, y)` is inside when an odd number of crossings lie right of `x` (the even-odd rule). `None` for a polygon of
/// fewer than three vertices (no outline known: everything inside). Computed once per row, so that an image's mask
/// costs one pass over the edges per row, not per pixel.
pub(crate) fn row_crossings(polygon: &[(f64, f64)], y: f64) -> Option<Vec<f64>> {
    if polygon.len() < 3 {
        return None;
    }
    let mut xs = Vec::new();
    let mut j = polygon.len() - 1;
    for (i, &(xi, yi)) in polygon.iter().enumerate() {
        let (xj, yj) = polygon[j];
        if (yi > y) != (yj > y) {
            xs.push((xj - xi) * (y - yi) / (yj - yi) + xi);
        }
        j = i;
    }
    xs.sort_by(f64::total_cmp);
    Some(xs)
}

/// True when `x` is inside by `crossings` (from [`row_crossings`]).
pub(crate) fn inside_row(crossings: Option<&[f64]>, x: f64) -> bool {
    crossings.is_none_or(|xs| xs.iter().filter(|&&c| x < c).count() % 2 == 1)
}

/// Convex hull of `points` (Andrew's monotone chain), counter-clockwise, without repeating the first vertex;
/// non-finite points are skipped.
pub(crate) fn convex_hull(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite()).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(2 * p.len());
    for pass in [p.clone(), p.iter().rev().copied().collect()] {
        let start = hull.len();
        for q in pass {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Samples of an image on a regular raster: `nx` x `ny` values, row by row from `(x0, y0)` in steps of `step`
/// (same units as the positions); `None` where the image has no value.
pub(crate) struct Raster {
    pub x0: f64,
    pub y0: f64,
    pub step: f64,
    pub nx: usize,
    pub ny: usize,
    pub values: Vec<Option<f64>>,
}

impl Raster {
    /// Keeps, of the region at or above `level`, only the part connected (through edge neighbours) to the sample
    /// nearest `seed`: every other sample at or above `level` is lowered below it, so that [`Raster::contour`]
    /// traces only that part's boundary (the focus's half-maximum contour, not other crests of the field). When the
    /// seed's sample is below `level` or outside the raster, nothing of the level region is kept.
    pub fn keep_region_around(&mut self, seed: (f64, f64), level: f64) {
        let below = level - level.abs().max(1.0);
        let (sx, sy) = ((seed.0 - self.x0) / self.step, (seed.1 - self.y0) / self.step);
        let mut keep = vec![false; self.values.len()];
        let start = (sx.is_finite() && sy.is_finite() && sx > -0.5 && sy > -0.5)
            .then(|| (sx.round() as usize, sy.round() as usize))
            .filter(|&(ix, iy)| ix < self.nx && iy < self.ny)
            .map(|(ix, iy)| iy * self.nx + ix)
            .filter(|&i| self.values[i].is_some_and(|v| v >= level));
        let mut stack: Vec<usize> = start.into_iter().collect();
        while let Some(i) = stack.pop() {
            if keep[i] {
                continue;
            }
            keep[i] = true;
            let (ix, iy) = (i % self.nx, i / self.nx);
            let neighbours = [
                (ix > 0).then(|| i - 1),
                (ix + 1 < self.nx).then(|| i + 1),
                (iy > 0).then(|| i - self.nx),
                (iy + 1 < self.ny).then(|| i + self.nx),
            ];
            stack.extend(
                neighbours.into_iter().flatten().filter(|&j| !keep[j] && self.values[j].is_some_and(|v| v >= level)),
            );
        }
        for (v, kept) in self.values.iter_mut().zip(keep) {
            if !kept && v.is_some_and(|x| x >= level) {
                *v = Some(below);
            }
        }
    }

    /// Segments of the line where the raster crosses `level` (marching squares, positions linearly interpolated
    /// along cell edges; a cell with a missing corner draws nothing; saddles split by the cell's mean).
    pub fn contour(&self, level: f64) -> Vec<[(f64, f64); 2]> {
        let mut segments = Vec::new();
        if self.nx < 2 || self.ny < 2 {
            return segments;
        }
        let at = |ix: usize, iy: usize| self.values[iy * self.nx + ix];
        let pos = |ix: usize, iy: usize| (self.x0 + ix as f64 * self.step, self.y0 + iy as f64 * self.step);
        for iy in 0..self.ny - 1 {
            for ix in 0..self.nx - 1 {
                // Corners counter-clockwise from the lower left.
                let corners = [(ix, iy), (ix + 1, iy), (ix + 1, iy + 1), (ix, iy + 1)];
                let Some(v) = corners.iter().map(|&(i, j)| at(i, j)).collect::<Option<Vec<f64>>>() else {
                    continue;
                };
                let above: Vec<bool> = v.iter().map(|&x| x >= level).collect();
                // The crossing on edge k (from corner k to corner k + 1).
                let cross = |k: usize| {
                    let (a, b) = (k, (k + 1) % 4);
                    let (pa, pb) = (pos(corners[a].0, corners[a].1), pos(corners[b].0, corners[b].1));
                    let t = if v[b] != v[a] { ((level - v[a]) / (v[b] - v[a])).clamp(0.0, 1.0) } else { 0.5 };
                    (pa.0 + t * (pb.0 - pa.0), pa.1 + t * (pb.1 - pa.1))
                };
                let edges: Vec<usize> = (0..4).filter(|&k| above[k] != above[(k + 1) % 4]).collect();
                match edges.as_slice() {
                    [a, b] => segments.push([cross(*a), cross(*b)]),
                    [a, b, c, d] => {
                        // A saddle: corners 0 and 2 on one side. When the centre is on their side, they join.
                        let centre_above = v.iter().sum::<f64>() / 4.0 >= level;
                        if centre_above == above[0] {
                            segments.push([cross(*a), cross(*b)]);
                            segments.push([cross(*c), cross(*d)]);
                        } else {
                            segments.push([cross(*a), cross(*d)]);
                            segments.push([cross(*b), cross(*c)]);
                        }
                    }
                    _ => {}
                }
            }
        }
        segments
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_between_points_and_half_a_step_beyond() {
        let grid = GridSpec { nx: 2, ny: 2, spacing_m: 1.0, origin_x_m: 0.0, origin_y_m: 0.0 };
        let values = [Some(0.0), Some(1.0), Some(2.0), Some(3.0)];
        let measured = [true; 4];
        let f = LatticeField { grid: &grid, values: &values, measured: &measured };
        assert_eq!(f.at(0.5, 0.5), Sample::Value(1.5));
        assert_eq!(f.at(0.25, 0.0), Sample::Value(0.25));
        assert_eq!(f.at(-0.4, 0.0), Sample::Value(0.0));
        assert_eq!(f.at(-0.6, 0.0), Sample::Unmeasured);
        assert_eq!(f.at(1.0, 1.6), Sample::Unmeasured);
        let values = [Some(0.0), None, Some(2.0), None];
        let measured = [true, true, true, false];
        let f = LatticeField { grid: &grid, values: &values, measured: &measured };
        assert_eq!(f.at(0.9, 0.1), Sample::NoValue);
        assert_eq!(f.at(1.0, 0.9), Sample::Unmeasured);
        // Only the corners with a value count: (0, 0) and (0, 1), weights 0.6 * 0.8 and 0.6 * 0.2.
        let Sample::Value(v) = f.at(0.4, 0.2) else { panic!("no value") };
        assert!((v - 2.0 * 0.2).abs() < 1e-12);
    }

    #[test]
    fn polygons_and_hulls() {
        let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
        let row = row_crossings(&square, 0.5);
        assert_eq!(row.as_deref(), Some(&[0.0, 1.0][..]));
        assert!(inside_row(row.as_deref(), 0.5));
        assert!(!inside_row(row.as_deref(), 1.5) && !inside_row(row.as_deref(), -0.5));
        assert!(row_crossings(&square, 1.5).is_some_and(|xs| xs.is_empty()));
        assert!(inside_row(row_crossings(&[], 9.0).as_deref(), 9.0));
        let mut points = square.to_vec();
        points.push((0.5, 0.5));
        assert_eq!(convex_hull(&points).len(), 4);
    }

    #[test]
    fn contour_of_a_cone_is_a_closed_ring_at_the_level() {
        let n = 21;
        let values = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 - 10.0, (i / n) as f64 - 10.0);
                Some(1.0 - x.hypot(y) / 10.0)
            })
            .collect();
        let mut raster = Raster { x0: -10.0, y0: -10.0, step: 1.0, nx: n, ny: n, values };
        // A second crest, not connected to the centre's: traced until only the centre's region is kept.
        raster.values[0] = Some(0.9);
        let all = raster.contour(0.5).len();
        raster.keep_region_around((0.2, -0.3), 0.5);
        let segments = raster.contour(0.5);
        assert!(segments.len() < all);
        assert!(segments.len() > 20);
        for s in &segments {
            for p in s {
                assert!((p.0.hypot(p.1) - 5.0).abs() < 0.2, "{p:?}");
            }
        }
    }
}

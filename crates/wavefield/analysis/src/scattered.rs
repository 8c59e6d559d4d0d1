//! Scattered points (a scan mesh imported from another tool, `metaplate_store::ScatteredPoints`): what the
//! analyses do with points on no lattice.
//!
//! - **On the points themselves**: POD, the authority (the square domains select points by position), the
//!   refresh and the driven response need no lattice, and run on the measured points as they are.
//! - **On a lattice interpolated within the points' hull**: the k-space wavelength (a 2-D FFT) and the pixel-area
//!   contours (marching squares) need a lattice. [`interpolate`] lays one over the points at their median
//!   nearest-neighbour spacing and fills the nodes inside the points' convex hull by **linear interpolation on
//!   their Delaunay triangulation** (each node a convex combination of the three corners of its triangle):
//!   - exact for fields linear in x and y, and never beyond the corners' values (no overshoot, no ringing): an
//!     interpolated peak is never higher than a measured one;
//!   - defined exactly on the hull: nodes outside it are left unmeasured (masked), nothing is extrapolated;
//!   - valid range: a wave resolved by the triangles (edges below a quarter wavelength keep the error of a plane
//!     wave's amplitude below about 8 %, the linear interpolant's `(k h)^2 / 8`); its error is second order in
//!     the edge length, so a mesh that resolves the wave resolves it interpolated.
//!
//!   Natural-neighbour interpolation would be smoother (C¹ away from the points) but costs a Voronoi diagram
//!   per node for no gain in what these analyses measure (both are exact for linear fields; a k-space peak and a
//!   half-maximum contour depend on the sampled wave, not on the interpolant's smoothness).
//! - **Refused by name**: fewer than three points, or points on one line, span no area: no lattice, and the
//!   wavelength and the pixel area say so ([`AnalysisError::NeedsLattice`]).

use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSpec;
use metaplate_core::points::median_spacing_m;
use num_complex::Complex64;
use serde::Serialize;

use crate::authority::domain_authority_at;
use crate::error::AnalysisError;
use crate::lattice::Lattice;
use crate::pixel::{PixelAreaMap, PixelAreaOptions, pixel_area_map};
use crate::pod::pod;
use crate::refresh::refresh;
use crate::report::{PlateReport, ReportOptions, wavelength_at};
use crate::response::driven_response;

/// What `analyze` did with scattered points (in its JSON as `scattered`).
#[derive(Debug, Clone, Serialize)]
pub struct ScatteredSummary {
    /// Measured points analysed.
    pub points: usize,
    /// The analyses run on the points themselves.
    pub on_points: &'static str,
    /// How the lattice analyses were run: the interpolation and its lattice, or why there is none.
    pub lattice_analyses: String,
}

/// Every analysis of [`crate::report::analyse`] on scattered points: `g`'s row `m` at `positions_m[m]` (m).
/// POD, authority, refresh and driven response run on the points; the wavelength and the pixel-area map on the
/// lattice [`interpolate`] lays within their hull (or each fails with [`AnalysisError::NeedsLattice`]). Returns
/// the report (its `lattice` the interpolated one), the pixel-area map, the summary, and the matrices on the
/// lattice for the figures (`g` itself when there is no lattice).
///
/// # Errors
/// [`AnalysisError::LengthMismatch`] unless there is one position per row of `g`.
pub fn analyse_scattered(
    g: &PropagationMatrices,
    positions_m: &[(f64, f64)],
    opts: &ReportOptions,
) -> Result<(PlateReport, Result<PixelAreaMap, AnalysisError>, ScatteredSummary, PropagationMatrices), AnalysisError> {
    if positions_m.len() != g.n_points() {
        return Err(AnalysisError::LengthMismatch {
            what: "positions against the rows of G",
            a: positions_m.len(),
            b: g.n_points(),
        });
    }
    let by_point: std::collections::HashMap<u32, (f64, f64)> =
        g.points().iter().copied().zip(positions_m.iter().copied()).collect();
    let position = move |p: u32| by_point.get(&p).copied().unwrap_or((f64::NAN, f64::NAN));
    let on_points = "POD, authority (domains by position), refresh and driven response: on the points themselves";
    let interpolated = interpolate(g, positions_m);
    let (lattice, wavelength, pixels, lattice_analyses, figures_g) = match interpolated {
        Ok((weights, on_lattice)) => {
            let lattice = Lattice { grid: weights.grid, indices: on_lattice.points().to_vec(), stride: 1 };
            let resolvable = lattice.resolvable();
            let wavelength = opts
                .wavelength_freqs_hz
                .iter()
                .filter_map(|&f| wavelength_at(&on_lattice, &weights.grid, f, &resolvable))
                .collect();
            let pixels = pixel_area_map(&on_lattice, &weights.grid, &weights.mask(), &PixelAreaOptions::default());
            let text = format!(
                "k-space wavelength and pixel area on a {} x {} lattice at {:.2} mm (the points' median spacing) \
                 interpolated within the points' convex hull: linear on their Delaunay triangulation, {} of {} \
                 nodes inside the hull, none extrapolated",
                weights.grid.nx,
                weights.grid.ny,
                weights.grid.spacing_m * 1e3,
                weights.nodes.len(),
                weights.grid.len()
            );
            (lattice, wavelength, pixels, text, on_lattice)
        }
        Err(e) => {
            let (x, y) = positions_m.first().copied().unwrap_or_default();
            let grid = GridSpec { nx: 1, ny: 1, spacing_m: 1e-3, origin_x_m: x, origin_y_m: y };
            let lattice = Lattice { grid, indices: Vec::new(), stride: 1 };
            let text = format!("k-space wavelength and pixel area not computed: {e}");
            (lattice, Vec::new(), Err(e), text, g.clone())
        }
    };
    let report = PlateReport {
        resolvable: lattice.resolvable(),
        lattice,
        wavelength,
        pod: pod(g, &opts.pod),
        authority: opts
            .domain_edges_m
            .iter()
            .map(|&d| (d, domain_authority_at(g, &position, d, &opts.authority)))
            .collect(),
        refresh: refresh(g, &opts.refresh),
        driven_response: driven_response(g, opts.response_band_hz),
    };
    let summary = ScatteredSummary { points: g.n_points(), on_points, lattice_analyses };
    Ok((report, pixels, summary, figures_g))
}

/// `g` of scattered points (row `m` at `positions_m[m]`, m) on the lattice at their median nearest-neighbour
/// spacing within their convex hull: the weights and the interpolated matrices.
///
/// # Errors
/// As [`lattice_weights`] and [`interpolate_g`].
pub fn interpolate(
    g: &PropagationMatrices,
    positions_m: &[(f64, f64)],
) -> Result<(LatticeWeights, PropagationMatrices), AnalysisError> {
    // Triangulated first: it names what spans no area before a spacing is asked of it.
    delaunay(positions_m)?;
    let spacing_m = median_spacing_m(positions_m)
        .ok_or_else(|| AnalysisError::NeedsLattice { reason: "the points have no spacing".into() })?;
    let weights = lattice_weights(positions_m, spacing_m)?;
    let on_lattice = interpolate_g(g, &weights)?;
    Ok((weights, on_lattice))
}

/// Most points triangulated (the Bowyer-Watson insertion here is `O(n²)`): the import's own limit.
pub const MAX_SCATTERED_POINTS: usize = 20_000;

/// A barycentric weight this far below zero still counts as inside a triangle (a node on an edge, rounding).
const INSIDE_TOLERANCE: f64 = 1e-9;

/// A triangle of point indices, counter-clockwise.
type Triangle = [usize; 3];

/// The Delaunay triangulation of `points_m` (Bowyer-Watson from a super-triangle), as triangles of indices.
///
/// # Errors
/// [`AnalysisError::NeedsLattice`] for fewer than three points, points on one line or at one position (no area),
/// more than [`MAX_SCATTERED_POINTS`], or a non-finite coordinate.
pub fn delaunay(points_m: &[(f64, f64)]) -> Result<Vec<Triangle>, AnalysisError> {
    let n = points_m.len();
    let refuse = |reason: String| Err(AnalysisError::NeedsLattice { reason });
    if n < 3 {
        return refuse(format!("{n} point(s) span no area (a triangle needs 3)"));
    }
    if n > MAX_SCATTERED_POINTS {
        return refuse(format!("{n} scattered points: at most {MAX_SCATTERED_POINTS} are triangulated"));
    }
    if points_m.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
        return refuse("a position is not finite".into());
    }
    let mut sorted: Vec<(f64, f64)> = points_m.to_vec();
    sorted.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
        return refuse(format!(
            "two points lie at one position ({}, {}) m: they span no area between them",
            w[0].0, w[0].1
        ));
    }
    let (lo, hi) = bounds(points_m);
    let span = (hi.0 - lo.0).max(hi.1 - lo.1);
    // Points on one line: no third point off the line through the first and the farthest from it.
    let a = points_m[0];
    let b = points_m.iter().copied().max_by(|p, q| dist2(*p, a).total_cmp(&dist2(*q, a))).unwrap_or(a);
    let off = points_m.iter().map(|&c| area2(a, b, c).abs()).fold(0.0, f64::max);
    if !(span > 0.0 && off > 1e-12 * span * span) {
        return refuse(format!("the {n} points lie on one line: they span no area"));
    }
    // Super-triangle far around the points; its corners are indices n, n + 1, n + 2.
    let (cx, cy, r) = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0, 20.0 * span);
    let mut all: Vec<(f64, f64)> = points_m.to_vec();
    all.extend([(cx - r, cy - r), (cx + r, cy - r), (cx, cy + r)]);
    let mut triangles: Vec<(Triangle, (f64, f64), f64)> = vec![with_circle(&all, [n, n + 1, n + 2])];
    for i in 0..n {
        let p = all[i];
        let mut edges: Vec<[usize; 2]> = Vec::new();
        triangles.retain(|(t, c, r2)| {
            let inside = (p.0 - c.0).powi(2) + (p.1 - c.1).powi(2) < *r2;
            if inside {
                edges.extend([[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]]);
            }
            !inside
        });
        // The cavity's boundary: the edges of exactly one removed triangle.
        for (k, e) in edges.iter().enumerate() {
            let shared = edges.iter().enumerate().any(|(j, f)| j != k && f[0] == e[1] && f[1] == e[0]);
            if !shared {
                triangles.push(with_circle(&all, [e[0], e[1], i]));
            }
        }
    }
    Ok(triangles.into_iter().map(|(t, _, _)| t).filter(|t| t.iter().all(|&v| v < n)).collect())
}

/// Twice the signed area of the triangle (a, b, c): positive counter-clockwise.
fn area2(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// The triangle `t` of `all`, counter-clockwise, with its circumcentre and squared circumradius.
fn with_circle(all: &[(f64, f64)], mut t: Triangle) -> (Triangle, (f64, f64), f64) {
    if area2(all[t[0]], all[t[1]], all[t[2]]) < 0.0 {
        t.swap(1, 2);
    }
    let (a, b, c) = (all[t[0]], all[t[1]], all[t[2]]);
    let d = 2.0 * area2(a, b, c);
    let (a2, b2, c2) = (a.0 * a.0 + a.1 * a.1, b.0 * b.0 + b.1 * b.1, c.0 * c.0 + c.1 * c.1);
    let ux = (a2 * (b.1 - c.1) + b2 * (c.1 - a.1) + c2 * (a.1 - b.1)) / d;
    let uy = (a2 * (c.0 - b.0) + b2 * (a.0 - c.0) + c2 * (b.0 - a.0)) / d;
    // A degenerate (zero-area) triangle gets an infinite circle: every later point removes it.
    let r2 = if d == 0.0 { f64::INFINITY } else { (a.0 - ux).powi(2) + (a.1 - uy).powi(2) };
    (t, (ux, uy), r2)
}

fn dist2(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)
}

/// Lower-left and upper-right corners of the points' box, m.
fn bounds(points_m: &[(f64, f64)]) -> ((f64, f64), (f64, f64)) {
    points_m.iter().fold(((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY)), |(lo, hi), p| {
        ((lo.0.min(p.0), lo.1.min(p.1)), (hi.0.max(p.0), hi.1.max(p.1)))
    })
}

/// The interpolation of scattered points onto a lattice: for each lattice node inside the points' convex hull,
/// the three points and their barycentric weights.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeWeights {
    /// The lattice: origin at the points' lower-left corner, spacing as asked, covering their box.
    pub grid: GridSpec,
    /// Per lattice node inside the hull (ascending flat index): the node and its three (point, weight) pairs; the
    /// weights are non-negative and sum to 1.
    pub nodes: Vec<(u32, [(usize, f64); 3])>,
}

impl LatticeWeights {
    /// Per lattice node: inside the hull (interpolated).
    pub fn mask(&self) -> Vec<bool> {
        let mut mask = vec![false; self.grid.len()];
        for &(node, _) in &self.nodes {
            mask[node as usize] = true;
        }
        mask
    }

    /// `values` (one per point) at the interpolated nodes, in [`LatticeWeights::nodes`]' order.
    pub fn apply<T>(&self, values: &[T]) -> Vec<T>
    where
        T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
    {
        self.nodes
            .iter()
            .map(|(_, w)| values[w[0].0] * w[0].1 + values[w[1].0] * w[1].1 + values[w[2].0] * w[2].1)
            .collect()
    }
}

/// The lattice at `spacing_m` over the points `points_m` (m) and the linear interpolation weights of its nodes
/// inside their convex hull (see the module documentation). Valid range: `spacing_m` finite, positive, and at
/// least 1/1000 of the points' extent; the points as [`delaunay`] takes them.
///
/// # Errors
/// As [`delaunay`]; [`AnalysisError::InvalidParameter`] for a spacing outside its range.
pub fn lattice_weights(points_m: &[(f64, f64)], spacing_m: f64) -> Result<LatticeWeights, AnalysisError> {
    let triangles = delaunay(points_m)?;
    let (lo, hi) = bounds(points_m);
    let extent = (hi.0 - lo.0).max(hi.1 - lo.1);
    if !(spacing_m.is_finite() && spacing_m > 0.0 && spacing_m >= extent / 1000.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "spacing_m",
            reason: format!("{spacing_m} m: a positive spacing of at least 1/1000 of the points' extent {extent} m"),
        });
    }
    // Nodes up to the box's far edges (within rounding), so that a hull vertex on the edge gets its node.
    let count = |span: f64| (span / spacing_m + 1e-9).floor() as usize + 1;
    let grid =
        GridSpec { nx: count(hi.0 - lo.0), ny: count(hi.1 - lo.1), spacing_m, origin_x_m: lo.0, origin_y_m: lo.1 };
    let mut weights: Vec<Option<[(usize, f64); 3]>> = vec![None; grid.len()];
    for t in &triangles {
        let [a, b, c] = t.map(|i| points_m[i]);
        let d = area2(a, b, c);
        if d <= 0.0 {
            continue;
        }
        let (tlo, thi) = bounds(&[a, b, c]);
        let first = |v: f64, o: f64| (((v - o) / spacing_m) - 1e-9).ceil().max(0.0) as usize;
        let last = |v: f64, o: f64, n: usize| ((((v - o) / spacing_m) + 1e-9).floor().max(0.0) as usize).min(n - 1);
        for iy in first(tlo.1, lo.1)..=last(thi.1, lo.1, grid.ny) {
            for ix in first(tlo.0, lo.0)..=last(thi.0, lo.0, grid.nx) {
                let node = grid.index(ix, iy);
                if weights[node].is_some() {
                    continue;
                }
                let p = grid.position_m(node);
                let (wa, wb) = (area2(p, b, c) / d, area2(a, p, c) / d);
                let wc = 1.0 - wa - wb;
                if wa >= -INSIDE_TOLERANCE && wb >= -INSIDE_TOLERANCE && wc >= -INSIDE_TOLERANCE {
                    // Clamped onto the triangle and renormalised: a node on an edge takes its two ends only.
                    let w = [wa.max(0.0), wb.max(0.0), wc.max(0.0)];
                    let sum = w[0] + w[1] + w[2];
                    weights[node] = Some([(t[0], w[0] / sum), (t[1], w[1] / sum), (t[2], w[2] / sum)]);
                }
            }
        }
    }
    let nodes = weights.into_iter().enumerate().filter_map(|(i, w)| Some((i as u32, w?))).collect();
    Ok(LatticeWeights { grid, nodes })
}

/// `g` of scattered points (row `m` at `positions_m[m]`, m) interpolated onto the lattice of `weights`: one row
/// per interpolated node, labelled by its flat index on `weights.grid`.
///
/// # Errors
/// [`AnalysisError::LengthMismatch`] unless there is one position per row of `g`; [`AnalysisError::Empty`] when no
/// node lies inside the hull; [`AnalysisError::Step`] if the matrices cannot be built.
pub fn interpolate_g(g: &PropagationMatrices, weights: &LatticeWeights) -> Result<PropagationMatrices, AnalysisError> {
    if weights.nodes.iter().any(|(_, w)| w.iter().any(|&(i, _)| i >= g.n_points())) {
        return Err(AnalysisError::LengthMismatch {
            what: "interpolation weights' points against the rows of G",
            a: weights.nodes.iter().flat_map(|(_, w)| w.iter().map(|&(i, _)| i + 1)).max().unwrap_or(0),
            b: g.n_points(),
        });
    }
    if weights.nodes.is_empty() {
        return Err(AnalysisError::Empty { input: "lattice nodes inside the points' hull" });
    }
    let (m, n) = (weights.nodes.len(), g.n_actuators());
    let mut data = Vec::with_capacity(g.n_bins() * m * n);
    let mut column = vec![Complex64::new(0.0, 0.0); g.n_points()];
    for k in 0..g.n_bins() {
        let Some(gk) = g.at_bin(k) else { break };
        for a in 0..n {
            for (row, c) in column.iter_mut().enumerate() {
                *c = gk[(row, a)];
            }
            data.extend(weights.apply(&column));
        }
    }
    let nodes = weights.nodes.iter().map(|&(node, _)| node).collect();
    PropagationMatrices::from_parts(g.bins(), g.fft_len(), g.sample_rate_hz(), nodes, g.actuators().to_vec(), data)
        .map_err(|e| AnalysisError::Step { step: "interpolating G(omega) onto a lattice", reason: e.to_string() })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    /// Deterministic jittered points in a 10 x 8 cm rectangle (a scan mesh of about `n` points).
    fn mesh(n: usize) -> Vec<(f64, f64)> {
        let mut state = 99u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| (0.10 * next(), 0.08 * next())).collect()
    }

    #[test]
    fn a_linear_field_is_interpolated_exactly_and_nothing_outside_the_hull() {
        let points = mesh(300);
        let h = median_spacing_m(&points).unwrap();
        let weights = lattice_weights(&points, h).unwrap();
        let field: Vec<f64> = points.iter().map(|p| 3.0 + 20.0 * p.0 - 7.0 * p.1).collect();
        let at_nodes = weights.apply(&field);
        for (&(node, w), v) in weights.nodes.iter().zip(&at_nodes) {
            let p = weights.grid.position_m(node as usize);
            // Exact for a linear field, to rounding (values about 3, so 1e-12 is ~5000 ulps of headroom).
            assert!((v - (3.0 + 20.0 * p.0 - 7.0 * p.1)).abs() < 1e-12, "node {node}: {v}");
            assert!(w.iter().all(|&(_, x)| x >= 0.0) && (w.iter().map(|x| x.1).sum::<f64>() - 1.0).abs() < 1e-12);
        }
        // Every node inside the hull (in a triangle) is interpolated, none outside: the hull of a 300-point random
        // mesh fills most of its box, but not all of it.
        let triangles = delaunay(&points).unwrap();
        let hull_inside = |p: (f64, f64)| {
            triangles.iter().any(|t| {
                let [a, b, c] = t.map(|i| points[i]);
                let d = area2(a, b, c);
                area2(p, b, c) / d >= -1e-9 && area2(a, p, c) / d >= -1e-9 && area2(a, b, p) / d >= -1e-9
            })
        };
        let mask = weights.mask();
        let inside = mask.iter().filter(|&&m| m).count();
        assert!(inside > weights.grid.len() / 2 && inside < weights.grid.len(), "{inside} of {}", weights.grid.len());
        for (node, &m) in mask.iter().enumerate() {
            assert_eq!(m, hull_inside(weights.grid.position_m(node)), "node {node}");
        }
    }

    #[test]
    fn at_the_extremes_points_on_nodes_edges_and_the_hull_are_exact() {
        // A square's corners with its centre: the lattice's corners are the points themselves (weight 1 each), the
        // edges' nodes interpolate between two corners only, and a field of a point's value alone is its hat.
        let points = [(0.0, 0.0), (0.04, 0.0), (0.04, 0.04), (0.0, 0.04), (0.02, 0.02)];
        let weights = lattice_weights(&points, 0.01).unwrap();
        assert_eq!((weights.grid.nx, weights.grid.ny), (5, 5));
        assert_eq!(weights.nodes.len(), 25, "a convex square: every node inside or on the hull");
        for (corner, node) in [(0, 0), (1, 4), (2, 24), (3, 20)] {
            let (_, w) = weights.nodes.iter().find(|(n, _)| *n == node).unwrap();
            let own: f64 = w.iter().filter(|x| x.0 == corner).map(|x| x.1).sum();
            assert!((own - 1.0).abs() < 1e-12, "corner {corner}: {w:?}");
        }
        let hat = weights.apply(&[0.0, 0.0, 0.0, 0.0, 1.0]);
        let at = |node: u32| hat[weights.nodes.iter().position(|(n, _)| *n == node).unwrap()];
        assert!((at(12) - 1.0).abs() < 1e-12, "the centre point");
        assert!(at(2).abs() < 1e-12 && at(10).abs() < 1e-12, "edge nodes take their edge's two corners only");
        assert!((at(6) - 0.5).abs() < 1e-12, "halfway to a corner");
        // A triangle: the box's corner off the hull is not interpolated (nothing extrapolated).
        let weights = lattice_weights(&[(0.0, 0.0), (0.04, 0.0), (0.0, 0.04)], 0.01).unwrap();
        let mask = weights.mask();
        assert!(mask[weights.grid.index(0, 0)] && mask[weights.grid.index(4, 0)] && mask[weights.grid.index(2, 2)]);
        assert!(!mask[weights.grid.index(4, 4)] && !mask[weights.grid.index(3, 2)]);
    }

    #[test]
    fn points_that_span_no_area_are_refused_by_name() {
        let cases = [
            vec![],
            vec![(0.0, 0.0)],
            vec![(0.0, 0.0), (0.01, 0.0)],
            vec![(0.0, 0.0), (0.01, 0.01), (0.03, 0.03)],
            vec![(0.0, 0.0), (0.01, 0.0), (0.0, 0.01), (0.01, 0.0)],
        ];
        for points in cases {
            let e = lattice_weights(&points, 0.01).unwrap_err();
            assert!(matches!(e, AnalysisError::NeedsLattice { .. }), "{e}");
            assert!(e.to_string().contains("span no area"), "{e}");
        }
        assert!(matches!(
            lattice_weights(&[(0.0, 0.0), (0.01, 0.0), (0.0, 0.01)], 0.0),
            Err(AnalysisError::InvalidParameter { name: "spacing_m", .. })
        ));
    }
}

//! The masked square lattice the plate is discretised on.
//!
//! Lattice point `(i, j)` lies at `(origin_x_m + i h, origin_y_m + j h)`. A *cell* is the square between four
//! neighbouring lattice points; it belongs to the plate when all four corners are inside the outline. The *nodes*
//! (the unknowns) are the corners of the plate's cells, so every node carries area and stiffness: a lattice point
//! inside the outline but touching no full cell (a sliver at a curved edge) is dropped rather than left as a loose
//! mass.

use crate::error::PlateError;

/// The largest number of lattice points accepted (a 4000 x 4000 lattice: far finer than any plate here needs).
pub const MAX_LATTICE_POINTS: usize = 16_000_000;

/// A masked square lattice.
#[derive(Debug, Clone)]
pub(crate) struct Mesh {
    /// Lattice spacing h, m.
    pub spacing_m: f64,
    /// Position of lattice point (0, 0), m.
    pub origin_m: (f64, f64),
    /// Lattice points along x and y.
    pub nx: usize,
    /// Lattice points along y.
    pub ny: usize,
    /// Node number of each lattice point (`i + nx j`), if it is a node.
    node_of: Vec<Option<usize>>,
    /// Lattice coordinates of each node.
    pub lattice_of: Vec<(usize, usize)>,
    /// Whether cell `(i, j)` (lower-left corner at lattice point `(i, j)`) is a plate cell; `nx * ny` entries, the
    /// last row and column always false.
    cell_full: Vec<bool>,
}

impl Mesh {
    /// Discretises the region `inside` (true on the plate) within the bounding box `(x_min, x_max, y_min, y_max)`
    /// (m) at spacing `spacing_m` (m), with the lattice aligned so that `anchor_m` is a lattice point.
    ///
    /// Valid range: finite `spacing_m > 0`, a finite box, at most [`MAX_LATTICE_POINTS`] lattice points.
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] for a bad spacing or box or a region with no full cell;
    /// [`PlateError::TooLarge`] for too many lattice points.
    pub fn new(
        inside: &dyn Fn(f64, f64) -> bool,
        bbox_m: (f64, f64, f64, f64),
        spacing_m: f64,
        anchor_m: (f64, f64),
    ) -> Result<Self, PlateError> {
        let (x_min, x_max, y_min, y_max) = bbox_m;
        if !(spacing_m.is_finite() && spacing_m > 0.0) {
            return Err(PlateError::invalid("spacing_m", format!("must be finite and positive, got {spacing_m}")));
        }
        if ![x_min, x_max, y_min, y_max, anchor_m.0, anchor_m.1].iter().all(|v| v.is_finite())
            || x_min >= x_max
            || y_min >= y_max
        {
            return Err(PlateError::invalid("bounding box", format!("must be finite and non-empty, got {bbox_m:?}")));
        }
        // Lattice indices relative to the anchor; one spare point each side so the outline is fully covered.
        let i0 = ((x_min - anchor_m.0) / spacing_m).floor() - 1.0;
        let i1 = ((x_max - anchor_m.0) / spacing_m).ceil() + 1.0;
        let j0 = ((y_min - anchor_m.1) / spacing_m).floor() - 1.0;
        let j1 = ((y_max - anchor_m.1) / spacing_m).ceil() + 1.0;
        let (nx_f, ny_f) = (i1 - i0 + 1.0, j1 - j0 + 1.0);
        if nx_f * ny_f > MAX_LATTICE_POINTS as f64 || !(nx_f * ny_f).is_finite() {
            return Err(PlateError::TooLarge {
                what: "plate lattice",
                needed: (nx_f * ny_f).min(usize::MAX as f64) as usize,
                max: MAX_LATTICE_POINTS,
            });
        }
        let (nx, ny) = (nx_f as usize, ny_f as usize);
        let origin_m = (anchor_m.0 + i0 * spacing_m, anchor_m.1 + j0 * spacing_m);
        let point_in: Vec<bool> = (0..nx * ny)
            .map(|k| inside(origin_m.0 + (k % nx) as f64 * spacing_m, origin_m.1 + (k / nx) as f64 * spacing_m))
            .collect();
        let mut cell_full = vec![false; nx * ny];
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let k = i + nx * j;
                cell_full[k] = point_in[k] && point_in[k + 1] && point_in[k + nx] && point_in[k + nx + 1];
            }
        }
        let mut node_of = vec![None; nx * ny];
        let mut lattice_of = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let touches = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .any(|&(di, dj)| i >= di && j >= dj && cell_full[(i - di) + nx * (j - dj)]);
                if touches {
                    node_of[i + nx * j] = Some(lattice_of.len());
                    lattice_of.push((i, j));
                }
            }
        }
        if lattice_of.is_empty() {
            return Err(PlateError::invalid(
                "spacing_m",
                format!("{spacing_m} m leaves no full cell inside the plate outline"),
            ));
        }
        Ok(Self { spacing_m, origin_m, nx, ny, node_of, lattice_of, cell_full })
    }

    /// Number of nodes (unknowns).
    pub fn len(&self) -> usize {
        self.lattice_of.len()
    }

    /// Node at lattice point `(i, j)`, with signed offsets; `None` off the lattice or off the plate.
    pub fn node(&self, i: isize, j: isize) -> Option<usize> {
        if i < 0 || j < 0 || i as usize >= self.nx || j as usize >= self.ny {
            return None;
        }
        self.node_of[i as usize + self.nx * j as usize]
    }

    /// Whether the cell with lower-left lattice corner `(i, j)` is a plate cell.
    pub fn cell_full(&self, i: isize, j: isize) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self.cell_full[i as usize + self.nx * j as usize]
    }

    /// How many of the four cells around node `n` are plate cells (1 to 4): a node's share of area is this / 4.
    pub fn cells_around(&self, n: usize) -> usize {
        let (i, j) = (self.lattice_of[n].0 as isize, self.lattice_of[n].1 as isize);
        [(0, 0), (-1, 0), (0, -1), (-1, -1)].iter().filter(|&&(di, dj)| self.cell_full(i + di, j + dj)).count()
    }

    /// Position of node `n`, m.
    pub fn position_m(&self, n: usize) -> (f64, f64) {
        let (i, j) = self.lattice_of[n];
        (self.origin_m.0 + i as f64 * self.spacing_m, self.origin_m.1 + j as f64 * self.spacing_m)
    }

    /// Bilinear interpolation weights `(node, weight)` of the point `(x_m, y_m)`: the displacement there is
    /// `sum weight * w[node]`, and a point force there loads the nodes with the same weights (which keeps the model
    /// reciprocal). Corners with a negligible weight (the point lies on a lattice line or point) are skipped, so a
    /// point exactly on a node needs only that node. `None` when a needed corner is not a node.
    pub fn interpolation(&self, x_m: f64, y_m: f64) -> Option<Vec<(usize, f64)>> {
        let fx = (x_m - self.origin_m.0) / self.spacing_m;
        let fy = (y_m - self.origin_m.1) / self.spacing_m;
        if !(fx.is_finite() && fy.is_finite()) || fx < 0.0 || fy < 0.0 || fx >= self.nx as f64 || fy >= self.ny as f64 {
            return None;
        }
        let (i, j) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - i, fy - j);
        let (i, j) = (i as isize, j as isize);
        // Rounding can leave a point meant to sit on a lattice line a few ulps off it; 1e-9 of a cell is far below
        // any physical length and far above that rounding.
        const NEGLIGIBLE: f64 = 1e-9;
        let mut weights = Vec::with_capacity(4);
        for (di, dj, w) in
            [(0, 0, (1.0 - tx) * (1.0 - ty)), (1, 0, tx * (1.0 - ty)), (0, 1, (1.0 - tx) * ty), (1, 1, tx * ty)]
        {
            if w > NEGLIGIBLE {
                weights.push((self.node(i + di, j + dj)?, w));
            }
        }
        let total: f64 = weights.iter().map(|(_, w)| w).sum();
        weights.iter_mut().for_each(|(_, w)| *w /= total);
        Some(weights)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_nodes_and_area_shares() {
        // A 4 h x 2 h rectangle anchored on a corner: 5 x 3 nodes, corner nodes a quarter, edge nodes half.
        let h = 0.01;
        let inside = |x: f64, y: f64| (-1e-12..=0.04 + 1e-12).contains(&x) && (-1e-12..=0.02 + 1e-12).contains(&y);
        let mesh = Mesh::new(&inside, (0.0, 0.04, 0.0, 0.02), h, (0.0, 0.0)).unwrap();
        assert_eq!(mesh.len(), 15);
        let shares: usize = (0..mesh.len()).map(|n| mesh.cells_around(n)).sum();
        assert_eq!(shares, 4 * 8, "8 cells of 4 corners each");
        let corner = mesh.interpolation(0.0, 0.0).unwrap();
        assert_eq!(corner.len(), 1);
        assert_eq!(mesh.cells_around(corner[0].0), 1);
        let mid = mesh.interpolation(0.015, 0.005).unwrap();
        assert_eq!(mid.len(), 4);
        assert!(mid.iter().all(|&(_, w)| (w - 0.25).abs() < 1e-12));
        assert!(mesh.interpolation(0.05, 0.01).is_none());
    }

    #[test]
    fn refuses_bad_spacing_and_empty_regions() {
        let inside = |_: f64, _: f64| true;
        assert!(Mesh::new(&inside, (0.0, 1.0, 0.0, 1.0), 0.0, (0.0, 0.0)).is_err());
        assert!(Mesh::new(&inside, (0.0, 1.0, 0.0, 1.0), f64::NAN, (0.0, 0.0)).is_err());
        assert!(matches!(Mesh::new(&inside, (0.0, 1.0, 0.0, 1.0), 1e-5, (0.0, 0.0)), Err(PlateError::TooLarge { .. })));
        let nowhere = |_: f64, _: f64| false;
        assert!(Mesh::new(&nowhere, (0.0, 1.0, 0.0, 1.0), 0.1, (0.0, 0.0)).is_err());
    }
}

//! The sparsity pattern shared by every matrix of the model (compressed sparse columns).
//!
//! All matrices (bending stiffness, supports, masses, rotary inertia) live on one pattern: the 13-point
//! neighbourhood of each node (the 3 x 3 block and the points two steps away along x and y), which holds the bending
//! stencils' couplings. The system matrix at a frequency is then a weighted sum of value arrays, and the LU's symbolic
//! analysis is done once.

use crate::mesh::Mesh;

/// Lattice offsets coupled by the discrete bending energy: the 3 x 3 block plus (+-2, 0) and (0, +-2).
const NEIGHBOURS: [(isize, isize); 13] =
    [(0, -2), (-1, -1), (0, -1), (1, -1), (-2, 0), (-1, 0), (0, 0), (1, 0), (2, 0), (-1, 1), (0, 1), (1, 1), (0, 2)];

/// A square symmetric sparsity pattern in compressed sparse column form, row indices sorted within each column.
#[derive(Debug, Clone)]
pub(crate) struct Pattern {
    /// Column starts, `n + 1` entries.
    pub col_ptr: Vec<usize>,
    /// Row index of each stored entry.
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// The 13-point pattern of `mesh`.
    pub fn new(mesh: &Mesh) -> Self {
        let mut col_ptr = Vec::with_capacity(mesh.len() + 1);
        let mut row_idx = Vec::with_capacity(13 * mesh.len());
        col_ptr.push(0);
        for n in 0..mesh.len() {
            let (i, j) = (mesh.lattice_of[n].0 as isize, mesh.lattice_of[n].1 as isize);
            let start = row_idx.len();
            row_idx.extend(NEIGHBOURS.iter().filter_map(|&(di, dj)| mesh.node(i + di, j + dj)));
            row_idx[start..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        Self { col_ptr, row_idx }
    }

    /// Number of rows (= columns).
    pub fn dim(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Position of entry `(row, col)` in the value array, if it is in the pattern.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let (start, end) = (*self.col_ptr.get(col)?, *self.col_ptr.get(col + 1)?);
        self.row_idx[start..end].binary_search(&row).ok().map(|k| start + k)
    }

    /// Adds `scale * s s^T` to `values`, where `s` is a sparse vector `(node, coefficient)` whose nodes all lie
    /// within one 13-point neighbourhood of each other (true of every stencil and interpolation used here).
    /// Returns false, touching nothing, if an entry falls outside the pattern (a programming error upstream).
    pub fn add_outer(&self, values: &mut [f64], s: &[(usize, f64)], scale: f64) -> bool {
        self.add_product(values, s, s, scale)
    }

    /// Adds `scale * a b^T` to `values` (see [`Pattern::add_outer`]).
    pub fn add_product(&self, values: &mut [f64], a: &[(usize, f64)], b: &[(usize, f64)], scale: f64) -> bool {
        let mut positions = Vec::with_capacity(a.len() * b.len());
        for &(r, _) in a {
            for &(c, _) in b {
                match self.position(r, c) {
                    Some(p) => positions.push(p),
                    None => return false,
                }
            }
        }
        let mut k = 0;
        for &(_, va) in a {
            for &(_, vb) in b {
                values[positions[k]] += scale * va * vb;
                k += 1;
            }
        }
        true
    }
}

//! The cell's mesh: an O-grid of biquadratic (9-node) quadrilaterals between the circular footprint and the square
//! cell's sides, graded in radius (small elements where the rocking footprint bends the plate most).
//!
//! The ring of elements is indexed by a tangential index `j` (counter-clockwise from the angle -45 degrees, `8 nt`
//! node columns: `nt` elements per side, two node columns each) and a radial index `i` (`0` on the footprint's
//! circle, `2 nr` on the cell's side). The nodes on opposite sides sit at the same coordinate along the side, so
//! the Bloch conditions pair them one to one.

/// Mesh resolution of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshOptions {
    /// Elements along each side of the cell (tangentially, per quarter of the ring).
    pub per_side: usize,
    /// Elements from the footprint to the cell's side.
    pub radial: usize,
    /// Beam elements along the rod.
    pub rod_elements: usize,
}

impl Default for MeshOptions {
    /// The default meshes: converged to 0.5 % on the first three branches of the paper's cell (docs/design.md).
    fn default() -> Self {
        Self { per_side: 3, radial: 3, rod_elements: 6 }
    }
}

impl MeshOptions {
    /// `n` times finer than [`MeshOptions::default`] in every direction (refinement studies).
    pub fn refined(n: usize) -> Self {
        let d = Self::default();
        Self { per_side: d.per_side * n, radial: d.radial * n, rod_elements: d.rod_elements * n }
    }
}

/// Node coordinates and 9-node elements of the ring.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Node coordinates (x, y), m, the cell centred on the origin.
    pub nodes: Vec<[f64; 2]>,
    /// Elements: node indices in tensor order `[a + 3 b]`, `a` tangential, `b` radial (0, 1, 2 each).
    pub elements: Vec<[usize; 9]>,
    /// Nodes on the footprint's circle (rigidly attached to it).
    pub footprint_nodes: Vec<usize>,
    /// Nodes on the cell's sides.
    pub side_nodes: Vec<usize>,
}

impl Mesh {
    /// The O-grid of a square cell of side `a_m` around a footprint of radius `r_m` (`0 < r_m < a_m / 2`).
    pub fn o_grid(a_m: f64, r_m: f64, options: MeshOptions) -> Self {
        let nt = options.per_side.max(1);
        let nr = options.radial.max(1);
        let columns = 8 * nt;
        let rows = 2 * nr + 1;
        let half = a_m / 2.0;
        let mut nodes = Vec::with_capacity(columns * rows);
        for j in 0..columns {
            let side = j / (2 * nt);
            let t = 2.0 * (j - side * 2 * nt) as f64 / (2 * nt) as f64 - 1.0;
            let angle = -std::f64::consts::FRAC_PI_4 + 2.0 * std::f64::consts::PI * j as f64 / columns as f64;
            let (sin, cos) = (side as f64 * std::f64::consts::FRAC_PI_2).sin_cos();
            let outer = [half * cos - half * t * sin, half * sin + half * t * cos];
            let inner = [r_m * angle.cos(), r_m * angle.sin()];
            let (r_in, r_out) = (r_m, (outer[0].powi(2) + outer[1].powi(2)).sqrt());
            // Element edges halfway between an even and a geometric spacing (the distance from the centre growing
            // by a constant ratio): small elements at the footprint, where the rocking bends the plate most,
            // without starving the rest of the cell when the footprint is tiny; mid-side nodes halfway between,
            // so that each element's map is affine along the radius.
            let edge = |e: usize| {
                let xi = e as f64 / nr as f64;
                let radius = r_in * (r_out / r_in).powf(xi);
                0.5 * (xi + (radius - r_in) / (r_out - r_in))
            };
            for i in 0..rows {
                let s = if i % 2 == 0 { edge(i / 2) } else { 0.5 * (edge(i / 2) + edge(i / 2 + 1)) };
                nodes.push([inner[0] + s * (outer[0] - inner[0]), inner[1] + s * (outer[1] - inner[1])]);
            }
        }
        let id = |j: usize, i: usize| (j % columns) * rows + i;
        let mut elements = Vec::with_capacity(4 * nt * nr);
        for et in 0..4 * nt {
            for er in 0..nr {
                let mut e = [0; 9];
                for b in 0..3 {
                    for a in 0..3 {
                        e[a + 3 * b] = id(2 * et + a, 2 * er + b);
                    }
                }
                elements.push(e);
            }
        }
        let footprint_nodes = (0..columns).map(|j| id(j, 0)).collect();
        let side_nodes = (0..columns).map(|j| id(j, rows - 1)).collect();
        Self { nodes, elements, footprint_nodes, side_nodes }
    }
}

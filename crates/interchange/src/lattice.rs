//! Positions as other tools write them: points in three dimensions (a scan mesh on a tilted or rotated plate),
//! placed on the regular lattice they lie on within a tolerance, with the plane, the rotation, the spacing and the
//! residuals found.
//!
//! The plane is the least-squares plane of the points (through their centroid, normal along the covariance's
//! smallest eigenvector); the points are expressed in it (u along the projection of x, or of y when x is the normal).
//! The lattice's rotation is the mean direction of the nearest-neighbour vectors modulo 90° (the circular mean of
//! 4φ), its spacing the median nearest-neighbour distance, refined with the origin by least squares over every
//! point's node. The points lie on it when each is within [`LATTICE_TOLERANCE`] of a spacing of its node and no two
//! share a node.

use metaplate_core::grid::{GridSpec, MAX_GRID_POINTS};
use metaplate_core::points::{median_distance_m, nearest_neighbours};

/// Largest distance of a point from its lattice node accepted, in spacings (a scan head's positioning and a mesh
/// written with 6 digits sit far below it; a point between two nodes lies half a spacing off).
pub const LATTICE_TOLERANCE: f64 = 0.1;

/// Most points fitted (the nearest neighbours are found pairwise).
pub const MAX_LATTICE_POINTS: usize = 20_000;

/// A lattice found in 3-D points.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// The grid in the plane's rotated coordinates, m.
    pub grid: GridSpec,
    /// Each point's flat index in `grid`.
    pub indices: Vec<usize>,
    /// Each point's in-plane rotated coordinates (the grid's frame), m.
    pub in_plane_m: Vec<(f64, f64)>,
    /// The frame, to place other points (the actuators) in it.
    pub frame: Frame,
    /// RMS distance of the points from the plane, m.
    pub plane_rms_m: f64,
    /// RMS and largest distance of the points from their lattice nodes, m.
    pub lattice_rms_m: f64,
    /// Largest distance of a point from its node, m.
    pub lattice_max_m: f64,
}

impl Lattice {
    /// One line for the import's report.
    pub fn describe(&self) -> String {
        // Rounded to the digits shown, without a sign on zero.
        let n = self.frame.normal.map(|v| (v * 1e3).round() / 1e3 + 0.0);
        format!(
            "nodes on a lattice: plane normal ({:.3}, {:.3}, {:.3}) with points {:.3} µm rms off it; rotated {:.3}°; \
             {} x {} at {:.4} mm; points {:.3} µm rms, {:.3} µm at most, off their nodes",
            n[0],
            n[1],
            n[2],
            self.plane_rms_m * 1e6,
            self.frame.rotation_rad.to_degrees(),
            self.grid.nx,
            self.grid.ny,
            self.grid.spacing_m * 1e3,
            self.lattice_rms_m * 1e6,
            self.lattice_max_m * 1e6
        )
    }
}

/// The plane's frame: centroid, in-plane axes, normal, and the lattice's rotation in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Centroid of the points, m.
    pub centroid_m: [f64; 3],
    /// In-plane unit axes.
    pub u: [f64; 3],
    /// Second in-plane axis (normal × u).
    pub v: [f64; 3],
    /// Unit normal of the plane.
    pub normal: [f64; 3],
    /// The lattice's rotation about the normal, radians.
    pub rotation_rad: f64,
}

impl Frame {
    /// `p` (m) in the lattice's frame: projected on the plane, rotated by `-rotation_rad`.
    pub fn place(&self, p: [f64; 3]) -> (f64, f64) {
        let d = [p[0] - self.centroid_m[0], p[1] - self.centroid_m[1], p[2] - self.centroid_m[2]];
        let (a, b) = (dot(d, self.u), dot(d, self.v));
        let (s, c) = self.rotation_rad.sin_cos();
        (c * a + s * b, -s * a + c * b)
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 { [a[0] / n, a[1] / n, a[2] / n] } else { a }
}

/// The eigenvector of the smallest eigenvalue of the symmetric 3 x 3 matrix `m` (cyclic Jacobi rotations).
fn smallest_eigenvector(mut m: [[f64; 3]; 3]) -> [f64; 3] {
    let mut vectors = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
        if off <= 1e-30 * (m[0][0].abs() + m[1][1].abs() + m[2][2].abs()).max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if m[p][q] == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // m <- Jᵀ m J, columns p and q of the vectors rotated with it.
            for row in &mut m {
                let (mkp, mkq) = (row[p], row[q]);
                row[p] = c * mkp - s * mkq;
                row[q] = s * mkp + c * mkq;
            }
            let (row_p, row_q) = (m[p], m[q]);
            m[p] = std::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            m[q] = std::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            for row in &mut vectors {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let smallest = (0..3).min_by(|&a, &b| m[a][a].total_cmp(&m[b][b])).unwrap_or(2);
    unit([vectors[0][smallest], vectors[1][smallest], vectors[2][smallest]])
}

/// The least-squares plane of `points_m` (finite, at least one): its frame (through the centroid, normal along the
/// covariance's smallest eigenvector oriented towards +z, else +y, +x; u along the projection of x, or of y when x
/// is the normal; no rotation) and the points' RMS distance from it, m.
pub fn plane(points_m: &[[f64; 3]]) -> (Frame, f64) {
    let n = points_m.len().max(1);
    let mut centroid = [0.0; 3];
    for p in points_m {
        for k in 0..3 {
            centroid[k] += p[k] / n as f64;
        }
    }
    let mut cov = [[0.0; 3]; 3];
    for p in points_m {
        let d = [p[0] - centroid[0], p[1] - centroid[1], p[2] - centroid[2]];
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, c) in row.iter_mut().enumerate() {
                *c += d[i] * d[j];
            }
        }
    }
    let mut normal = smallest_eigenvector(cov);
    // Oriented towards +z (else +y, +x), so that a plate in the xy plane keeps its axes.
    let sign = if normal[2] != 0.0 {
        normal[2]
    } else if normal[1] != 0.0 {
        normal[1]
    } else {
        normal[0]
    };
    if sign < 0.0 {
        normal = [-normal[0], -normal[1], -normal[2]];
    }
    let x_axis = if normal[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let along = dot(x_axis, normal);
    let u = unit([x_axis[0] - along * normal[0], x_axis[1] - along * normal[1], x_axis[2] - along * normal[2]]);
    let v = cross(normal, u);
    let frame = Frame { centroid_m: centroid, u, v, normal, rotation_rad: 0.0 };
    let plane_rms_m = (points_m
        .iter()
        .map(|p| dot([p[0] - centroid[0], p[1] - centroid[1], p[2] - centroid[2]], normal).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    (frame, plane_rms_m)
}

/// The lattice the 3-D points `points_m` lie on, or why not.
///
/// # Errors
/// A sentence: fewer than 2 points, more than [`MAX_LATTICE_POINTS`], a non-finite coordinate, points that do not
/// lie on a lattice within [`LATTICE_TOLERANCE`] (with the worst point's distance), two on one node, a lattice of
/// more than [`MAX_GRID_POINTS`].
pub fn fit(points_m: &[[f64; 3]]) -> Result<Lattice, String> {
    let n = points_m.len();
    if !(2..=MAX_LATTICE_POINTS).contains(&n) {
        return Err(format!("{n} points: a lattice is fitted to 2 to {MAX_LATTICE_POINTS}"));
    }
    if points_m.iter().flatten().any(|v| !v.is_finite()) {
        return Err("a coordinate is not finite".into());
    }
    let (mut frame, plane_rms_m) = plane(points_m);
    let flat: Vec<(f64, f64)> = points_m.iter().map(|&p| frame.place(p)).collect();
    let nearest = nearest_neighbours(&flat);
    if nearest.iter().any(|n| n.distance_m <= 0.0) {
        return Err("two points are at one position".into());
    }
    let Some(mut spacing) = median_distance_m(&nearest) else { return Err("the points have no spacing".into()) };
    let (s4, c4) = nearest
        .iter()
        .fold((0.0, 0.0), |(s, c), n| (s + (4.0 * n.direction_rad).sin(), c + (4.0 * n.direction_rad).cos()));
    frame.rotation_rad = s4.atan2(c4) / 4.0;
    let rotated: Vec<(f64, f64)> = points_m.iter().map(|&p| frame.place(p)).collect();
    let x0 = rotated.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let y0 = rotated.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let steps: Vec<(f64, f64)> =
        rotated.iter().map(|p| (((p.0 - x0) / spacing).round(), ((p.1 - y0) / spacing).round())).collect();
    // Least squares of x = ox + i s, y = oy + j s over (ox, oy, s).
    let (mut sii, mut si, mut sj, mut sxi, mut sx, mut sy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, &(i, j)) in rotated.iter().zip(&steps) {
        sii += i * i + j * j;
        si += i;
        sj += j;
        sxi += p.0 * i + p.1 * j;
        sx += p.0;
        sy += p.1;
    }
    let nf = n as f64;
    let denominator = sii - (si * si + sj * sj) / nf;
    if denominator > 0.0 {
        spacing = (sxi - (sx * si + sy * sj) / nf) / denominator;
    }
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err("no spacing could be found".into());
    }
    let (ox, oy) = ((sx - spacing * si) / nf, (sy - spacing * sj) / nf);
    let nx = steps.iter().map(|s| s.0).fold(0.0, f64::max) + 1.0;
    let ny = steps.iter().map(|s| s.1).fold(0.0, f64::max) + 1.0;
    if nx * ny > MAX_GRID_POINTS as f64 {
        return Err(format!("a {nx} x {ny} lattice exceeds the limit of {MAX_GRID_POINTS} points"));
    }
    let grid = GridSpec { nx: nx as usize, ny: ny as usize, spacing_m: spacing, origin_x_m: ox, origin_y_m: oy };
    let mut taken = vec![false; grid.len()];
    let (mut sum2, mut worst) = (0.0f64, (0.0f64, 0usize));
    let mut indices = Vec::with_capacity(n);
    for (k, (p, &(i, j))) in rotated.iter().zip(&steps).enumerate() {
        let off = (p.0 - ox - i * spacing).hypot(p.1 - oy - j * spacing);
        sum2 += off * off;
        if off > worst.0 {
            worst = (off, k);
        }
        let index = grid.index(i as usize, j as usize);
        if std::mem::replace(&mut taken[index], true) {
            return Err(format!("two points fall on one node ({i}, {j}) of a lattice at {:.4} mm", spacing * 1e3));
        }
        indices.push(index);
    }
    if worst.0 > LATTICE_TOLERANCE * spacing {
        return Err(format!(
            "point {} lies {:.4} mm from its node of the best lattice ({:.4} mm spacing, rotated {:.2}°), more than \
             {LATTICE_TOLERANCE} of a spacing",
            worst.1,
            worst.0 * 1e3,
            spacing * 1e3,
            frame.rotation_rad.to_degrees()
        ));
    }
    Ok(Lattice {
        grid,
        indices,
        in_plane_m: rotated,
        frame,
        plane_rms_m,
        lattice_rms_m: (sum2 / nf).sqrt(),
        lattice_max_m: worst.0,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    /// A 7 x 5 lattice at 4 mm, rotated `angle` about z, tilted `tilt` about x, offset, with `noise_m` of jitter.
    fn mesh(angle: f64, tilt: f64, noise_m: f64) -> Vec<[f64; 3]> {
        let mut state = 12345u64;
        let mut jitter = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 2.0 * noise_m
        };
        let mut out = Vec::new();
        for j in 0..5 {
            for i in 0..7 {
                let (x, y) = (i as f64 * 0.004 + jitter(), j as f64 * 0.004 + jitter());
                let (xr, yr) = (x * angle.cos() - y * angle.sin(), x * angle.sin() + y * angle.cos());
                out.push([0.1 + xr, 0.2 + yr * tilt.cos(), 0.3 + yr * tilt.sin()]);
            }
        }
        out
    }

    #[test]
    fn a_rotated_tilted_lattice_is_found_with_its_spacing_and_residuals() {
        for (angle, tilt) in [(0.0, 0.0), (0.3, 0.0), (-0.2, 0.7), (1.0, 1.2)] {
            let points = mesh(angle, tilt, 0.0);
            let lattice = fit(&points).unwrap();
            assert_eq!((lattice.grid.nx * lattice.grid.ny, lattice.indices.len()), (35, 35), "{angle} {tilt}");
            assert!((lattice.grid.spacing_m - 0.004).abs() < 1e-12, "{}", lattice.grid.spacing_m);
            assert!(lattice.plane_rms_m < 1e-12 && lattice.lattice_max_m < 1e-12, "{lattice:?}");
            // Distances within the plane are kept: neighbours one spacing apart.
            let (a, b) = (lattice.frame.place(points[0]), lattice.frame.place(points[1]));
            assert!(((a.0 - b.0).hypot(a.1 - b.1) - 0.004).abs() < 1e-12);
        }
        // Jitter of 0.05 mm (1/80 of the spacing) is within the tolerance and reported.
        let lattice = fit(&mesh(0.4, 0.3, 5e-5)).unwrap();
        assert!(lattice.lattice_max_m > 1e-5 && lattice.lattice_max_m < 1e-4, "{}", lattice.lattice_max_m);
    }

    #[test]
    fn scattered_points_are_no_lattice_and_say_why() {
        let mut points = mesh(0.3, 0.2, 0.0);
        points[17][0] += 0.0015;
        let why = fit(&points).unwrap_err();
        assert!(why.starts_with("point 17 lies"), "{why}");
        assert!(fit(&points[..1]).unwrap_err().starts_with("1 points"));
    }
}

//! Element matrices: the Mindlin plate's 9-node quadrilateral and the rod's beam element.
//!
//! Plate: three degrees of freedom per node, the deflection `w` and the rotations `bx`, `by` of the normal, with
//! in-plane displacements `u = z bx`, `v = z by` (Kirchhoff's limit: `bx = -w_x`). Bending, transverse shear
//! (factor 5/6) and rotary inertia, full 3x3 Gauss integration: with elements no longer than a few plate thicknesses,
//! as the cells' are, shear locking is negligible (the homogeneous cell matches the analytic A0: tests).
//!
//! Beam: lateral displacement and section rotation at each end, cubic Hermite interpolation with the Timoshenko
//! shear parameter in the stiffness (exact for end loads) and the consistent mass with the sections' rotary
//! inertia (Rayleigh).

use metaplate_core::design::CellPlate;

/// Degrees of freedom of a plate element.
pub const PLATE_DOFS: usize = 27;

/// Stiffness and mass of one 9-node Mindlin element, row-major `PLATE_DOFS x PLATE_DOFS`, DOF `3 n + c` for node
/// `n` (tensor order) and component `c` in (w, bx, by).
pub fn mindlin_q9(plate: &CellPlate, xy: &[[f64; 2]; 9]) -> (Vec<f64>, Vec<f64>) {
    const G: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let d = plate.flexural_rigidity_n_m();
    let nu = plate.poisson_ratio;
    let shear_modulus = plate.youngs_modulus_pa / (2.0 * (1.0 + nu));
    let shear = 5.0 / 6.0 * shear_modulus * plate.thickness_m;
    let rho_h = plate.areal_density_kg_m2();
    let rho_i = plate.density_kg_m3 * plate.thickness_m.powi(3) / 12.0;
    let bending = [[d, d * nu, 0.0], [d * nu, d, 0.0], [0.0, 0.0, d * (1.0 - nu) / 2.0]];
    let mut k = vec![0.0; PLATE_DOFS * PLATE_DOFS];
    let mut m = vec![0.0; PLATE_DOFS * PLATE_DOFS];
    for (gx, wx) in G.iter().zip(W) {
        for (gy, wy) in G.iter().zip(W) {
            let (n, dn_dxi, dn_deta) = shape(*gx, *gy);
            // Jacobian of (xi, eta) -> (x, y).
            let mut j = [[0.0; 2]; 2];
            for a in 0..9 {
                j[0][0] += dn_dxi[a] * xy[a][0];
                j[0][1] += dn_dxi[a] * xy[a][1];
                j[1][0] += dn_deta[a] * xy[a][0];
                j[1][1] += dn_deta[a] * xy[a][1];
            }
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let (dx, dy): (Vec<f64>, Vec<f64>) = (0..9)
                .map(|a| {
                    let dx = (j[1][1] * dn_dxi[a] - j[0][1] * dn_deta[a]) / det;
                    let dy = (-j[1][0] * dn_dxi[a] + j[0][0] * dn_deta[a]) / det;
                    (dx, dy)
                })
                .unzip();
            let weight = wx * wy * det.abs();
            // Strain rows: curvatures (3) and shear strains (2), each as (dof, coefficient) pairs.
            for a in 0..9 {
                for b in 0..9 {
                    let (ia, ib) = (3 * a, 3 * b);
                    // Bending: kappa = [bx_x, by_y, bx_y + by_x].
                    let ka = [[0.0, dx[a], 0.0], [0.0, 0.0, dy[a]], [0.0, dy[a], dx[a]]];
                    let kb = [[0.0, dx[b], 0.0], [0.0, 0.0, dy[b]], [0.0, dy[b], dx[b]]];
                    // Shear: gamma = [w_x + bx, w_y + by].
                    let sa = [[dx[a], n[a], 0.0], [dy[a], 0.0, n[a]]];
                    let sb = [[dx[b], n[b], 0.0], [dy[b], 0.0, n[b]]];
                    for ca in 0..3 {
                        for cb in 0..3 {
                            let mut v = 0.0;
                            for (p, row) in bending.iter().enumerate() {
                                for (q, dpq) in row.iter().enumerate() {
                                    v += ka[p][ca] * dpq * kb[q][cb];
                                }
                            }
                            v += shear * (sa[0][ca] * sb[0][cb] + sa[1][ca] * sb[1][cb]);
                            k[(ia + ca) * PLATE_DOFS + ib + cb] += weight * v;
                        }
                    }
                    let nn = weight * n[a] * n[b];
                    m[ia * PLATE_DOFS + ib] += rho_h * nn;
                    m[(ia + 1) * PLATE_DOFS + ib + 1] += rho_i * nn;
                    m[(ia + 2) * PLATE_DOFS + ib + 2] += rho_i * nn;
                }
            }
        }
    }
    (k, m)
}

/// Biquadratic Lagrange shape functions and their derivatives at (xi, eta), tensor order `a + 3 b`.
fn shape(xi: f64, eta: f64) -> ([f64; 9], [f64; 9], [f64; 9]) {
    let l = |t: f64| [t * (t - 1.0) / 2.0, 1.0 - t * t, t * (t + 1.0) / 2.0];
    let dl = |t: f64| [t - 0.5, -2.0 * t, t + 0.5];
    let (lx, dlx, ly, dly) = (l(xi), dl(xi), l(eta), dl(eta));
    let mut n = [0.0; 9];
    let mut dxi = [0.0; 9];
    let mut deta = [0.0; 9];
    for b in 0..3 {
        for a in 0..3 {
            n[a + 3 * b] = lx[a] * ly[b];
            dxi[a + 3 * b] = dlx[a] * ly[b];
            deta[a + 3 * b] = lx[a] * dly[b];
        }
    }
    (n, dxi, deta)
}

/// A uniform circular beam's section properties.
#[derive(Debug, Clone, Copy)]
pub struct BeamSection {
    /// Bending stiffness E I, N m^2.
    pub ei: f64,
    /// Shear stiffness kappa G A, N (circular section: kappa = 6 (1 + nu) / (7 + 6 nu)).
    pub kga: f64,
    /// Mass per length rho A, kg/m.
    pub rho_a: f64,
    /// Rotary inertia per length rho I, kg m.
    pub rho_i: f64,
}

impl BeamSection {
    /// A solid circular section of diameter `d_m`.
    pub fn circular(d_m: f64, youngs_pa: f64, poisson: f64, density_kg_m3: f64) -> Self {
        let area = std::f64::consts::PI * d_m * d_m / 4.0;
        let inertia = std::f64::consts::PI * d_m.powi(4) / 64.0;
        let kappa = 6.0 * (1.0 + poisson) / (7.0 + 6.0 * poisson);
        let g = youngs_pa / (2.0 * (1.0 + poisson));
        Self {
            ei: youngs_pa * inertia,
            kga: kappa * g * area,
            rho_a: density_kg_m3 * area,
            rho_i: density_kg_m3 * inertia,
        }
    }
}

/// Stiffness and mass of a beam element of length `l_m` in one bending plane, row-major 4x4, DOFs (u1, psi1, u2,
/// psi2): lateral displacement and section rotation at each end.
pub fn beam(section: &BeamSection, l_m: f64) -> ([f64; 16], [f64; 16]) {
    let l = l_m;
    let phi = 12.0 * section.ei / (section.kga * l * l);
    let c = section.ei / (l.powi(3) * (1.0 + phi));
    let k = [
        12.0,
        6.0 * l,
        -12.0,
        6.0 * l,
        6.0 * l,
        (4.0 + phi) * l * l,
        -6.0 * l,
        (2.0 - phi) * l * l,
        -12.0,
        -6.0 * l,
        12.0,
        -6.0 * l,
        6.0 * l,
        (2.0 - phi) * l * l,
        -6.0 * l,
        (4.0 + phi) * l * l,
    ]
    .map(|v| c * v);
    let ct = section.rho_a * l / 420.0;
    let translational = [
        156.0,
        22.0 * l,
        54.0,
        -13.0 * l,
        22.0 * l,
        4.0 * l * l,
        13.0 * l,
        -3.0 * l * l,
        54.0,
        13.0 * l,
        156.0,
        -22.0 * l,
        -13.0 * l,
        -3.0 * l * l,
        -22.0 * l,
        4.0 * l * l,
    ];
    let cr = section.rho_i / (30.0 * l);
    let rotary = [
        36.0,
        3.0 * l,
        -36.0,
        3.0 * l,
        3.0 * l,
        4.0 * l * l,
        -3.0 * l,
        -l * l,
        -36.0,
        -3.0 * l,
        36.0,
        -3.0 * l,
        3.0 * l,
        -l * l,
        -3.0 * l,
        4.0 * l * l,
    ];
    let mut m = [0.0; 16];
    for i in 0..16 {
        m[i] = ct * translational[i] + cr * rotary[i];
    }
    (k, m)
}

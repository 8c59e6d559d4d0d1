//! The homogenised rocking-rod plate fitted to a cell's slow branch: the parameters a continuum plate model needs so
//! that its flexural waves follow the cell's first branch where the lattice is fine against the wavelength.
//!
//! The model (the simulated plate's `rocking_rod`): per unit area, the cell's whole mass `rho_c` (plate, footprint
//! and rod) moves with the plate, the rod's rotary inertia `J` about its base (per cell, `J / a^2` per area) rocks
//! with the plate's slope through a joint resonating at `f_r`, and the rigid footprints stiffen the plate to
//! `s_D D`. Its dispersion, `s_D D k^4 = w^2 [rho_c + J w_r^2 / (w_r^2 - w^2) k^2 / a^2]`, is a quadratic in `w^2`;
//! its lower root is the slow branch. The mass is the cell's (known); `s_D`, `J` and `f_r` are fitted by
//! Levenberg-Marquardt (QR least squares per step) on log-parameters, minimising the relative frequency error at the
//! cell's branch points along Gamma-X and Gamma-M with `|k| a <= pi / 2` (wavelengths of 4 lattice constants and
//! more: beyond that the waves see the lattice, and no continuum follows them).

use std::f64::consts::PI;

use faer::Mat;
use faer::linalg::solvers::SolveLstsq;
use serde::Serialize;

use metaplate_core::design::{CellResonator, Design};

use crate::bloch::{Reduction, Sides};
use crate::error::DesignError;
use crate::mesh::MeshOptions;
use crate::model::CellModel;

/// The fitted points' largest `|k| a`: wavelengths of at least 4 lattice constants.
pub const HOMOGENISED_MAX_KA: f64 = PI / 2.0;

/// Fewest branch points a fit takes (three parameters, and one more to show a residual).
const MIN_POINTS: usize = 4;

/// Wave vectors per direction (Gamma-X, Gamma-M) that [`homogenised_rocking_rod`] solves.
const POINTS_PER_DIRECTION: usize = 8;

/// Levenberg-Marquardt steps at most; the fit converges in a few tens from the starting point below.
const MAX_STEPS: usize = 200;

/// The homogenised rocking-rod model of a rod design, and how well it follows the cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RockingRodFit {
    /// Cell mass per area beyond the bare plate's, over the bare plate's `rho h` (rod, footprint), dimensionless.
    pub added_mass_ratio: f64,
    /// The homogenised plate's bending stiffness over the bare plate's `D` (the rigid footprints stiffen it).
    pub rigidity_factor: f64,
    /// The rod's effective rotary inertia about its base, per cell, kg m^2.
    pub rotary_inertia_kg_m2: f64,
    /// The rocking joint's resonance, Hz.
    pub resonance_hz: f64,
    /// Branch points fitted.
    pub points: usize,
    /// The fitted points' frequency range, Hz.
    pub min_freq_hz: f64,
    /// The fitted points' frequency range, Hz.
    pub max_freq_hz: f64,
    /// Largest relative frequency error of the model at the fitted points.
    pub max_relative_error: f64,
    /// Root-mean-square relative frequency error at the fitted points.
    pub rms_relative_error: f64,
}

impl RockingRodFit {
    /// The model's slow-branch frequency at wavenumber `k_rad_m` for `design`'s plate and lattice, Hz.
    ///
    /// Valid for `k_rad_m >= 0`; 0 at 0. Finite for every finite, non-negative `k_rad_m`: it tends to `f_r` as k
    /// grows.
    pub fn freq_hz(&self, design: &Design, k_rad_m: f64) -> f64 {
        let params = Params::of(design);
        params.freq_hz(k_rad_m, self.rigidity_factor, self.rotary_inertia_kg_m2, self.resonance_hz)
    }

    /// The model's slow-branch wavenumber at `freq_hz`, rad/m: the root of the dispersion relation solved for
    /// `k^2` (a quadratic). `None` at or above the joint's resonance (the slow branch does not reach it) or for a
    /// frequency that is not finite and positive.
    pub fn wavenumber_rad_m(&self, design: &Design, freq_hz: f64) -> Option<f64> {
        if !(freq_hz.is_finite() && freq_hz > 0.0 && freq_hz < self.resonance_hz) {
            return None;
        }
        let p = Params::of(design);
        let w2 = (2.0 * PI * freq_hz).powi(2);
        let wr2 = (2.0 * PI * self.resonance_hz).powi(2);
        // s_D D q^2 - b q - w^2 rho_c = 0 in q = k^2, with b = w^2 J(w) / a^2 > 0 below resonance.
        let d = self.rigidity_factor * p.rigidity_n_m;
        let b = w2 * self.rotary_inertia_kg_m2 * wr2 / (wr2 - w2) / (p.lattice_m * p.lattice_m);
        let q = (b + (b * b + 4.0 * d * w2 * p.mass_per_area_kg_m2).sqrt()) / (2.0 * d);
        Some(q.sqrt())
    }
}

/// What the dispersion needs of the design.
struct Params {
    rigidity_n_m: f64,
    mass_per_area_kg_m2: f64,
    lattice_m: f64,
}

impl Params {
    fn of(design: &Design) -> Self {
        let a = design.lattice_constant_m;
        Self {
            rigidity_n_m: design.plate.flexural_rigidity_n_m(),
            mass_per_area_kg_m2: design.cell_mass_kg() / (a * a),
            lattice_m: a,
        }
    }

    /// The lower root of `rho_c s^2 - B s + C = 0` in `s = w^2`, written `2 C / (B + sqrt(B^2 - 4 rho_c C))` so
    /// that it keeps its digits when `C` is small against `B^2`.
    fn freq_hz(&self, k: f64, rigidity_factor: f64, inertia: f64, resonance_hz: f64) -> f64 {
        let wr2 = (2.0 * PI * resonance_hz).powi(2);
        let dk4 = rigidity_factor * self.rigidity_n_m * k.powi(4);
        let rho = self.mass_per_area_kg_m2;
        let b = rho * wr2 + inertia * wr2 * k * k / (self.lattice_m * self.lattice_m) + dk4;
        let c = dk4 * wr2;
        let disc = (b * b - 4.0 * rho * c).max(0.0);
        let denominator = b + disc.sqrt();
        if denominator > 0.0 { (2.0 * c / denominator).sqrt() / (2.0 * PI) } else { 0.0 }
    }
}

/// Fits the homogenised rocking rod to `design`'s first branch, given as its points `(|k| rad/m, frequency Hz)` at
/// any wave vectors (those with `0 < |k| a <= pi / 2` are used).
///
/// # Errors
/// [`DesignError::Option`] when the design has no rod, or fewer than 4 usable points are given (compute the band
/// with more wave vectors); [`DesignError::Fit`] when the fit does not give finite, positive parameters.
pub fn fit_rocking_rod(design: &Design, first_branch: &[(f64, f64)]) -> Result<RockingRodFit, DesignError> {
    let CellResonator::Rod(rod) = &design.resonator else {
        return Err(DesignError::Option("the homogenised rocking rod needs a rod resonator".into()));
    };
    let a = design.lattice_constant_m;
    let points: Vec<(f64, f64)> = first_branch
        .iter()
        .copied()
        .filter(|&(k, f)| k > 0.0 && k * a <= HOMOGENISED_MAX_KA * (1.0 + 1e-9) && f.is_finite() && f > 0.0)
        .collect();
    if points.len() < MIN_POINTS {
        return Err(DesignError::Option(format!(
            "the homogenised fit needs at least {MIN_POINTS} branch points with |k| a <= pi/2, got {} (use more wave \
             vectors)",
            points.len()
        )));
    }
    let params = Params::of(design);
    // Start: the bare plate, a rigid rod turning about its base, the joint at the clamped rod's first mode.
    let free = rod.free_length_m();
    let start = [1.0_f64.ln(), (rod.free_mass_kg() * free * free / 3.0).ln(), rod.clamped_resonance_hz().ln()];
    let residuals = |p: &[f64; 3]| -> Vec<f64> {
        points.iter().map(|&(k, f)| params.freq_hz(k, p[0].exp(), p[1].exp(), p[2].exp()) / f - 1.0).collect()
    };
    let cost = |r: &[f64]| r.iter().map(|e| e * e).sum::<f64>();
    let mut p = start;
    let mut r = residuals(&p);
    let mut lambda: f64 = 1e-3;
    for _ in 0..MAX_STEPS {
        let jacobian = jacobian(&residuals, &p);
        let n = points.len();
        // Damped Gauss-Newton as one least-squares problem: [J; sqrt(lambda) I] dp = [-r; 0].
        let a_mat = Mat::from_fn(n + 3, 3, |i, j| {
            if i < n {
                jacobian[i][j]
            } else if i - n == j {
                lambda.sqrt()
            } else {
                0.0
            }
        });
        let b_mat = Mat::from_fn(n + 3, 1, |i, _| if i < n { -r[i] } else { 0.0 });
        let step = a_mat.qr().solve_lstsq(&b_mat);
        let trial = [p[0] + step[(0, 0)], p[1] + step[(1, 0)], p[2] + step[(2, 0)]];
        let r_trial = residuals(&trial);
        if r_trial.iter().all(|e| e.is_finite()) && cost(&r_trial) < cost(&r) {
            let gain = cost(&r) - cost(&r_trial);
            p = trial;
            r = r_trial;
            lambda = (lambda / 3.0).max(1e-12);
            if gain <= 1e-16 * cost(&r).max(1e-30) {
                break;
            }
        } else {
            lambda *= 4.0;
            if lambda > 1e12 {
                break;
            }
        }
    }
    let [s_d, inertia, f_r] = p.map(f64::exp);
    if !([s_d, inertia, f_r].iter().all(|v| v.is_finite() && *v > 0.0) && r.iter().all(|e| e.is_finite())) {
        return Err(DesignError::Fit(format!(
            "parameters {s_d}, {inertia} kg m^2, {f_r} Hz are not finite and positive"
        )));
    }
    let freqs = points.iter().map(|&(_, f)| f);
    Ok(RockingRodFit {
        added_mass_ratio: params.mass_per_area_kg_m2 / design.plate.areal_density_kg_m2() - 1.0,
        rigidity_factor: s_d,
        rotary_inertia_kg_m2: inertia,
        resonance_hz: f_r,
        points: points.len(),
        min_freq_hz: freqs.clone().fold(f64::INFINITY, f64::min),
        max_freq_hz: freqs.fold(0.0, f64::max),
        max_relative_error: r.iter().fold(0.0, |m, e| m.max(e.abs())),
        rms_relative_error: (cost(&r) / r.len() as f64).sqrt(),
    })
}

/// Computes the first branch of `design`'s cell where the continuum holds (8 wave vectors along Gamma-X and 8 along
/// Gamma-M, `|k| a` from pi/16 to pi/2, the default mesh) and fits the homogenised rocking rod to it: what a plate
/// model built from a design uses, without the whole band diagram.
///
/// # Errors
/// As [`fit_rocking_rod`], and [`DesignError::Eigen`] when an eigenproblem fails.
pub fn homogenised_rocking_rod(design: &Design) -> Result<RockingRodFit, DesignError> {
    if !matches!(design.resonator, CellResonator::Rod(_)) {
        return Err(DesignError::Option("the homogenised rocking rod needs a rod resonator".into()));
    }
    let model = CellModel::new(design, MeshOptions::default());
    let reduction = Reduction::new(&model, Sides::Periodic)?;
    let k_max = HOMOGENISED_MAX_KA / design.lattice_constant_m;
    let (c, d) = (1.0, std::f64::consts::FRAC_1_SQRT_2);
    let wave_vectors: Vec<(f64, f64)> = [(c, 0.0), (d, d)]
        .iter()
        .flat_map(|&(cx, cy)| {
            (1..=POINTS_PER_DIRECTION).map(move |i| {
                let k = k_max * i as f64 / POINTS_PER_DIRECTION as f64;
                (k * cx, k * cy)
            })
        })
        .collect();
    let modes = reduction.solve_many(&model, &wave_vectors, 1, 0)?;
    let mut points = Vec::with_capacity(wave_vectors.len());
    for (&(kx, ky), at) in wave_vectors.iter().zip(&modes) {
        let mode = at
            .first()
            .ok_or_else(|| DesignError::Eigen { at: format!("k = ({kx:.3}, {ky:.3}) rad/m"), why: "no mode".into() })?;
        points.push((kx.hypot(ky), mode.freq_hz));
    }
    fit_rocking_rod(design, &points)
}

/// Central-difference Jacobian of `residuals` at `p` (log-parameters: a step of 1e-6 is a relative 1e-6).
fn jacobian(residuals: &dyn Fn(&[f64; 3]) -> Vec<f64>, p: &[f64; 3]) -> Vec<[f64; 3]> {
    const STEP: f64 = 1e-6;
    let mut columns = Vec::with_capacity(3);
    for j in 0..3 {
        let (mut up, mut down) = (*p, *p);
        up[j] += STEP;
        down[j] -= STEP;
        let (ru, rd) = (residuals(&up), residuals(&down));
        columns.push(ru.iter().zip(&rd).map(|(u, d)| (u - d) / (2.0 * STEP)).collect::<Vec<_>>());
    }
    (0..columns[0].len()).map(|i| [columns[0][i], columns[1][i], columns[2][i]]).collect()
}

//! The rod resonators, homogenised onto the lattice, one rod per lattice cell of the metamaterial.
//!
//! Each rod owns the plate area of its lattice cell (pitch a, centred on its site); every node in that area carries
//! the rod's share of mass in proportion to its own area. Two models:
//! - `AddedMass`: the rod is a mass `mu rho h a^2` on a spring to the plate, resonance `f_r`, loss `eta_r`: its
//!   dynamic mass is `m w_r^2 (1 + i eta_r) / (w_r^2 (1 + i eta_r) - w^2)` (the `mu w_r^2 / (w_r^2 - w^2)` of the
//!   local-resonance literature, with its own loss). Homogenised, the A0 dispersion becomes
//!   `D k^4 = rho h w^2 [1 + mu w_r^2 / (w_r^2 - w^2)]`.
//! - `RockingRod`: the rod moves with the plate (static mass `m`) and rocks with the plate's slope about its base,
//!   through a compliant joint resonating at `f_r`: rotary inertia `J = m r_g^2` per cell (`r_g` the radius of
//!   gyration about the base, `L / sqrt(3)` for a rigid rod unless the scene fits it), dynamic
//!   `J w_r^2 (1 + i eta_r) / (w_r^2 (1 + i eta_r) - w^2)`, entering as `-w^2 div(J grad w)` (a Laplacian-shaped
//!   mass matrix). It alone gives a slow, nearly non-dispersive wave `c = sqrt(D a^2 / J)`.
//!
//! Rod heights spread by the scene's `height_spread` (relative standard deviation, drawn from the seed): a rod of
//! relative height `s` has mass `s m`, length `s L`, radius of gyration `s r_g` and resonance `f_r / s^2` (a
//! cantilever's scaling).
//! Defaults when the scene gives no override: `mu` from the rod and plate densities, `f_r` the first mode of the rod
//! clamped at its base, `(1.875^2 / 2 pi) (d / 4) sqrt(E / rho) / L^2` (an upper bound: the real plate is compliant).
//!
//! A lattice that names a unit-cell design takes all of it from the cell instead: `metaplate-design`'s homogenised
//! rocking rod, fitted to the cell's band structure (its mass, the rod's rotary inertia and joint resonance, and the
//! footprints' stiffening of the plate, which [`Resonators::rigidity_factor_at`] gives the bending stiffness).

use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::Mutex;

use metaplate_core::design::{Design, cantilever_first_mode_hz};
use metaplate_design::RockingRodFit;

use metaplate_core::scene::{ResonatorModel, ResonatorSpec, Scene};
use num_complex::Complex64;

use crate::error::PlateError;
use crate::mesh::Mesh;
use crate::pattern::Pattern;
use metaplate_core::rng::SplitMix64;

/// Stream constant separating rod-height draws from the scene's other random draws.
const HEIGHT_STREAM: u64 = 0x726f_6473; // "rods"

/// The largest relative rod height drawn (the scene limits the spread below 0.5; clipping at 3 sigma keeps every
/// rod physical).
const MAX_SIGMAS: f64 = 3.0;

/// One rod: its squared resonance (rad^2/s^2) and loss factor.
#[derive(Debug, Clone, Copy)]
struct Rod {
    omega_r_sq: f64,
    loss_factor: f64,
}

/// The resonators' contributions to the system matrix.
#[derive(Debug, Clone, Default)]
pub(crate) struct Resonators {
    rods: Vec<Rod>,
    /// Resonant masses: (value position, rod, mass in kg).
    resonant_mass: Vec<(usize, usize, f64)>,
    /// Masses that follow the plate rigidly: (value position, mass in kg).
    static_mass: Vec<(usize, f64)>,
    /// Resonant rotary inertia (Laplacian-shaped): (value position, rod, coefficient in kg).
    resonant_inertia: Vec<(usize, usize, f64)>,
    /// Lattice constant, m, and the cells of the lattice's sites (keys of [`site_key`]).
    pitch_m: f64,
    sites: std::collections::HashSet<(i64, i64)>,
    /// Bending stiffness under the lattice over the bare plate's.
    rigidity_factor: f64,
}

/// The lattice cell (pitch `a_m`, a site at the origin) holding the point `(x_m, y_m)`.
fn site_key(x_m: f64, y_m: f64, a_m: f64) -> (i64, i64) {
    ((x_m / a_m).round() as i64, (y_m / a_m).round() as i64)
}

/// The rods as the plate model takes them, after a design's fit, overrides and defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RodParameters {
    /// Mass per cell that moves with the plate, over the plate's own `rho h a^2` (dimensionless).
    pub mass_ratio: f64,
    /// Resonance of a rod of the mean height, Hz.
    pub resonance_hz: f64,
    /// Rotary inertia of a rod of the mean height about its base, per cell, kg m^2 (`rocking_rod`).
    pub rotary_inertia_kg_m2: f64,
    /// Bending stiffness of the plate under the lattice over the bare plate's (1 unless a design's fit stiffens it).
    pub rigidity_factor: f64,
}

/// The rods' parameters of `scene`'s lattice: from its design's homogenised fit when it names one, else from the
/// rod and the scene's overrides.
///
/// # Errors
/// [`PlateError::InvalidParameter`] when a parameter is not finite and positive, or the design's fit fails.
pub fn effective_parameters(scene: &Scene) -> Result<RodParameters, PlateError> {
    let spec = &scene.resonators;
    let rho_h = scene.plate.mass_per_area_kg_m2();
    let parameters = match &spec.design {
        Some(design) => {
            let fit = design_fit(design)?;
            RodParameters {
                mass_ratio: fit.added_mass_ratio,
                resonance_hz: fit.resonance_hz,
                rotary_inertia_kg_m2: fit.rotary_inertia_kg_m2,
                rigidity_factor: fit.rigidity_factor,
            }
        }
        None => {
            let mass_ratio = match spec.mass_ratio {
                Some(mu) => mu,
                None => spec
                    .cell_mass_ratio(rho_h)
                    .map_err(|e| PlateError::invalid("resonators.mass_ratio", e.to_string()))?,
            };
            RodParameters {
                mass_ratio,
                resonance_hz: spec.resonance_hz.unwrap_or_else(|| clamped_rod_resonance_hz(spec)),
                rotary_inertia_kg_m2: mass_ratio * rho_h * spec.pitch_m.powi(2) * spec.gyration_radius_m().powi(2),
                rigidity_factor: 1.0,
            }
        }
    };
    let RodParameters { mass_ratio, resonance_hz, rotary_inertia_kg_m2, rigidity_factor } = parameters;
    if ![mass_ratio, resonance_hz, rotary_inertia_kg_m2, rigidity_factor].iter().all(|v| v.is_finite() && *v > 0.0) {
        return Err(PlateError::invalid(
            "resonators",
            format!(
                "mass ratio {mass_ratio}, resonance {resonance_hz} Hz, rotary inertia {rotary_inertia_kg_m2} kg m^2 \
                 and stiffness factor {rigidity_factor} must be finite and positive"
            ),
        ));
    }
    Ok(parameters)
}

/// Fits already made in this process: a plate model is built many times from one scene (the lab, its truth, the
/// error budget's variants), and a fit solves 16 eigenproblems.
static FITS: Mutex<Vec<(Design, RockingRodFit)>> = Mutex::new(Vec::new());

/// The homogenised rocking rod the plate model takes from `design` (computed once per design in a process).
///
/// # Errors
/// [`PlateError::InvalidParameter`] at `resonators.design` when the design has no rod or its fit fails.
pub fn design_fit(design: &Design) -> Result<RockingRodFit, PlateError> {
    // A poisoned memo only means another thread panicked mid-push: recompute rather than trust or fail.
    if let Ok(fits) = FITS.lock()
        && let Some((_, fit)) = fits.iter().find(|(d, _)| d == design)
    {
        return Ok(*fit);
    }
    let fit = metaplate_design::homogenised_rocking_rod(design)
        .map_err(|e| PlateError::invalid("resonators.design", format!("design `{}`: {e}", design.name)))?;
    if let Ok(mut fits) = FITS.lock() {
        fits.push((design.clone(), fit));
    }
    Ok(fit)
}

/// First bending mode of a rod clamped at its base and free at its tip, Hz.
fn clamped_rod_resonance_hz(spec: &ResonatorSpec) -> f64 {
    cantilever_first_mode_hz(spec.rod_diameter_m, spec.rod_youngs_modulus_pa, spec.rod_density_kg_m3, spec.rod_height_m)
}

impl Resonators {
    /// Builds the resonators of `scene` on `mesh` (empty for `ResonatorModel::None`).
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] when the resonator parameters are unusable.
    pub fn new(scene: &Scene, mesh: &Mesh, pattern: &Pattern) -> Result<Self, PlateError> {
        let spec = &scene.resonators;
        if spec.model == ResonatorModel::None {
            return Ok(Self::default());
        }
        let rods = effective_parameters(scene)?;
        let (mu, f_r) = (rods.mass_ratio, rods.resonance_hz);
        let sites = spec
            .lattice_sites_m(&scene.plate.outline)
            .map_err(|e| PlateError::invalid("resonators.pitch_m", e.to_string()))?;
        let a = spec.pitch_m;
        let site_key = |x: f64, y: f64| site_key(x, y, a);
        let mut rng = SplitMix64::new(scene.seed, HEIGHT_STREAM);
        let heights: Vec<f64> =
            sites.iter().map(|_| 1.0 + spec.height_spread * rng.normal().clamp(-MAX_SIGMAS, MAX_SIGMAS)).collect();
        let rod_list = heights
            .iter()
            .map(|s| Rod { omega_r_sq: (2.0 * PI * f_r / (s * s)).powi(2), loss_factor: spec.loss_factor })
            .collect();
        let rod_at: HashMap<(i64, i64), usize> =
            sites.iter().enumerate().map(|(k, &(x, y))| (site_key(x, y), k)).collect();
        let mass_per_area = mu * scene.plate.mass_per_area_kg_m2();
        let h2 = mesh.spacing_m * mesh.spacing_m;
        let mut out = Self {
            rods: rod_list,
            pitch_m: a,
            sites: rod_at.keys().copied().collect(),
            rigidity_factor: rods.rigidity_factor,
            ..Self::default()
        };
        for n in 0..mesh.len() {
            let (x, y) = mesh.position_m(n);
            let Some(&rod) = rod_at.get(&site_key(x, y)) else { continue };
            let pos = pattern.position(n, n).ok_or_else(|| PlateError::invalid("mesh", "missing diagonal"))?;
            let mass = heights[rod] * mass_per_area * h2 * mesh.cells_around(n) as f64 / 4.0;
            match spec.model {
                ResonatorModel::AddedMass => out.resonant_mass.push((pos, rod, mass)),
                _ => out.static_mass.push((pos, mass)),
            }
        }
        if spec.model == ResonatorModel::RockingRod {
            out.resonant_inertia = rotary_entries(mesh, pattern, &rod_at, &site_key, |rod| {
                // J / a^2 per unit area, and 1/2 per cell edge (each gradient component is averaged over two edges);
                // a rod s times as tall has s times the mass at s times the radius of gyration. Rods given key by
                // key keep the expression (and so the bits) of earlier versions.
                let s = heights[rod];
                match spec.design {
                    None => 0.5 * s * mass_per_area * (s * spec.gyration_radius_m()).powi(2),
                    Some(_) => 0.5 * s.powi(3) * rods.rotary_inertia_kg_m2 / (a * a),
                }
            })?;
        }
        Ok(out)
    }

    /// Adds `-w^2 M_rod(w)` to the system values at angular frequency `omega` (rad/s).
    pub fn add_to(&self, values: &mut [Complex64], omega: f64) {
        let w2 = omega * omega;
        let factor: Vec<Complex64> = self
            .rods
            .iter()
            .map(|r| {
                let k = Complex64::new(r.omega_r_sq, r.omega_r_sq * r.loss_factor);
                k / (k - w2)
            })
            .collect();
        for &(pos, rod, m) in &self.resonant_mass {
            values[pos] -= w2 * m * factor[rod];
        }
        for &(pos, m) in &self.static_mass {
            values[pos] -= w2 * m;
        }
        for &(pos, rod, c) in &self.resonant_inertia {
            values[pos] -= w2 * c * factor[rod];
        }
    }

    /// The bending stiffness at `(x_m, y_m)` over the bare plate's: the design's stiffening inside the lattice's
    /// cells, 1 elsewhere (and everywhere without rods).
    pub fn rigidity_factor_at(&self, x_m: f64, y_m: f64) -> f64 {
        if self.sites.contains(&site_key(x_m, y_m, self.pitch_m)) { self.rigidity_factor } else { 1.0 }
    }

    /// Smallest loss factor among the rods (`None` without rods): it bounds how slowly the coupled system rings.
    pub fn min_loss_factor(&self) -> Option<f64> {
        self.rods.iter().map(|r| r.loss_factor).reduce(f64::min)
    }

    /// Lowest rod resonance, Hz (`None` without rods).
    pub fn min_resonance_hz(&self) -> Option<f64> {
        self.rods.iter().map(|r| r.omega_r_sq.sqrt() / (2.0 * PI)).reduce(f64::min)
    }
}

/// Entries of `sum over plate cells of coef(rod) * sum over the cell's 4 edges (e e^T)`, `e = w[a] - w[b]`.
fn rotary_entries(
    mesh: &Mesh,
    pattern: &Pattern,
    rod_at: &HashMap<(i64, i64), usize>,
    site_key: &dyn Fn(f64, f64) -> (i64, i64),
    coef: impl Fn(usize) -> f64,
) -> Result<Vec<(usize, usize, f64)>, PlateError> {
    let missing = || PlateError::invalid("mesh", "an edge falls outside the sparsity pattern");
    let mut entries = Vec::new();
    for n in 0..mesh.len() {
        let (i, j) = (mesh.lattice_of[n].0 as isize, mesh.lattice_of[n].1 as isize);
        if !mesh.cell_full(i, j) {
            continue;
        }
        let (x, y) = mesh.position_m(n);
        let half = mesh.spacing_m / 2.0;
        let Some(&rod) = rod_at.get(&site_key(x + half, y + half)) else { continue };
        let c = coef(rod);
        let corner = |di, dj| mesh.node(i + di, j + dj).ok_or_else(missing);
        let (n00, n10, n01, n11) = (corner(0, 0)?, corner(1, 0)?, corner(0, 1)?, corner(1, 1)?);
        for (p, q) in [(n00, n10), (n01, n11), (n00, n01), (n10, n11)] {
            for (r, s, sign) in [(p, p, 1.0), (q, q, 1.0), (p, q, -1.0), (q, p, -1.0)] {
                entries.push((pattern.position(r, s).ok_or_else(missing)?, rod, sign * c));
            }
        }
    }
    Ok(entries)
}

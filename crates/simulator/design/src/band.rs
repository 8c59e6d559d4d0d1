//! The band diagram along Gamma-X-M-Gamma, each branch's phase velocity and wavelength, the slow branch, the clamped
//! cell's resonator mode, and the homogeneous plate's A0 folded into the same zone.

use std::f64::consts::PI;

use serde::Serialize;

use crate::bloch::{Mode, Reduction, Sides};
use crate::error::DesignError;
use crate::homogenise::{RockingRodFit, fit_rocking_rod};
use crate::mesh::MeshOptions;
use crate::model::CellModel;
use metaplate_core::design::{CellPlate, Design};

/// Options of a band computation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BandOptions {
    /// Wave vectors along Gamma-X-M-Gamma, both Gammas included (the paper: 90).
    pub wave_vectors: usize,
    /// Modes per wave vector (the paper's figure: 5).
    pub modes: usize,
    /// Mesh resolution.
    pub mesh: MeshOptions,
    /// Worker threads (0: as many as the machine has cores).
    pub threads: usize,
}

impl Default for BandOptions {
    fn default() -> Self {
        Self { wave_vectors: 90, modes: 10, mesh: MeshOptions::default(), threads: 0 }
    }
}

/// The frequencies at which the slow branch's wavelength is reported by default (the paper's: 75 Hz and the
/// branch's top, 558 Hz).
pub const PAPER_WAVELENGTH_FREQS_HZ: [f64; 2] = [75.0, 558.0];

/// One wave vector of the path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PathPoint {
    /// Index along the path, 0 (Gamma) to `wave_vectors - 1` (Gamma again).
    pub path_index: usize,
    /// Distance along the path in the reduced zone, 0 (Gamma) to 2 + sqrt(2) (back to Gamma), in units of pi/a.
    pub path_position: f64,
    /// Wave vector components, rad/m.
    pub kx_rad_m: f64,
    /// Wave vector components, rad/m.
    pub ky_rad_m: f64,
}

impl PathPoint {
    /// |k|, rad/m.
    pub fn k_rad_m(&self) -> f64 {
        self.kx_rad_m.hypot(self.ky_rad_m)
    }
}

/// The Gamma-X-M-Gamma path of a square lattice of constant `a_m`, `n` points spaced evenly by length (n >= 2).
pub fn gamma_x_m_path(a_m: f64, n: usize) -> Vec<PathPoint> {
    let total = 2.0 + 2f64.sqrt();
    let kmax = PI / a_m;
    (0..n)
        .map(|i| {
            // The last point is Gamma exactly (not a rounding error away from it).
            let s = if i + 1 == n { total } else { total * i as f64 / (n.max(2) - 1) as f64 };
            let (x, y) = if s <= 1.0 {
                (s, 0.0)
            } else if s <= 2.0 {
                (1.0, s - 1.0)
            } else {
                let t = if i + 1 == n { 0.0 } else { (1.0 - (s - 2.0) / 2f64.sqrt()).max(0.0) };
                (t, t)
            };
            PathPoint { path_index: i, path_position: s, kx_rad_m: x * kmax, ky_rad_m: y * kmax }
        })
        .collect()
}

/// One point of a branch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BranchPoint {
    /// Index along the path.
    pub path_index: usize,
    /// Wave vector, rad/m.
    pub kx_rad_m: f64,
    /// Wave vector, rad/m.
    pub ky_rad_m: f64,
    /// Eigenfrequency, Hz.
    pub freq_hz: f64,
    /// Phase velocity 2 pi f / |k|, m/s (absent at Gamma).
    pub phase_velocity_m_s: Option<f64>,
    /// Wavelength 2 pi / |k|, m (absent at Gamma).
    pub wavelength_m: Option<f64>,
    /// Share of the kinetic energy in the plate, 0 to 1 (the rest in the resonator).
    pub plate_energy_share: f64,
}

/// The `mode`-th lowest eigenfrequency at every wave vector of the path (m = 1 is the lowest).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Branch {
    /// Mode number m, from 1.
    pub mode: usize,
    /// Its points along the path.
    pub points: Vec<BranchPoint>,
}

/// A wavelength on the slow branch at a frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WavelengthAt {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Wavelength, m (absent when the branch does not reach the frequency).
    pub wavelength_m: Option<f64>,
}

/// The slow-wave branch: the lowest (m = 1).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlowBranch {
    /// Its mode number (1).
    pub mode: usize,
    /// Its highest frequency along the path, Hz.
    pub top_hz: f64,
    /// Its highest phase velocity along the path (Gamma left out), m/s.
    pub max_phase_velocity_m_s: f64,
    /// Wavelengths at the requested frequencies, from Gamma outwards along Gamma-X-M (the first crossing).
    pub wavelength_m_at: Vec<WavelengthAt>,
    /// The wavelength 2 pi / |k| where the branch tops out, m (the paper's 1.1 cm at 558 Hz, at M).
    pub top_wavelength_m: Option<f64>,
}

/// The cell's resonator mode with its sides fixed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClampedMode {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Its share of kinetic energy in the plate.
    pub plate_energy_share: f64,
}

/// A band diagram with everything derived from it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandDiagram {
    /// The design's name.
    pub design: String,
    /// Lattice constant, m.
    pub lattice_constant_m: f64,
    /// Resonator mass over cell plate mass.
    pub mass_ratio: f64,
    /// The path.
    pub path: Vec<PathPoint>,
    /// Branches m = 1, 2, ...
    pub branches: Vec<Branch>,
    /// The homogeneous plate's analytic A0 folded into the first zone: `a0_folded_hz[m - 1][path_index]`, Hz.
    pub a0_folded_hz: Vec<Vec<f64>>,
    /// The first resonator-associated mode of the clamped cell, Hz (absent without a resonator).
    pub resonator_mode_hz: Option<f64>,
    /// That mode in full.
    pub resonator_mode: Option<ClampedMode>,
    /// The slow branch (m = 1).
    pub slow_branch: SlowBranch,
    /// Reduced degrees of freedom of the Bloch problem (the model's size).
    pub degrees_of_freedom: usize,
    /// The homogenised rocking rod fitted to the slow branch (rod designs, with at least 4 path points at
    /// `|k| a <= pi / 2`).
    pub homogenised: Option<RockingRodFit>,
}

/// Computes the band diagram of `design`, with the slow branch's wavelength at `wavelength_freqs_hz`.
///
/// # Errors
/// [`DesignError::Option`] for fewer than 2 wave vectors or no mode; [`DesignError::Eigen`] when an eigenproblem
/// fails.
pub fn band_diagram(
    design: &Design,
    options: &BandOptions,
    wavelength_freqs_hz: &[f64],
) -> Result<BandDiagram, DesignError> {
    if options.wave_vectors < 2 || options.modes == 0 {
        return Err(DesignError::Option(format!(
            "need at least 2 wave vectors and 1 mode (got {} and {})",
            options.wave_vectors, options.modes
        )));
    }
    if options.mesh.per_side == 0 || options.mesh.radial == 0 || options.mesh.rod_elements == 0 {
        return Err(DesignError::Option("mesh sizes must be at least 1".into()));
    }
    let a = design.lattice_constant_m;
    let model = CellModel::new(design, options.mesh);
    let reduction = Reduction::new(&model, Sides::Periodic)?;
    let path = gamma_x_m_path(a, options.wave_vectors);
    let wave_vectors: Vec<(f64, f64)> = path.iter().map(|p| (p.kx_rad_m, p.ky_rad_m)).collect();
    let modes = reduction.solve_many(&model, &wave_vectors, options.modes, options.threads)?;
    let branches: Vec<Branch> = (0..options.modes.min(reduction.len()))
        .map(|j| Branch {
            mode: j + 1,
            points: path.iter().zip(&modes).map(|(p, at)| branch_point(p, at[j])).collect(),
        })
        .collect();
    let resonator_mode = clamped_resonator_mode(design, options.mesh)?;
    let slow_branch = slow_branch(&branches[0], wavelength_freqs_hz);
    // Too few points near Gamma (a coarse path) leaves the fit out rather than failing the diagram.
    let first: Vec<(f64, f64)> = branches[0].points.iter().map(|p| (p.kx_rad_m.hypot(p.ky_rad_m), p.freq_hz)).collect();
    let homogenised = match fit_rocking_rod(design, &first) {
        Ok(fit) => Some(fit),
        Err(DesignError::Option(_)) => None,
        Err(e) => return Err(e),
    };
    Ok(BandDiagram {
        design: design.name.clone(),
        lattice_constant_m: a,
        mass_ratio: design.mass_ratio(),
        a0_folded_hz: folded_a0(&design.plate, a, &path, options.modes),
        path,
        branches,
        resonator_mode_hz: resonator_mode.map(|m| m.freq_hz),
        resonator_mode,
        slow_branch,
        degrees_of_freedom: reduction.len(),
        homogenised,
    })
}

fn branch_point(p: &PathPoint, mode: Mode) -> BranchPoint {
    let k = p.k_rad_m();
    let (c, lambda) = if k > 0.0 { (Some(2.0 * PI * mode.freq_hz / k), Some(2.0 * PI / k)) } else { (None, None) };
    BranchPoint {
        path_index: p.path_index,
        kx_rad_m: p.kx_rad_m,
        ky_rad_m: p.ky_rad_m,
        freq_hz: mode.freq_hz,
        phase_velocity_m_s: c,
        wavelength_m: lambda,
        plate_energy_share: mode.plate_energy_share,
    }
}

/// The first resonator-associated mode of the cell with its sides fixed: the lowest mode with at least half of
/// its kinetic energy in the resonator; `None` without a resonator.
///
/// # Errors
/// [`DesignError::Eigen`] when the eigenproblem fails.
pub fn clamped_resonator_mode(design: &Design, mesh: MeshOptions) -> Result<Option<ClampedMode>, DesignError> {
    if design.resonator == metaplate_core::design::CellResonator::None {
        return Ok(None);
    }
    let model = CellModel::new(design, mesh);
    let reduction = Reduction::new(&model, Sides::Clamped)?;
    let modes = reduction.solve(&model, 0.0, 0.0, 12)?;
    Ok(modes
        .iter()
        .find(|m| m.plate_energy_share <= 0.5)
        .map(|m| ClampedMode { freq_hz: m.freq_hz, plate_energy_share: m.plate_energy_share }))
}

/// The slow branch's summary.
pub fn slow_branch(branch: &Branch, wavelength_freqs_hz: &[f64]) -> SlowBranch {
    let top_hz = branch.points.iter().map(|p| p.freq_hz).fold(0.0, f64::max);
    let max_phase_velocity_m_s = branch.points.iter().filter_map(|p| p.phase_velocity_m_s).fold(0.0, f64::max);
    let wavelength_m_at = wavelength_freqs_hz
        .iter()
        .map(|&f| WavelengthAt { freq_hz: f, wavelength_m: first_crossing_wavelength(branch, f) })
        .collect();
    let top_wavelength_m =
        branch.points.iter().max_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz)).and_then(|p| p.wavelength_m);
    SlowBranch { mode: branch.mode, top_hz, max_phase_velocity_m_s, wavelength_m_at, top_wavelength_m }
}

/// Wavelength where the branch first reaches `freq_hz` walking from Gamma, |k| interpolated linearly between the
/// two path points around the crossing; at the top itself (within 0.5 %) the top's wavelength.
fn first_crossing_wavelength(branch: &Branch, freq_hz: f64) -> Option<f64> {
    let k = |p: &BranchPoint| p.kx_rad_m.hypot(p.ky_rad_m);
    for pair in branch.points.windows(2) {
        let (p, q) = (&pair[0], &pair[1]);
        if p.freq_hz <= freq_hz && q.freq_hz >= freq_hz && q.freq_hz > p.freq_hz {
            let t = (freq_hz - p.freq_hz) / (q.freq_hz - p.freq_hz);
            let kk = k(p) + t * (k(q) - k(p));
            return (kk > 0.0).then(|| 2.0 * PI / kk);
        }
    }
    let top = branch.points.iter().max_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz))?;
    ((freq_hz - top.freq_hz).abs() <= 0.005 * top.freq_hz).then_some(top.wavelength_m).flatten()
}

/// The analytic A0 of the homogeneous plate folded into the first Brillouin zone: at each path point the lowest
/// `modes` of `f = sqrt(D / rho h) |k + G|^2 / (2 pi)` over reciprocal lattice vectors G, Hz.
pub fn folded_a0(plate: &CellPlate, a_m: f64, path: &[PathPoint], modes: usize) -> Vec<Vec<f64>> {
    let g = 2.0 * PI / a_m;
    // |G| up to a few zones more than the modes need (each zone adds about 4 folded branches).
    let reach = (modes as f64).sqrt().ceil() as i64 + 2;
    let per_point: Vec<Vec<f64>> = path
        .iter()
        .map(|p| {
            let mut f: Vec<f64> = (-reach..=reach)
                .flat_map(|i| (-reach..=reach).map(move |j| (i, j)))
                .map(|(i, j)| plate.a0_freq_hz((p.kx_rad_m + g * i as f64).hypot(p.ky_rad_m + g * j as f64)))
                .collect();
            f.sort_by(f64::total_cmp);
            f.truncate(modes);
            f
        })
        .collect();
    (0..modes).map(|m| per_point.iter().map(|f| f[m]).collect()).collect()
}

//! Boundary conditions on the cell and the eigenproblem of one wave vector.
//!
//! Floquet-Bloch: a node on the cell's right (top) side moves as its partner on the left (bottom) side times
//! `exp(i kx a)` (`exp(i ky a)`), so the free degrees of freedom `q` give all of them as `u = T(k) q`, and the
//! reduced problem `T^H K T q = omega^2 T^H M T q` is Hermitian. The mass is positive definite (every degree of
//! freedom carries mass or rotary inertia), so with `T^H M T = L L^H` it becomes the standard Hermitian problem
//! `L^-1 (T^H K T) L^-H y = omega^2 y`, solved densely (a few hundred unknowns).
//!
//! Clamped: the sides' degrees of freedom are zero (the cell's "fixed rather than periodic" resonator mode).

use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, Par, Side, c64};

use crate::error::DesignError;
use crate::model::{CellModel, Part, plate_dof};

/// Conditions on the cell's sides.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sides {
    /// Floquet-Bloch periodicity (the wave vector is given per solve).
    Periodic,
    /// Fixed (all degrees of freedom zero).
    Clamped,
}

/// One eigenmode's frequency and where its kinetic energy is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode {
    /// Eigenfrequency, Hz.
    pub freq_hz: f64,
    /// Share of the kinetic energy in the plate (footprint included), 0 to 1; the rest is the resonator's.
    pub plate_energy_share: f64,
}

/// The map from full degrees of freedom to the reduced (free) ones: `(reduced index, coefficient, shift)`, where
/// the shift indexes the phase `exp(i (kx sx + ky sy) a)` with `shift = sx + 2 sy`.
#[derive(Debug, Clone)]
pub struct Reduction {
    map: Vec<Vec<(usize, f64, u8)>>,
    n_reduced: usize,
    lattice_constant_m: f64,
}

impl Reduction {
    /// The reduction of `model` under `sides`.
    ///
    /// # Errors
    /// [`DesignError::Eigen`] when a side node has no partner (a mesh defect; never for the O-grid).
    pub fn new(model: &CellModel, sides: Sides) -> Result<Self, DesignError> {
        let n = model.n_full;
        let a = model.lattice_constant_m;
        let tol = 1e-9 * a;
        // Independent DOFs and, for each, its master and shift (itself and 0 unless a right or top side's node).
        let mut owner: Vec<Option<(usize, u8)>> = (0..n).map(|d| Some((d, 0))).collect();
        let mut constrained = vec![false; n];
        for (dof, _) in &model.constraints {
            constrained[*dof] = true;
        }
        let nodes = &model.mesh.nodes;
        for &node in &model.mesh.side_nodes {
            let [x, y] = nodes[node];
            match sides {
                Sides::Clamped => {
                    for c in 0..3 {
                        owner[plate_dof(node, c)] = None;
                    }
                }
                Sides::Periodic => {
                    let sx = u8::from((x - a / 2.0).abs() < tol);
                    let sy = u8::from((y - a / 2.0).abs() < tol);
                    if sx + sy == 0 {
                        continue;
                    }
                    let target = [x - f64::from(sx) * a, y - f64::from(sy) * a];
                    let partner = model
                        .mesh
                        .side_nodes
                        .iter()
                        .copied()
                        .find(|&p| (nodes[p][0] - target[0]).abs() < tol && (nodes[p][1] - target[1]).abs() < tol)
                        .ok_or_else(|| DesignError::Eigen {
                            at: "mesh".into(),
                            why: format!("side node at ({x}, {y}) m has no periodic partner"),
                        })?;
                    for c in 0..3 {
                        owner[plate_dof(node, c)] = Some((plate_dof(partner, c), sx + 2 * sy));
                    }
                }
            }
        }
        let mut reduced_index = vec![usize::MAX; n];
        let mut n_reduced = 0;
        for d in 0..n {
            if !constrained[d] && owner[d] == Some((d, 0)) {
                reduced_index[d] = n_reduced;
                n_reduced += 1;
            }
        }
        let direct = |d: usize| -> Vec<(usize, f64, u8)> {
            match owner[d] {
                Some((m, shift)) if reduced_index[m] != usize::MAX => vec![(reduced_index[m], 1.0, shift)],
                _ => Vec::new(),
            }
        };
        let mut map: Vec<Vec<(usize, f64, u8)>> = (0..n).map(direct).collect();
        for (dof, terms) in &model.constraints {
            // Masters of constraints are never on the sides: a direct lookup suffices.
            map[*dof] =
                terms.iter().flat_map(|&(m, c)| direct(m).into_iter().map(move |(r, c2, s)| (r, c * c2, s))).collect();
        }
        Ok(Self { map, n_reduced, lattice_constant_m: a })
    }

    /// Number of reduced degrees of freedom.
    pub fn len(&self) -> usize {
        self.n_reduced
    }

    /// Whether nothing is free.
    pub fn is_empty(&self) -> bool {
        self.n_reduced == 0
    }

    /// The reduced shifted stiffness `K + sigma M`, mass and resonator mass at wave vector (kx, ky), rad/m.
    fn assemble(&self, model: &CellModel, kx: f64, ky: f64, sigma: f64) -> [Mat<c64>; 3] {
        let a = self.lattice_constant_m;
        let phase = |sx: f64, sy: f64| {
            let t = (kx * sx + ky * sy) * a;
            c64::new(t.cos(), t.sin())
        };
        let phases = [phase(0.0, 0.0), phase(1.0, 0.0), phase(0.0, 1.0), phase(1.0, 1.0)];
        let n = self.n_reduced;
        let mut k = Mat::<c64>::zeros(n, n);
        let mut m = Mat::<c64>::zeros(n, n);
        let mut m_res = Mat::<c64>::zeros(n, n);
        for block in &model.blocks {
            let nd = block.dofs.len();
            for (p, &dp) in block.dofs.iter().enumerate() {
                for &(r, cp, sp) in &self.map[dp] {
                    let left = phases[usize::from(sp)].conj() * cp;
                    for (q, &dq) in block.dofs.iter().enumerate() {
                        let (kv, mv) = (block.k[p * nd + q] + sigma * block.m[p * nd + q], block.m[p * nd + q]);
                        if kv == 0.0 && mv == 0.0 {
                            continue;
                        }
                        for &(s, cq, sq) in &self.map[dq] {
                            let w = left * phases[usize::from(sq)] * cq;
                            k[(r, s)] += w * kv;
                            m[(r, s)] += w * mv;
                            if block.part == Part::Resonator {
                                m_res[(r, s)] += w * mv;
                            }
                        }
                    }
                }
            }
        }
        [k, m, m_res]
    }

    /// The lowest `n_modes` modes at each wave vector `(kx, ky)`, rad/m, spread over `threads` workers (0: as many
    /// as the machine has cores; each solve is independent).
    ///
    /// # Errors
    /// As [`Reduction::solve`], the first failing wave vector's.
    pub fn solve_many(
        &self,
        model: &CellModel,
        wave_vectors: &[(f64, f64)],
        n_modes: usize,
        threads: usize,
    ) -> Result<Vec<Vec<Mode>>, DesignError> {
        let threads = match threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        }
        .clamp(1, wave_vectors.len().max(1));
        let chunk = wave_vectors.len().div_ceil(threads).max(1);
        let results: Vec<Result<Vec<Vec<Mode>>, DesignError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = wave_vectors
                .chunks(chunk)
                .map(|ks| scope.spawn(move || ks.iter().map(|&(kx, ky)| self.solve(model, kx, ky, n_modes)).collect()))
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join().unwrap_or_else(|_| {
                        Err(DesignError::Eigen { at: "worker thread".into(), why: "panicked".into() })
                    })
                })
                .collect()
        });
        let mut all = Vec::with_capacity(wave_vectors.len());
        for r in results {
            all.extend(r?);
        }
        Ok(all)
    }

    /// The lowest `n_modes` modes at wave vector (kx, ky), rad/m (ignored when clamped: pass zeros).
    ///
    /// # Errors
    /// [`DesignError::Eigen`] when the shifted stiffness is not positive definite or the eigensolver fails.
    pub fn solve(&self, model: &CellModel, kx: f64, ky: f64, n_modes: usize) -> Result<Vec<Mode>, DesignError> {
        let fail = |why: String| DesignError::Eigen { at: format!("k = ({kx:.3}, {ky:.3}) rad/m"), why };
        let [k, m, m_res] = self.assemble(model, kx, ky, SHIFT_RAD2_S2);
        // Shift-invert: the lowest modes are the largest eigenvalues mu = 1 / (omega^2 + sigma) of
        // L^-1 M L^-H with K + sigma M = L L^H, so rounding (relative to the largest eigenvalue) spares them; the
        // plain reduction by the mass would lose them to the thickness-shear modes' 1e13 rad^2/s^2.
        let sigma = SHIFT_RAD2_S2;
        let llt = k.llt(Side::Lower).map_err(|e| fail(format!("shifted stiffness not positive definite: {e:?}")))?;
        let l = llt.L();
        // B = L^-1 M L^-H, as X = L^-1 M, then B = L^-1 X^H (B and M are Hermitian).
        let mut x = m.clone();
        solve_lower_triangular_in_place(l, x.as_mut(), Par::Seq);
        let mut b = x.adjoint().to_owned();
        solve_lower_triangular_in_place(l, b.as_mut(), Par::Seq);
        let evd = b.self_adjoint_eigen(Side::Lower).map_err(|e| fail(format!("eigensolver: {e:?}")))?;
        let n = self.n_reduced;
        let count = n_modes.min(n);
        // Largest mu last: the lowest modes are the last columns, in reverse.
        let mut vectors = Mat::<c64>::zeros(n, count);
        for j in 0..count {
            vectors.col_mut(j).copy_from(evd.U().col(n - 1 - j));
        }
        solve_upper_triangular_in_place(l.adjoint(), vectors.as_mut(), Par::Seq);
        let mu = evd.S().column_vector();
        let modes = (0..count)
            .map(|j| {
                let col = vectors.col(j);
                let total = (col.adjoint() * &m * col).re;
                let resonator = (col.adjoint() * &m_res * col).re;
                let omega2 = (1.0 / mu[n - 1 - j].re - sigma).max(0.0);
                Mode {
                    freq_hz: omega2.sqrt() / (2.0 * std::f64::consts::PI),
                    plate_energy_share: (1.0 - resonator / total).clamp(0.0, 1.0),
                }
            })
            .collect();
        Ok(modes)
    }
}

/// The shift sigma of shift-invert, rad^2/s^2: (2 pi 100 Hz)^2, below the bands of interest and far from zero, so
/// that K + sigma M is positive definite even with the rigid-body mode at Gamma.
const SHIFT_RAD2_S2: f64 = 4.0e5;

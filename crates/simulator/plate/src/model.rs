//! The discretised plate: matrices built once from a scene, solved per frequency.
//!
//! System at angular frequency w (time dependence `e^{i w t}`, the sign convention of a forward FFT):
//! `A(w) = K (1 + i eta) + K_s - w^2 [M + M_rod(w)]`, with `K` the bending stiffness ([`crate::bending`]), `eta` the
//! plate's loss factor, `K_s` the support pads (springs `k (1 + i eta_s)` shared equally by the nodes under each
//! pad), `M` the lumped plate mass and `M_rod(w)` the resonators ([`crate::resonators`]). `A` is complex symmetric;
//! each frequency is one sparse LU (fill-reducing ordering computed once) and one solve with a right-hand side per
//! actuator. Velocity per unit force is `i w A^{-1} f`.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{NumericLu, SymbolicLu, factorize_symbolic_lu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par};
use metaplate_core::scene::Scene;
use num_complex::Complex64;

use crate::bending;
use crate::error::PlateError;
use crate::mesh::Mesh;
use crate::pattern::Pattern;
use crate::resonators::Resonators;

/// How finely to discretise, and how many threads to use.
///
/// Valid range: `refinement` 1 to [`MAX_REFINEMENT`]; `threads` 1 to 64.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModelOptions {
    /// Lattice nodes per measurement-grid step: the lattice spacing is `grid.spacing_m / refinement`, so every grid
    /// point is a node. The default, 2, gives 2.5 mm on the paper's 5 mm grid: 8.4 nodes per wavelength at the
    /// metamaterial's shortest in the operating band (2.1 cm at 400 Hz), a discretisation error of 2.3 % in
    /// wavelength.
    pub refinement: usize,
    /// Worker threads for Green's functions (frequency bins are shared among them). Results do not depend on it.
    pub threads: usize,
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self { refinement: 2, threads: 2 }
    }
}

/// The largest [`ModelOptions::refinement`].
pub const MAX_REFINEMENT: usize = 16;

/// Interpolation weights `(node, weight)` of a point on the lattice.
type Weights = Vec<(usize, f64)>;

/// The plate of a scene, discretised and ready to solve.
#[derive(Debug)]
pub struct PlateModel {
    mesh: Mesh,
    pattern: Pattern,
    stiffness: Vec<f64>,
    plate_loss_factor: f64,
    /// Support springs: (value position, complex stiffness N/m).
    supports: Vec<(usize, Complex64)>,
    /// Lumped plate mass: (value position, kg).
    mass: Vec<(usize, f64)>,
    resonators: Resonators,
    /// Smallest loss factor of the plate and its pads.
    host_loss_factor: f64,
    actuators: Vec<Vec<(usize, f64)>>,
    /// Interpolation weights of each grid point (by flat index), or its position (m) when it is off the plate.
    /// Indices `0..grid_len` are the grid's points; `grid_len + k` is actuator k's driving point.
    points: Vec<Result<Weights, (f64, f64)>>,
    grid_len: usize,
    symbolic: SymbolicLu<usize>,
    scene_hash: u64,
    options: ModelOptions,
}

impl PlateModel {
    /// Discretises `scene` at `options.refinement` nodes per grid step.
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] for options out of range or an unusable scene (validate it first);
    /// [`PlateError::OffPlate`] when an actuator or support pad is not on the discretised plate;
    /// [`PlateError::TooLarge`] for a lattice beyond [`crate::MAX_LATTICE_POINTS`].
    pub fn from_scene(scene: &Scene, options: &ModelOptions) -> Result<Self, PlateError> {
        if !(1..=MAX_REFINEMENT).contains(&options.refinement) {
            return Err(PlateError::invalid(
                "refinement",
                format!("must be 1 to {MAX_REFINEMENT}, got {}", options.refinement),
            ));
        }
        if !(1..=64).contains(&options.threads) {
            return Err(PlateError::invalid("threads", format!("must be 1 to 64, got {}", options.threads)));
        }
        scene.validate().map_err(|e| PlateError::invalid("scene", e.to_string()))?;
        let plate = &scene.plate;
        let outline = plate.outline;
        let spacing_m = scene.grid.spacing_m / options.refinement as f64;
        let mesh = Mesh::new(
            &|x, y| outline.contains(x, y),
            outline.bounding_box_m(),
            spacing_m,
            (scene.grid.origin_x_m, scene.grid.origin_y_m),
        )?;
        let pattern = Pattern::new(&mesh);
        let resonators = Resonators::new(scene, &mesh, &pattern)?;
        let rigidity_at = |x, y| resonators.rigidity_factor_at(x, y);
        let stiffness =
            bending::stiffness(&mesh, &pattern, plate.bending_stiffness_n_m(), plate.poisson_ratio, &rigidity_at)
                .ok_or_else(|| PlateError::invalid("mesh", "a bending stencil falls outside the sparsity pattern"))?;
        let diag = |n: usize| pattern.position(n, n).ok_or_else(|| PlateError::invalid("mesh", "missing diagonal"));
        let mass = bending::lumped_mass(&mesh, plate.mass_per_area_kg_m2())
            .into_iter()
            .enumerate()
            .map(|(n, m)| Ok((diag(n)?, m)))
            .collect::<Result<Vec<_>, PlateError>>()?;
        let mut supports = Vec::new();
        for (k, s) in scene.supports.iter().enumerate() {
            let nodes: Vec<usize> = (0..mesh.len())
                .filter(|&n| {
                    let (x, y) = mesh.position_m(n);
                    s.covers(x, y)
                })
                .collect();
            // A pad smaller than a cell still holds the plate: it becomes a point spring at its centre.
            let weights = if nodes.is_empty() {
                mesh.interpolation(s.x_m, s.y_m).ok_or(PlateError::OffPlate {
                    what: "support",
                    index: k,
                    x_m: s.x_m,
                    y_m: s.y_m,
                })?
            } else {
                nodes.iter().map(|&n| (n, 1.0 / nodes.len() as f64)).collect()
            };
            let spring = Complex64::new(s.stiffness_n_per_m, s.stiffness_n_per_m * s.loss_factor);
            // Equal shares on distinct nodes (a Winkler pad) are diagonal; a point spring couples its corners.
            let point = nodes.is_empty();
            for &(a, wa) in &weights {
                for &(b, wb) in &weights {
                    if point || a == b {
                        let pos = pattern.position(a, b).ok_or_else(|| PlateError::invalid("mesh", "support"))?;
                        let share = if point { wa * wb } else { wa };
                        supports.push((pos, spring * share));
                    }
                }
            }
        }
        let host_loss_factor = scene.supports.iter().map(|s| s.loss_factor).fold(plate.loss_factor, f64::min);
        let actuators = scene
            .actuators
            .iter()
            .enumerate()
            .map(|(k, a)| {
                mesh.interpolation(a.x_m, a.y_m).ok_or(PlateError::OffPlate {
                    what: "actuator",
                    index: k,
                    x_m: a.x_m,
                    y_m: a.y_m,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let grid_len = scene.grid.len();
        let mut points: Vec<Result<Weights, (f64, f64)>> = (0..grid_len)
            .map(|i| {
                let (x, y) = scene.grid.position_m(i);
                outline
                    .contains(x, y)
                    .then(|| mesh.interpolation(x, y).or_else(|| nearest_node(&mesh, x, y)))
                    .flatten()
                    .ok_or((x, y))
            })
            .collect();
        // Driving points: index `grid_len + k` is actuator k's own position, where the calibration recipe puts the
        // beam (on the magnet), which is generally not a grid point.
        points.extend(actuators.iter().map(|w| Ok(w.clone())));
        let symbolic = factorize_symbolic_lu(symbolic_ref(&pattern), Default::default())
            .map_err(|e| PlateError::Solve { freq_hz: 0.0, reason: format!("symbolic analysis: {e:?}") })?;
        Ok(Self {
            mesh,
            pattern,
            stiffness,
            plate_loss_factor: plate.loss_factor,
            supports,
            mass,
            resonators,
            host_loss_factor,
            actuators,
            points,
            grid_len,
            symbolic,
            scene_hash: scene.physics_hash(),
            options: *options,
        })
    }

    /// Number of unknowns (lattice nodes on the plate).
    pub fn node_count(&self) -> usize {
        self.mesh.len()
    }

    /// Lattice spacing, m.
    pub fn spacing_m(&self) -> f64 {
        self.mesh.spacing_m
    }

    /// Number of actuators.
    pub fn actuator_count(&self) -> usize {
        self.actuators.len()
    }

    /// Number of grid points (all of them, on the plate or not). Point indices from `grid_len()` on address the
    /// actuators' driving points (see [`crate::GreensRequest::points`]).
    pub fn grid_len(&self) -> usize {
        self.grid_len
    }

    /// The smallest loss factor in the model (plate, pads, rods).
    pub fn min_loss_factor(&self) -> f64 {
        self.resonators.min_loss_factor().map_or(self.host_loss_factor, |r| r.min(self.host_loss_factor))
    }

    /// A lower bound on the loss factor of any mode of the model near `freq_hz` (Hz): a mode rings with an
    /// amplitude envelope no slower than `exp(-bound * pi f t)`.
    ///
    /// Why it holds: with hysteretic loss a mode's loss factor is the potential-energy-weighted mean of its parts'
    /// loss factors. Without rods every part (plate, pads) has at least the smallest of theirs. A rod driven at
    /// `x = f / f_r < 1` stores in its spring `x^2` times its kinetic energy, itself at most the mode's total, so the
    /// rods' share of the potential energy is at most `x^2` (taking the lowest rod resonance); above the resonance
    /// the share may reach 1. Hence `bound = eta_host - min(1, x^2) * max(0, eta_host - eta_rod)`.
    ///
    /// Valid range: finite `freq_hz >= 0`.
    pub fn loss_factor_bound(&self, freq_hz: f64) -> f64 {
        match (self.resonators.min_loss_factor(), self.resonators.min_resonance_hz()) {
            (Some(eta_rod), Some(f_r)) => {
                let share = (freq_hz / f_r).powi(2).min(1.0);
                self.host_loss_factor - share * (self.host_loss_factor - eta_rod).max(0.0)
            }
            _ => self.host_loss_factor,
        }
    }

    /// The options the model was built with.
    pub fn options(&self) -> &ModelOptions {
        &self.options
    }

    /// [`Scene::physics_hash`] of the scene the model was built from.
    pub fn scene_hash(&self) -> u64 {
        self.scene_hash
    }

    /// Plate normal velocity at grid `points` (flat grid indices, or `grid_len() + k` for actuator k's driving point) per unit force at `actuators` (indices into the
    /// scene's actuators), m/s/N, at `freq_hz`: `points.len() * actuators.len()` values, point-major
    /// (`[p * actuators.len() + a]`). One sparse LU and one solve per call: to sweep many frequencies use
    /// [`crate::greens_functions`], which shares the work across threads.
    ///
    /// Valid range: finite `0 < freq_hz <= 24000`. The result is accurate where the flexural wavelength spans at
    /// least about 10 lattice spacings ([`PlateModel::spacing_m`]); coarser, wavelengths come out short by about
    /// `(k h)^2 / 24`.
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] for a bad frequency or empty lists; [`PlateError::IndexOutOfRange`];
    /// [`PlateError::OffPlate`] for a grid point off the plate; [`PlateError::Solve`] if the system is singular;
    /// [`PlateError::NonFiniteResult`].
    pub fn frequency_response(
        &self,
        freq_hz: f64,
        actuators: &[usize],
        points: &[usize],
    ) -> Result<Vec<Complex64>, PlateError> {
        let (act, pts) = self.resolve(actuators, points)?;
        crate::error::check_range("freq_hz", freq_hz, f64::MIN_POSITIVE, 24_000.0)?;
        let mut ws = Workspace::new(self, actuators.len())?;
        let mut out = vec![Complex64::new(0.0, 0.0); points.len() * actuators.len()];
        let rhs: Vec<&[(usize, f64)]> = act.iter().map(|&a| self.actuators[a].as_slice()).collect();
        let columns: Vec<usize> = (0..act.len()).collect();
        ws.solve(self, freq_hz, &rhs, &columns, &pts, &mut out)?;
        Ok(out)
    }

    /// The interpolation weights of every actuator, in scene order: the right-hand sides of a Green's-function
    /// solve, which always solves for all of them (see [`crate::PlateModel::greens_functions`]).
    pub(crate) fn actuator_weights(&self) -> Vec<&[(usize, f64)]> {
        self.actuators.iter().map(Vec::as_slice).collect()
    }

    /// The interpolation weights of every point a request may address (grid points, then driving points), `None`
    /// for a grid point off the plate.
    pub(crate) fn point_weights(&self) -> Vec<Option<&[(usize, f64)]>> {
        self.points.iter().map(|p| p.as_ref().ok().map(Vec::as_slice)).collect()
    }

    /// Checks indices and returns the requested actuators (checked scene indices) and the interpolation weights of
    /// the requested points.
    #[allow(clippy::type_complexity)]
    pub(crate) fn resolve<'a>(
        &'a self,
        actuators: &[usize],
        points: &[usize],
    ) -> Result<(Vec<usize>, Vec<&'a [(usize, f64)]>), PlateError> {
        if actuators.is_empty() || points.is_empty() {
            return Err(PlateError::invalid("actuators/points", "need at least one actuator and one point"));
        }
        let act = actuators
            .iter()
            .map(|&a| {
                if a < self.actuators.len() {
                    Ok(a)
                } else {
                    Err(PlateError::IndexOutOfRange { what: "actuator", index: a, len: self.actuators.len() })
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let pts = points
            .iter()
            .map(|&p| match self.points.get(p) {
                None => Err(PlateError::IndexOutOfRange { what: "grid point", index: p, len: self.points.len() }),
                Some(Err((x_m, y_m))) => {
                    Err(PlateError::OffPlate { what: "grid point", index: p, x_m: *x_m, y_m: *y_m })
                }
                Some(Ok(w)) => Ok(w.as_slice()),
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((act, pts))
    }

    /// System values `A(w)` on the pattern.
    fn system_values(&self, omega: f64, values: &mut [Complex64]) {
        let k = Complex64::new(1.0, self.plate_loss_factor);
        for (v, &s) in values.iter_mut().zip(&self.stiffness) {
            *v = k * s;
        }
        for &(pos, s) in &self.supports {
            values[pos] += s;
        }
        let w2 = omega * omega;
        for &(pos, m) in &self.mass {
            values[pos] -= w2 * m;
        }
        self.resonators.add_to(values, omega);
    }
}

/// The nearest node within one lattice spacing of `(x_m, y_m)`, for grid points in a sliver of plate too thin to
/// hold a full cell (they take that node's displacement).
fn nearest_node(mesh: &Mesh, x_m: f64, y_m: f64) -> Option<Vec<(usize, f64)>> {
    let fx = ((x_m - mesh.origin_m.0) / mesh.spacing_m).round() as isize;
    let fy = ((y_m - mesh.origin_m.1) / mesh.spacing_m).round() as isize;
    let mut best: Option<(f64, usize)> = None;
    for dj in -1..=1 {
        for di in -1..=1 {
            if let Some(n) = mesh.node(fx + di, fy + dj) {
                let (nx, ny) = mesh.position_m(n);
                let d = (nx - x_m).hypot(ny - y_m);
                if d <= mesh.spacing_m * std::f64::consts::SQRT_2 && best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, n));
                }
            }
        }
    }
    best.map(|(_, n)| vec![(n, 1.0)])
}

fn symbolic_ref(pattern: &Pattern) -> SymbolicSparseColMatRef<'_, usize> {
    SymbolicSparseColMatRef::new_checked(pattern.dim(), pattern.dim(), &pattern.col_ptr, None, &pattern.row_idx)
}

/// Per-thread buffers for repeated solves: system values, numeric LU, scratch memory, right-hand sides.
pub(crate) struct Workspace {
    values: Vec<Complex64>,
    numeric: NumericLu<usize, Complex64>,
    mem: MemBuffer,
    rhs: Mat<Complex64>,
}

impl Workspace {
    /// Buffers for `model` with `n_rhs` right-hand sides.
    pub fn new(model: &PlateModel, n_rhs: usize) -> Result<Self, PlateError> {
        let req = StackReq::any_of(&[
            model.symbolic.factorize_numeric_lu_scratch::<Complex64>(Par::Seq, Default::default()),
            model.symbolic.solve_in_place_scratch::<Complex64>(n_rhs, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|_| PlateError::TooLarge {
            what: "LU workspace",
            needed: req.size_bytes(),
            max: isize::MAX as usize,
        })?;
        Ok(Self {
            values: vec![Complex64::new(0.0, 0.0); model.pattern.nnz()],
            numeric: NumericLu::new(),
            mem,
            rhs: Mat::zeros(model.mesh.len(), n_rhs),
        })
    }

    /// Velocity per unit force at `freq_hz` into `out` (`points.len() * columns.len()`, point-major): one solve
    /// with a right-hand side per entry of `rhs` (force weights; at most the workspace's `n_rhs`), read out at
    /// `points` for the right-hand sides `columns` (positions in `rhs`), in that order.
    pub fn solve(
        &mut self,
        model: &PlateModel,
        freq_hz: f64,
        rhs: &[&[(usize, f64)]],
        columns: &[usize],
        points: &[&[(usize, f64)]],
        out: &mut [Complex64],
    ) -> Result<(), PlateError> {
        let omega = 2.0 * std::f64::consts::PI * freq_hz;
        model.system_values(omega, &mut self.values);
        let a = SparseColMatRef::new(symbolic_ref(&model.pattern), &self.values);
        let stack = MemStack::new(&mut self.mem);
        let lu = model
            .symbolic
            .factorize_numeric_lu(&mut self.numeric, a, Par::Seq, stack, Default::default())
            .map_err(|e| PlateError::Solve { freq_hz, reason: format!("{e:?}") })?;
        self.rhs.fill(Complex64::new(0.0, 0.0));
        for (col, weights) in rhs.iter().enumerate() {
            for &(n, w) in weights.iter() {
                self.rhs[(n, col)] = Complex64::new(w, 0.0);
            }
        }
        lu.solve_in_place_with_conj(Conj::No, self.rhs.as_mut(), Par::Seq, MemStack::new(&mut self.mem));
        let i_omega = Complex64::new(0.0, omega);
        for (p, weights) in points.iter().enumerate() {
            for (c, &a) in columns.iter().enumerate() {
                let w: Complex64 = weights.iter().map(|&(n, c)| self.rhs[(n, a)] * c).sum();
                let v = i_omega * w;
                if !(v.re.is_finite() && v.im.is_finite()) {
                    return Err(PlateError::NonFiniteResult { what: "plate response" });
                }
                out[p * columns.len() + c] = v;
            }
        }
        Ok(())
    }
}

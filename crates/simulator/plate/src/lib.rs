//! Simulated plate for the metaplate mock lab: ground-truth Green's functions of a Kirchhoff plate with resonators.
//!
//! A scene ([`metaplate_core::scene::Scene`]) describes the plate (outline, material, loss), the foam pads it rests
//! on, the rod resonators and the actuators. [`PlateModel::from_scene`] discretises it: finite differences from the
//! discrete bending energy on a masked square lattice aligned with the measurement grid (free edges come out
//! naturally), pads as damped springs, rods homogenised as resonant added mass or rocking inertia
//! (`resonators` module docs). [`PlateModel::frequency_response`] solves one frequency (one sparse LU, a right-hand
//! side per actuator); [`greens_functions`] computes impulse responses for the requested band, points and actuators
//! on a frequency grid fine enough not to time-alias, across threads, cached on disk. [`actuator::VoiceCoil`] turns
//! drive signals into forces (suspension resonance, roll-off, unit spread, weak cubic nonlinearity).
//!
//! Units: SI throughout; a Green's function is plate normal velocity per unit actuator force, m/s/N. Every public
//! routine checks its input and returns a [`PlateError`], never a panic or a silent NaN.
//!
//! # The model
//!
//! - **Discretisation: finite differences from the discrete bending energy.** The plate's bending energy, summed
//!   only over cells fully on the plate, gives a symmetric positive semi-definite stiffness matrix whose free edges
//!   need no special treatment (there is simply no energy outside the plate) and whose rigid-body modes store no
//!   energy exactly. In the interior the operator is `D (5-point Laplacian)^2`, isotropic to leading order, with
//!   wavelengths short by `(k h)^2 / 24` (`bending` module docs). Finite elements would fit the curved stadium edge
//!   better, but the lattice is aligned with the measurement grid (every grid point is a node), assembles in a few
//!   lines, and is accurate where the recipes look (interior points).
//! - **Lattice spacing: 2.5 mm** ([`ModelOptions::refinement`] 2, the default, on the 5 mm measurement grid): about
//!   8.4 nodes per wavelength at the metamaterial's shortest wavelength in the operating band (2.1 cm at 400 Hz), a
//!   2.3 % wavelength error; 5259 nodes on the built-in plates.
//! - **Damping and supports:** structural damping `D (1 + i eta)`; the supports are springs `k (1 + i eta_s)` shared
//!   by the nodes under each pad; lumped mass.
//! - **Resonators, two homogenised models** (per rod cell, each with its own loss and a per-rod height spread drawn
//!   from the seed). `added_mass`: a mass on a spring, `mu omega_r^2 / (omega_r^2 - omega^2)`. `rocking_rod`: the
//!   rod moves with the plate and rocks with its slope, a rotary inertia `J = m r_g^2` entering as a
//!   Laplacian-shaped mass (the term `-omega^2 div(J grad w)`), resonant at the rod's clamped bending mode; or, when
//!   the lattice names a unit-cell design, with the mass, inertia, joint resonance and footprint stiffening of the
//!   cell's homogenised slow branch ([`design_fit`]). The built-in metamaterial names the design `paper`: the paper's
//!   mode shapes show "lateral resonator bending", and only rocking gives the slow branch that makes the pixels
//!   small. From its cell: 10.4 cm at 75 Hz (paper: 11.3), 3.8 and 2.1 cm at 250 and 400 Hz, and no slow wave
//!   above the branch's top, 552 Hz (the paper measured 2.5 cm at 600 Hz, above its own simulated branch).
//! - **Solver:** a sparse LU (faer) per frequency bin, with the fill-reducing ordering computed once on the one
//!   sparsity pattern every matrix shares; one solve per bin gives every actuator's field at every node; bins are
//!   shared among [`ModelOptions::threads`] threads, and the result does not depend on their number.
//! - **No time aliasing:** a mode at `f` rings as `exp(-eta pi f t)`; the FFT period `1 / delta_f` must hold
//!   [`ALIAS_DECAY_DB`] (60 dB) of decay of the slowest mode in band,
//!   `1 / delta_f >= ln(10^3) / (pi f eta_min(f))` ([`PlateModel::loss_factor_bound`]), and at least the requested
//!   duration plus a guard; responses are then cut to the duration with a 10 ms fade-out.
//! - **Actuators:** a Hammerstein voice coil ([`actuator::VoiceCoil`]): a static cubic, a gain with seeded
//!   unit-to-unit spread, a 2nd-order high-pass at the suspension resonance, a 1st-order low-pass roll-off.
//!
//! # The cache
//!
//! [`greens_functions`] with a cache directory keeps one entry per scene physics
//! ([`Scene::physics_hash`](metaplate_core::scene::Scene::physics_hash)), model options, band, duration and sample
//! rate, holding every grid point on the plate and every actuator; each request is cut from it, equal bit for bit
//! to computing it alone ([`cache_key`], [`cache_path`]). A file is written to a temporary name of its writer's
//! own, fsync'd and renamed, so concurrent writers are safe; a file that is not the expected entry, or is truncated
//! or damaged, is ignored and recomputed. On Linux an entry is computed once across processes: a
//! `<entry>.computing` claim holds the computing process's id, other requests wait on it, and it is taken over when
//! its process is gone. A scene whose entry would exceed [`MAX_GREENS_BYTES`] gets each request computed alone,
//! uncached. Without a cache directory nothing is written.
//!
//! # Convergence
//!
//! Under refinement (metamaterial, actuator 0, k-space median wavelength;
//! `cargo bench -p metaplate-plate --bench greens_bench -- convergence`; measured on the earlier added-mass scene,
//! not yet re-measured on the plate built from the design `paper`):
//!
//! | lattice h | 75 Hz | 300 Hz | 600 Hz |
//! |---|---|---|---|
//! | 5 mm | 107.7 mm | 52.2 mm | 23.7 mm |
//! | 2.5 mm (default) | 107.7 mm | 52.8 mm | 24.7 mm |
//! | 1.67 mm | 108.7 mm | 52.7 mm | 24.9 mm |
//! | 1.25 mm | 108.7 mm | 52.8 mm | 24.9 mm |

pub mod actuator;
mod bending;
mod cache;
mod entry;
mod entry_file;
pub mod error;
mod greens;
mod mesh;
mod model;
mod pattern;
mod resonators;

pub use cache::{
    CACHE_DIR_ENV, EntrySettings, cache_key, cache_path, default_cache_dir, greens_functions, greens_functions_within,
};
pub use error::PlateError;
pub use greens::{ALIAS_DECAY_DB, GreensFunctions, GreensRequest, MAX_GREENS_BYTES, MAX_IR_SAMPLES, SpectralPlan};
pub use mesh::MAX_LATTICE_POINTS;
pub use model::{MAX_REFINEMENT, ModelOptions, PlateModel};
pub use resonators::{RodParameters, design_fit, effective_parameters};

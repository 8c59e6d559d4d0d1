//! Metamaterial unit-cell design: the Bloch band structure of a square cell of plate holding a resonator (a rod
//! press-fit through it, or a spring-mass), computed by finite elements, as the paper's Fig. 2 does with COMSOL.
//!
//! - [`Design`]: the cell (plate, resonator, lattice constant), from a TOML design file or built in (`paper`).
//! - [`band_diagram`]: eigenfrequencies along Gamma-X-M-Gamma, each branch's phase velocity `2 pi f / |k|` and
//!   wavelength `2 pi / |k|`, each mode's share of kinetic energy in the plate, the slow branch (m = 1: its top,
//!   highest phase velocity, wavelengths), the clamped cell's resonator mode, and the analytic A0 folded in.
//! - [`fit_rocking_rod`]: the homogenised plate model (mass, stiffening, the rod's rocking inertia and joint
//!   resonance) whose dispersion follows the slow branch where the lattice is fine against the wavelength.
//!
//! # Method
//! Mindlin plate elements (9-node quadrilaterals on an O-grid around the rod's footprint), the footprint rigid,
//! the rod as Timoshenko beams in both bending planes attached to the footprint's rotation (it rocks), Floquet-Bloch
//! conditions on the sides by a complex phase reduction, and a dense Hermitian eigenproblem per wave vector. The
//! choices and their validation: docs/design.md.

mod band;
mod bloch;
mod elements;
mod error;
mod homogenise;
mod mesh;
mod model;
mod parquet;
mod report;
pub mod search;

pub use band::{
    BandDiagram, BandOptions, Branch, BranchPoint, ClampedMode, PAPER_WAVELENGTH_FREQS_HZ, PathPoint, SlowBranch,
    WavelengthAt, band_diagram, clamped_resonator_mode, folded_a0, gamma_x_m_path,
};
pub use bloch::{Mode, Reduction, Sides};
pub use error::DesignError;
pub use homogenise::{HOMOGENISED_MAX_KA, RockingRodFit, fit_rocking_rod, homogenised_rocking_rod};
pub use mesh::{Mesh, MeshOptions};
pub use model::CellModel;
pub use parquet::write_parquet;

//! Simulated plate for the metaplate mock lab: ground-truth Green's functions of a Kirchhoff plate with resonators.
//!
//! A scene ([`metaplate_core::scene::Scene`]) describes the plate (outline, material, loss), the foam pads it rests
//! on, the rod resonators and the actuators. [`PlateModel::from_scene`] discretises it: finite differences from the
//! discrete bending energy on a masked square lattice aligned with the measurement grid (free edges come out
//! naturally), pads as damped springs, rods homogenised as resonant added mass or rocking inertia
//! (`resonators` module docs). [`PlateModel::frequency_response`] solves one frequency (one sparse LU, a right-hand
//! side per actuator); [`greens_functions`] computes impulse responses for the requested band, points and actuators
//! on a frequency grid fine enough not to time-alias, across threads, cached on disk: one entry per scene physics,
//! model options, band, duration and sample rate holds every point and actuator, and every request is cut from it.
//! [`actuator::VoiceCoil`] turns drive signals into forces (suspension resonance, roll-off, unit spread, weak cubic
//! nonlinearity).
//!
//! Units: SI throughout; a Green's function is plate normal velocity per unit actuator force, m/s/N. Every public
//! routine checks its input and returns a [`PlateError`], never a panic or a silent NaN.

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

pub use cache::{cache_key, cache_path, greens_functions};
pub use error::PlateError;
pub use greens::{ALIAS_DECAY_DB, GreensFunctions, GreensRequest, MAX_GREENS_BYTES, MAX_IR_SAMPLES, SpectralPlan};
pub use mesh::MAX_LATTICE_POINTS;
pub use model::{MAX_REFINEMENT, ModelOptions, PlateModel};
pub use resonators::effective_parameters;

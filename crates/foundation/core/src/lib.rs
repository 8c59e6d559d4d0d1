//! Shared domain types of metaplate.
//!
//! Measurement grids ([`grid`]) and scenes ([`scene`]: one TOML file describing a whole simulated lab); the
//! capability traits recipes see (`Vibrometer`, `Daq`, `AudioOut`, `Clock`). It depends on nothing
//! else in the workspace, and everything else may depend on it.

pub mod audio;
pub mod clock;
pub mod daq;
pub mod grid;
pub mod hash;
pub mod rig;
pub mod rng;
pub mod scene;
pub mod toml_locate;
pub mod vibrometer;

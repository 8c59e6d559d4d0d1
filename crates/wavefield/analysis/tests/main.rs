//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod analyses;
mod common;
mod dispersion;
mod extremes;
mod local_wavelength;
mod paper_table;
mod pixel_area;
mod wavelength;
mod wavelength_lattice;
mod wavelength_proptest;

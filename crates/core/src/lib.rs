//! Shared domain types of metaplate.
//!
//! This crate grows with the suite: measurement grids now; scenes, configuration and the capability traits
//! (`Vibrometer`, `Daq`, `AudioOut`, `Clock`) as the mock-hardware and driver layers arrive. It depends on nothing
//! else in the workspace, and everything else may depend on it.

pub mod grid;

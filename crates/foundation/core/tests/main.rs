//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod design;
mod error_chain;
mod grid;
mod scene;
mod scene_fuzz;
mod units;

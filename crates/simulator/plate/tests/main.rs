//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod cache_dir;
mod common;
mod dispersion;
mod greens;
mod physics;

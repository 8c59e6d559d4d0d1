//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod from_dataset;
mod multi_pixel;
mod solve_extremes;
mod units;

//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod faults;
mod galvo;
mod hardware_file;
mod units;
mod zaber;

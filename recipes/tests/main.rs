//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod calibrate_mock;
mod common;
mod corruption;
mod engine;
mod error_estimate;
mod faults;
mod preflight;
mod resume;
mod scan_mock;
mod scan_protocols;

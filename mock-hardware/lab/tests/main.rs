//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod chain;
mod common;
mod faults;
mod serve;
mod switches;
mod windowed_truth;

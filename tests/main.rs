//! End-to-end tests of the `metaplate` binary and of workflows across crates: one test binary, a module per
//! command or workflow. Declared as the `e2e` test of `crates/cli` (its `Cargo.toml`), so that Cargo builds the
//! binary these tests run (`CARGO_BIN_EXE_metaplate`): a separate package cannot ask for another's binary.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod aim;
mod analyze;
mod browser;
mod budget;
mod check;
mod commands;
mod common;
mod crash;
mod demo;
mod design;
mod experiment;
mod experiment_run;
mod focus;
mod monitor;
mod play;
mod recipes;
mod replay;
mod report;
mod standin;
mod tradeoff;
mod uff;

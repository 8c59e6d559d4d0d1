//! The aiming backends' tests, one module per topic.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod galvo_aimer;
mod galvo_file;
mod galvo_fit;
mod galvo_teach;

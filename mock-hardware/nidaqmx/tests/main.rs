//! The stand-in's behaviour in Rust (what the exported C functions do), one binary; the C path itself is tested
//! through the NI-DAQmx backend in `metaplate-daq`'s tests.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod lab;
mod model;

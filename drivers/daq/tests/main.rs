//! The crate's integration tests, one binary: each file a module.

#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

mod acquisition;
mod common;
mod exchange;
mod faults;
#[cfg(feature = "nidaqmx")]
mod nidaqmx;
#[cfg(feature = "usb")]
mod real_device;
mod units;

//! The tests of each module of `src/`, one file per module: outside the library so that a test build
//! compiles the library once (a unit-test harness compiles it a second time, in test mode).

mod checksum;
mod config;

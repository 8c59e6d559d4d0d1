//! The tests of each module of `src/`, one file per module: outside the library so that a test build
//! compiles the library once (a unit-test harness compiles it a second time, in test mode).

mod aim;
mod audio;
mod clock;
mod daq;
mod grid;
mod hash;
mod points;
mod rig;
mod rng;
mod scene_outline;
mod scene_setup;
mod toml_locate;
mod vibrometer;

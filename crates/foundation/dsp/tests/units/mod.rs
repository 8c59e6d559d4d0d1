//! The tests of each module of `src/`, one file per module: outside the library so that a test build
//! compiles the library once (a unit-test harness compiles it a second time, in test mode).

mod accuracy;
mod average;
mod band;
mod conv;
mod deconv;
mod drift;
mod equalise;
mod excitation;
mod fft;
mod impulse;
mod lstsq;
mod noise;
mod pipeline;
mod resample;
mod smooth;
mod stats;
mod sweep;
mod window;

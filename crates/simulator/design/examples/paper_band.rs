//! The paper's band diagram once (90 wave vectors, 10 modes, the default mesh), timed: run under
//! `/usr/bin/time -v` for its peak memory (docs/benchmarks.md).
//!
//! `cargo run --release -p metaplate-design --example paper_band`

#![allow(clippy::expect_used)] // An example: a failure is reported by the panic.

use metaplate_core::design::Design;
use metaplate_design::{BandOptions, PAPER_WAVELENGTH_FREQS_HZ, band_diagram};

fn main() {
    let start = std::time::Instant::now();
    let band = band_diagram(&Design::paper(), &BandOptions::default(), &PAPER_WAVELENGTH_FREQS_HZ).expect("band");
    println!(
        "{} DOFs, {} wave vectors x {} modes in {:.2} s; f_n {:.1} Hz, top {:.1} Hz",
        band.degrees_of_freedom,
        band.path.len(),
        band.branches.len(),
        start.elapsed().as_secs_f64(),
        band.resonator_mode_hz.unwrap_or(0.0),
        band.slow_branch.top_hz
    );
}

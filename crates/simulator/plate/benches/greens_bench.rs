//! Benchmark of the Green's-function computation (run in release; not a timed test):
//!
//! `cargo bench -p metaplate-plate --bench greens_bench -- [full|scaling|convergence]`
//!
//! - `full`: the figure: all measured points x 8 actuators, 0.5 s at 24 kHz, band 50 to 700 Hz, built-in
//!   metamaterial scene, 2 threads. Measure memory with `/usr/bin/time -v` (maximum resident set size).
//! - `scaling`: how the cost grows with band, lattice spacing and number of points (each run times one knob).
//! - `convergence`: responses and k-space wavelengths against lattice spacing (the table for ARCHITECTURE.md).

#![allow(clippy::expect_used)] // A benchmark binary: a panic with its message is the report.

use std::time::Instant;

use metaplate_analysis::wavelength::{KSpaceOptions, estimate_wavelength};
use metaplate_core::scene::Scene;
use metaplate_plate::{GreensRequest, ModelOptions, PlateModel, SpectralPlan};
use num_complex::Complex64;

fn run(scene: &Scene, refinement: usize, points: Vec<usize>, band_hz: (f64, f64)) {
    let request =
        GreensRequest { points, actuators: (0..8).collect(), band_hz, duration_s: 0.5, sample_rate_hz: 24_000.0 };
    let t = Instant::now();
    let model = PlateModel::from_scene(scene, &ModelOptions { refinement, threads: 2 }).expect("model");
    let build = t.elapsed();
    let plan = SpectralPlan::new(&request, &|f| model.loss_factor_bound(f)).expect("plan");
    let t = Instant::now();
    let g = model.greens_functions(&request).expect("greens");
    println!(
        "{:>5} points, h = {:.2} mm ({} nodes), band {:?} Hz: {} bins, FFT {}: build {:.2} s, Green's functions {:.1} s \
         ({:.1} ms per bin), {} MB out",
        request.points.len(),
        model.spacing_m() * 1e3,
        model.node_count(),
        band_hz,
        plan.bins.len(),
        plan.fft_len,
        build.as_secs_f64(),
        t.elapsed().as_secs_f64(),
        t.elapsed().as_secs_f64() * 1e3 / plan.bins.len() as f64,
        g.data.len() * 8 / 1_000_000,
    );
}

fn main() {
    // `cargo bench` passes `--bench`: not one of ours.
    let what = std::env::args().skip(1).find(|a| a != "--bench").unwrap_or_else(|| "full".into());
    let scene = Scene::builtin("metamaterial").expect("scene");
    let all = scene.measured_points();
    match what.as_str() {
        "full" => run(&scene, 2, all, (50.0, 700.0)),
        "scaling" => {
            for band in [(50.0, 200.0), (50.0, 400.0), (50.0, 700.0), (100.0, 700.0), (200.0, 700.0)] {
                run(&scene, 2, all[..64].to_vec(), band);
            }
            for refinement in [1, 2, 3, 4] {
                run(&scene, refinement, all[..64].to_vec(), (200.0, 700.0));
            }
            for n in [16, 256, all.len()] {
                run(&scene, 2, all[..n].to_vec(), (200.0, 700.0));
            }
        }
        "convergence" => {
            let pts: Vec<usize> = [(10, 12), (24, 12), (40, 6)].iter().map(|&(i, j)| scene.grid.index(i, j)).collect();
            let mask = scene.grid_mask();
            for refinement in [1, 2, 3, 4] {
                let model = PlateModel::from_scene(&scene, &ModelOptions { refinement, threads: 1 }).expect("model");
                let mut line = format!("h = {:.3} mm:", model.spacing_m() * 1e3);
                for f in [75.0, 300.0, 600.0] {
                    let r = model.frequency_response(f, &[0], &pts).expect("response");
                    let field_r = model.frequency_response(f, &[0], &scene.measured_points()).expect("field");
                    let mut field = vec![Complex64::new(0.0, 0.0); scene.grid.len()];
                    for (k, &p) in scene.measured_points().iter().enumerate() {
                        field[p] = field_r[k];
                    }
                    let g = &scene.grid;
                    let e = estimate_wavelength(&field, &mask, g.nx, g.ny, g.spacing_m, &KSpaceOptions::default())
                        .expect("wavelength");
                    line += &format!(
                        "  {f} Hz: |v/F| at 3 points {:.4} {:.4} {:.4} m/s/N, lambda {:.2} mm;",
                        r[0].norm(),
                        r[1].norm(),
                        r[2].norm(),
                        e.median_m * 1e3
                    );
                }
                println!("{line}");
            }
        }
        other => eprintln!("unknown mode {other}: full, scaling or convergence"),
    }
}

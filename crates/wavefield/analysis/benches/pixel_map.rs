//! The full pixel-area map (focal fields for every measured point, then every half-maximum area) on the
//! metamaterial plate's ground truth, and its scaling with points and band; plus the single-pixel focal-field GEMM
//! alone. `cargo bench -p metaplate-analysis --bench pixel_map`.
//!
//! With `PIXEL_MAP_EXPORT=FILE` set, also writes the propagation matrices and target gains for the NumPy
//! implementation (`pixel_map_numpy.py`): a little-endian header of u64 (bins, points, actuators, fft_len), f64
//! sample rate, then `bins` f64 gains, then complex128 `G`, bin-major, each bin's matrix column-major (the layout
//! of `PropagationMatrices`), then the Rust map's peaks (f64 per point) and areas (f64 per point, NaN when flagged).

#![allow(clippy::unwrap_used, missing_docs)] // a benchmark harness: failures are failures, no public API

use criterion::{Criterion, criterion_group, criterion_main};
use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_control::focal::single_pixel_focal_fields;
use metaplate_core::scene::Scene;
use metaplate_ground_truth::{GroundTruth, GroundTruthOptions};

/// The metamaterial plate's compensated ground truth over `band_hz`, from the tests' cache (target/tmp).
fn ground_truth(band_hz: (f64, f64)) -> (Scene, PropagationMatrices) {
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../target/tmp/greens-cache");
    let truth = GroundTruth::builtin("metamaterial", &GroundTruthOptions::default(), Some(&cache)).unwrap();
    let g = truth.propagation(band_hz).unwrap();
    (truth.scene, g)
}

fn export(path: &str, g: &PropagationMatrices, scene: &Scene) {
    let options = PixelAreaOptions::default();
    let map = pixel_area_map(g, &scene.grid, &scene.grid_mask(), &options).unwrap();
    let gains = options.target_band.gains(g).unwrap();
    let mut bytes = Vec::new();
    for v in [g.n_bins(), g.n_points(), g.n_actuators(), g.fft_len()] {
        bytes.extend((v as u64).to_le_bytes());
    }
    bytes.extend(g.sample_rate_hz().to_le_bytes());
    bytes.extend(gains.iter().flat_map(|v| v.to_le_bytes()));
    for k in 0..g.n_bins() {
        let gk = g.at_bin(k).unwrap();
        for n in 0..g.n_actuators() {
            for m in 0..g.n_points() {
                bytes.extend(gk[(m, n)].re.to_le_bytes());
                bytes.extend(gk[(m, n)].im.to_le_bytes());
            }
        }
    }
    bytes.extend(map.peak.iter().flat_map(|v| v.to_le_bytes()));
    bytes.extend(map.area_cm2.iter().flat_map(|a| a.unwrap_or(f64::NAN).to_le_bytes()));
    std::fs::write(path, bytes).unwrap();
    eprintln!("exported G ({} bins x {} points x {} actuators) to {path}", g.n_bins(), g.n_points(), g.n_actuators());
}

fn bench(c: &mut Criterion) {
    let (scene, full) = ground_truth((75.0, 400.0));
    if let Ok(path) = std::env::var("PIXEL_MAP_EXPORT") {
        export(&path, &full, &scene);
    }
    let (_, half_band) = ground_truth((75.0, 237.5));
    let mask = scene.grid_mask();
    let options = PixelAreaOptions::default();
    let mut group = c.benchmark_group("pixel_map");
    group.sample_size(10);
    let m = full.n_points();
    for (label, g) in [("full band", &full), ("half band", &half_band)] {
        for points in [m / 4, m / 2, m] {
            // An evenly spread subset, so the fields and areas stay those of a plate-wide map.
            let rows: Vec<usize> = (0..points).map(|i| i * m / points).collect();
            let sub = g.select_rows(&rows).unwrap();
            let name = format!("{label}, {points} points, {} bins", sub.n_bins());
            group.bench_function(format!("map: {name}"), |b| {
                b.iter(|| pixel_area_map(&sub, &scene.grid, &mask, &options).unwrap());
            });
            if points == m {
                let gains = options.target_band.gains(&sub).unwrap();
                let targets: Vec<usize> = (0..points).collect();
                group.bench_function(format!("focal GEMM only: {name}"), |b| {
                    b.iter(|| {
                        single_pixel_focal_fields(&sub, &targets, &gains, options.regularisation, options.method, 2)
                            .unwrap()
                    });
                });
            }
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

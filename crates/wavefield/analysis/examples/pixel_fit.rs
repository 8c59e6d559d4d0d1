//! Fits a scene's resonator parameters against the paper: prints the k-space (and plate-equation) median wavelength
//! at 75 / 150 / 250 / 400 / 600 Hz and the median virtual-pixel area of the ground truth (8 actuators, compensated
//! as in tests/pixel_area.rs and uncompensated, on the full grid and on every other point as the demo scans), for a
//! built-in scene or a scene file:
//! `cargo run --release -p metaplate-analysis --example pixel_fit -- SCENE [SCENE...]`
//! (environment: `NO_AREA=1` for the wavelengths only).
#![allow(clippy::unwrap_used)] // a report on fixed inputs: a failure is a bug to see at once

use metaplate_analysis::dispersion::{DispersionOptions, SceneLayout, wavelengths_at};
use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_control::solve::Method;
use metaplate_core::scene::Scene;
use metaplate_ground_truth::{GroundTruth, GroundTruthOptions};
use metaplate_plate::{ModelOptions, PlateModel};

const FREQS_HZ: [f64; 5] = [75.0, 150.0, 250.0, 400.0, 600.0];

fn wavelengths(scene: &Scene) {
    let model = PlateModel::from_scene(scene, &ModelOptions::default()).unwrap();
    let layout = SceneLayout::new(scene);
    let actuators: Vec<usize> = (0..scene.actuators.len()).collect();
    for f in FREQS_HZ {
        let response = model.frequency_response(f, &actuators, &layout.points).unwrap();
        let w = wavelengths_at(&response, actuators.len(), &layout.layout(), &DispersionOptions::default()).unwrap();
        let a0 = scene.plate.a0_wavelength_m(f).unwrap();
        let k = w.k_space_summary.median_m;
        let local = w.local_summary.map_or(f64::NAN, |s| s.wavelength_m);
        println!(
            "  {f:>5} Hz: k-space {:6.2} cm, plate-equation {:6.2} cm, A0 / k-space {:4.2}, c {:5.1} m/s",
            k * 100.0,
            local * 100.0,
            a0 / k,
            f * k
        );
    }
}

fn pixel_areas(scene: &Scene) {
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../target/tmp/greens-cache");
    let compensated = GroundTruthOptions::default();
    let uncompensated = GroundTruthOptions { compensation: None, ..GroundTruthOptions::default() };
    for (label, options) in [("compensated", compensated), ("uncompensated", uncompensated)] {
        let started = std::time::Instant::now();
        let truth = GroundTruth::new(scene.clone(), &options, Some(&cache)).unwrap();
        let g = truth.propagation((75.0, 400.0)).unwrap();
        // The demo's default scan grid: every other point of each row and column.
        let grid = scene.grid;
        let rows: Vec<usize> = (0..g.n_points())
            .filter(|&r| {
                let p = g.points()[r] as usize;
                (p % grid.nx).is_multiple_of(2) && (p / grid.nx).is_multiple_of(2)
            })
            .collect();
        let coarse = g.select_rows(&rows).unwrap();
        for (grid_label, g) in [("full grid", &g), ("every other point", &coarse)] {
            let options = PixelAreaOptions::default();
            let map = pixel_area_map(g, &scene.grid, &scene.grid_mask(), &options).unwrap();
            let tr = PixelAreaOptions { method: Method::TimeReversal, ..options };
            let tr_map = pixel_area_map(g, &scene.grid, &scene.grid_mask(), &tr).unwrap();
            println!(
                "  {label}, {grid_label}: pixel area median {:.2} cm^2 ({:.0} % flagged), time reversal {:.2} cm^2 \
                 ({:.1} s)",
                map.median_area_cm2().unwrap_or(f64::NAN),
                100.0 * map.flagged_fraction(),
                tr_map.median_area_cm2().unwrap_or(f64::NAN),
                started.elapsed().as_secs_f64()
            );
        }
    }
}

fn main() {
    for name in std::env::args().skip(1) {
        let scene = Scene::resolve(&name).unwrap();
        println!("{name} (hash {:016x})", scene.content_hash());
        wavelengths(&scene);
        if std::env::var("NO_AREA").is_err() {
            pixel_areas(&scene);
        }
    }
}

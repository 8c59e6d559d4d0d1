//! Virtual-pixel area on the ground truth of both built-in plates (DESIGN.md section 6: median 2.74 cm^2 on the
//! metamaterial plate, about 10 x larger on the homogeneous one), plus the map's edge rules on synthetic fields.
//!
//! Ground truth: the plate model's Green's functions at every measured point, 8 actuators, 0.5 s at 2 kHz (the
//! focusing band 75 to 400 Hz is far below 1 kHz), cached under the test target directory, as in paper_table.rs
//! (same request, so one cache serves both).

#![allow(clippy::unwrap_used)] // tests may unwrap

use metaplate_analysis::pixel::{PixelAreaOptions, PixelOutcome, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_control::solve::Method;
use metaplate_core::scene::Scene;
use metaplate_plate::{GreensRequest, ModelOptions, greens_functions};

fn ground_truth(name: &str) -> (Scene, PropagationMatrices) {
    let scene = Scene::builtin(name).unwrap();
    let request = GreensRequest {
        points: scene.measured_points(),
        actuators: (0..scene.actuators.len()).collect(),
        band_hz: (40.0, 700.0),
        duration_s: 0.5,
        sample_rate_hz: 2000.0,
    };
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&cache).unwrap();
    let greens = greens_functions(&scene, &ModelOptions::default(), &request, Some(&cache)).unwrap();
    let g = PropagationMatrices::from_impulse_responses(
        greens.points.iter().map(|&p| p as u32).collect(),
        greens.actuators.iter().map(|&a| a as u16).collect(),
        greens.sample_rate_hz,
        (75.0, 400.0),
        |m, n| greens.ir(m, n),
    )
    .unwrap();
    (scene, g)
}

/// Median of the areas of some pixels, cm^2 (diagnostics).
fn median<'a>(pixels: impl Iterator<Item = (&'a Option<f64>, &'a PixelOutcome)>) -> Option<f64> {
    let mut a: Vec<f64> = pixels.filter_map(|(a, _)| *a).collect();
    a.sort_unstable_by(f64::total_cmp);
    (!a.is_empty()).then(|| a[a.len() / 2])
}

#[test]
#[ignore = "known failure, issue 6: the metamaterial gives 7.3 cm^2 against the paper's 2.74 (bound 1.37 to 5.48). Its \
            added-mass rods, fitted to the measured 11.3 cm at 75 Hz and 2.5 cm at 600 Hz, leave mid-band waves long \
            (5.9 cm at 250 Hz). Rod loss leaves the area alone (7.35 at eta_r 0.1); rocking rods with the rods' own \
            inertia (the paper's lateral bending) give 1.9 cm^2 but 1.8 cm at 600 Hz (plate equation; k-space breaks \
            down) against the measured 2.5 (examples/pixel_fit.rs). Run with --ignored."]
fn metamaterial_pixels_are_small_and_homogeneous_ones_large() {
    let options = PixelAreaOptions::default();
    let (meta_scene, meta_g) = ground_truth("metamaterial");
    let meta = pixel_area_map(&meta_g, &meta_scene.grid, &meta_scene.grid_mask(), &options).unwrap();
    let (homo_scene, homo_g) = ground_truth("homogeneous");
    let homo = pixel_area_map(&homo_g, &homo_scene.grid, &homo_scene.grid_mask(), &options).unwrap();
    let meta_median = meta.median_area_cm2().unwrap();
    // Diagnostic only (not asserted): the half maximum of the intensity v^2 instead of the velocity v.
    let intensity = PixelAreaOptions { threshold: std::f64::consts::FRAC_1_SQRT_2, ..options };
    for (name, scene, g) in [("metamaterial", &meta_scene, &meta_g), ("homogeneous", &homo_scene, &homo_g)] {
        let map = pixel_area_map(g, &scene.grid, &scene.grid_mask(), &intensity).unwrap();
        eprintln!(
            "{name}: intensity half-maximum median {:?} cm^2, {:.0} % flagged",
            map.median_area_cm2(),
            100.0 * map.flagged_fraction()
        );
    }
    let homo_median = homo.median_area_cm2().unwrap();
    for (name, map) in [("metamaterial", &meta), ("homogeneous", &homo)] {
        eprintln!(
            "{name}: median {:.2} cm^2 over {} points: {} closed, {} closed at a support, {} reach the edge, {} no \
             focus; median of the closed-only {:?} cm^2",
            map.median_area_cm2().unwrap(),
            map.points.len(),
            map.count(PixelOutcome::Closed),
            map.count(PixelOutcome::ClosedAtSupport),
            map.count(PixelOutcome::ReachesEdge),
            map.count(PixelOutcome::NoFocus),
            median(map.area_cm2.iter().zip(&map.outcome).filter(|(_, o)| **o == PixelOutcome::Closed)),
        );
    }
    // The paper's 2.74 cm^2 comes from a real plate; a simulated one must agree in order of magnitude: factor 2.
    assert!((2.74 / 2.0..=2.74 * 2.0).contains(&meta_median), "metamaterial median {meta_median} cm^2");
    // "About 10 x larger" on the homogeneous plate: at least 5 x leaves room for the simulation's differences. A
    // homogeneous pixel that touches the edge is not counted, which only lowers its median, so this is conservative.
    assert!(homo_median >= 5.0 * meta_median, "homogeneous {homo_median} vs metamaterial {meta_median} cm^2");
    // Most metamaterial pixels must close inside the plate (the paper maps the whole display).
    assert!(meta.flagged_fraction() < 0.5, "{:.2} of metamaterial pixels flagged", meta.flagged_fraction());
    // Time reversal gives similar areas on the metamaterial plate (paper, Fig. S5): within a factor 2.
    let tr = PixelAreaOptions { method: Method::TimeReversal, ..options };
    let tr_median =
        pixel_area_map(&meta_g, &meta_scene.grid, &meta_scene.grid_mask(), &tr).unwrap().median_area_cm2().unwrap();
    eprintln!("time reversal: metamaterial median {tr_median:.2} cm^2");
    assert!(tr_median / meta_median < 2.0 && meta_median / tr_median < 2.0, "time reversal {tr_median} cm^2");
}

//! Virtual-pixel area on the ground truth of both built-in plates (DESIGN.md section 6: median 2.74 cm^2 on the
//! metamaterial plate, about 10 x larger on the homogeneous one), plus the map's edge rules on synthetic fields.
//!
//! Ground truth: `metaplate_ground_truth` (the plate model's Green's functions at every measured point through the
//! voice coils, each actuator compensated as the calibration recipe does, 0.5 s at 2 kHz), cached under the test
//! target directory (one cache for every test binary).

#![allow(clippy::unwrap_used)] // tests may unwrap

use metaplate_analysis::pixel::{PixelAreaOptions, PixelOutcome, pixel_area_map};
use metaplate_control::PropagationMatrices;
use metaplate_control::solve::Method;
use metaplate_core::scene::Scene;
use metaplate_ground_truth::{GroundTruth, GroundTruthOptions};

fn cache() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache")
}

/// The compensated ground truth (as the paper measured) over the operating band.
fn ground_truth(name: &str) -> (Scene, PropagationMatrices) {
    let truth = GroundTruth::builtin(name, &GroundTruthOptions::default(), Some(&cache())).unwrap();
    let g = truth.propagation((75.0, 400.0)).unwrap();
    (truth.scene, g)
}

/// Median of the areas of some pixels, cm^2 (diagnostics).
fn median<'a>(pixels: impl Iterator<Item = (&'a Option<f64>, &'a PixelOutcome)>) -> Option<f64> {
    let mut a: Vec<f64> = pixels.filter_map(|(a, _)| *a).collect();
    a.sort_unstable_by(f64::total_cmp);
    (!a.is_empty()).then(|| a[a.len() / 2])
}

#[test]
// Measured on the compensated ground truth: metamaterial 2.53 cm^2 (45 % flagged: pixels reaching the edge),
// homogeneous 36.8 cm^2 (14.6 x), time reversal 4.99 cm^2 (1.97 x the inverse filter's). The metamaterial is the
// plate built from the paper's cell, fitted to nothing the paper measured: 8 % under the paper's 2.74 cm^2.
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
    // Time reversal gives similar areas on the metamaterial plate (paper, Fig. S5): within a factor 2 (1.97
    // measured; why it is not "slightly larger" here: the next test).
    let tr = PixelAreaOptions { method: Method::TimeReversal, ..options };
    let tr_median =
        pixel_area_map(&meta_g, &meta_scene.grid, &meta_scene.grid_mask(), &tr).unwrap().median_area_cm2().unwrap();
    eprintln!("time reversal: metamaterial median {tr_median:.2} cm^2");
    assert!(tr_median / meta_median < 2.0 && meta_median / tr_median < 2.0, "time reversal {tr_median} cm^2");
}

/// What compensation changes, and the band: inverse filtering solves per bin, so a per-actuator gain (the
/// compensation) only rescales its solution and leaves the field alone; time reversal weighs each bin by |G|^2, so
/// without compensation the strong low frequencies dominate and its pixels grow. The paper's time-reversal pixels
/// are "on average slightly larger" than the inverse filter's (Fig. S5): here 1.97 x compensated, 3.67 x without.
#[test]
fn compensation_matters_to_time_reversal_only_and_the_map_uses_the_operating_band() {
    let truth = GroundTruth::builtin("metamaterial", &GroundTruthOptions::default(), Some(&cache())).unwrap();
    let raw_options = GroundTruthOptions { compensation: None, ..GroundTruthOptions::default() };
    let raw = GroundTruth::builtin("metamaterial", &raw_options, Some(&cache())).unwrap();
    let (grid, mask) = (truth.scene.grid, truth.scene.grid_mask());
    let inverse = PixelAreaOptions::default();
    let reversal = PixelAreaOptions { method: Method::TimeReversal, ..inverse };
    let median = |g: &PropagationMatrices, options: &PixelAreaOptions| {
        pixel_area_map(g, &grid, &mask, options).unwrap().median_area_cm2().unwrap()
    };
    let g = truth.propagation((75.0, 400.0)).unwrap();
    let g_raw = raw.propagation((75.0, 400.0)).unwrap();
    let (inv, inv_raw) = (median(&g, &inverse), median(&g_raw, &inverse));
    let (tr, tr_raw) = (median(&g, &reversal), median(&g_raw, &reversal));
    eprintln!("inverse filter {inv:.2} cm^2 ({inv_raw:.2} uncompensated), time reversal {tr:.2} ({tr_raw:.2})");
    // Only the regularisation (relative to sigma_max per bin) sees the per-actuator gains: within 5 %.
    assert!((inv / inv_raw - 1.0).abs() < 0.05, "inverse filter {inv} vs {inv_raw} uncompensated");
    // Larger than the inverse filter's when compensated but within 2 x, and without compensation larger again by
    // more than 1.5 x: the strong low frequencies then set the pixel. (On the plate built from the paper's cell,
    // time reversal's compensated pixels are about twice the inverse filter's, not "slightly larger": its waves
    // shorten 4.5-fold over the band, so the |G|^2 weight on the strong low bins likely counts for more;
    // docs/results-paper.md.)
    assert!((1.0..2.0).contains(&(tr / inv)), "time reversal {tr} vs inverse filter {inv}");
    assert!(
        (tr_raw / inv_raw) / (tr / inv) > 1.5,
        "uncompensated time reversal {tr_raw} vs {inv_raw}, compensated {tr}"
    );
    // A dataset loaded over a wider band (as `metaplate analyze` loads 50 to 625 Hz) is cut to the operating band:
    // the same map, area for area.
    let wide = truth.propagation((50.0, 625.0)).unwrap();
    let from_wide = pixel_area_map(&wide, &grid, &mask, &inverse).unwrap();
    let from_band = pixel_area_map(&g, &grid, &mask, &inverse).unwrap();
    assert_eq!(from_wide.area_cm2, from_band.area_cm2);
}

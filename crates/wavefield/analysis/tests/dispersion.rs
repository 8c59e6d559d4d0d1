//! One frequency of a propagation response through both estimators (`metaplate_analysis::dispersion`).
#![allow(clippy::unwrap_used)] // tests may unwrap

use crate::common;

use common::*;
use metaplate_analysis::AnalysisError;
use metaplate_analysis::dispersion::{
    ACTUATOR_EXCLUSION_M, DispersionOptions, FieldLayout, SceneLayout, actuator_field, wavelengths_at,
};
use metaplate_analysis::wavelength::{KSpaceOptions, LocalOptions, estimate_local_wavelength, estimate_wavelength};
use metaplate_core::scene::Scene;
use num_complex::Complex64;

/// A point-major response (`[k * actuators + a]`) over the stadium's points from one field per actuator.
fn response(fields: &[Vec<Complex64>], points: &[usize]) -> Vec<Complex64> {
    points.iter().flat_map(|&p| fields.iter().map(move |f| f[p])).collect()
}

fn measured_points() -> Vec<usize> {
    stadium_mask().iter().enumerate().filter_map(|(i, &m)| m.then_some(i)).collect()
}

#[test]
fn each_actuator_is_measured_by_both_estimators() {
    let (mask, g, points) = (stadium_mask(), grid(), measured_points());
    let fields: Vec<Vec<Complex64>> = (0..5).map(|seed| standing_mixture(0.10, 24, seed)).collect();
    let r = response(&fields, &points);
    let layout = FieldLayout { grid: &g, points: &points, mask: &mask, local_mask: &mask, exclusions: &[] };
    let w = wavelengths_at(&r, fields.len(), &layout, &DispersionOptions::default()).unwrap();
    assert_eq!((w.k_space.len(), w.local.len()), (5, 5));
    for (a, field) in fields.iter().enumerate() {
        // The assembled field is the original on the measured points (zero elsewhere), so each estimate is the one
        // made on the original: identical, not merely close.
        let masked: Vec<Complex64> =
            field.iter().zip(&mask).map(|(v, &m)| if m { *v } else { Complex64::ZERO }).collect();
        assert_eq!(actuator_field(&r, 5, a, &points, NX * NY).unwrap(), masked);
        let k = estimate_wavelength(field, &mask, NX, NY, SPACING_M, &KSpaceOptions::default()).unwrap();
        assert_eq!(w.k_space[a], k);
        let local = estimate_local_wavelength(field, &mask, &g, &[], &LocalOptions::default()).unwrap();
        assert_eq!(w.local[a], Ok(local));
    }
    // Median of five: the third of the sorted per-actuator values, exactly.
    let mut sorted: Vec<f64> = w.local.iter().map(|e| e.as_ref().unwrap().wavelength_m).collect();
    sorted.sort_by(f64::total_cmp);
    let s = w.local_summary.unwrap();
    assert_eq!(s.wavelength_m, sorted[2]);
    assert_eq!((s.range_m, s.actuators, s.flagged), ((sorted[0], sorted[4]), 5, 0));
    // 10 cm: the direction bound of the plate-equation estimator, 0.11 % (tests/local_wavelength.rs).
    assert!((s.wavelength_m / 0.10 - 1.0).abs() < 0.0011, "{s:?}");
    assert_eq!(w.k_space_summary.actuators, 5);
}

#[test]
fn an_actuator_without_a_plate_wave_is_reported_not_fatal() {
    // Actuator 1's field is a tilt (no bilaplacian): the k-space estimator still finds a peak, the plate equation
    // finds no wave; the summary combines the other two.
    let (mask, g, points) = (stadium_mask(), grid(), measured_points());
    let tilt: Vec<Complex64> = (0..NX * NY).map(|i| Complex64::new(xy_m(i).0, 0.0)).collect();
    let fields = vec![plane_wave(0.05, 0.2), tilt, plane_wave(0.05, 1.0)];
    let layout = FieldLayout { grid: &g, points: &points, mask: &mask, local_mask: &mask, exclusions: &[] };
    let w = wavelengths_at(&response(&fields, &points), 3, &layout, &DispersionOptions::default()).unwrap();
    assert!(matches!(w.local[1], Err(AnalysisError::NotAPlateWave { .. })));
    assert_eq!(w.local_summary.unwrap().actuators, 2);
    // Every actuator failing: no plate-equation summary, the k-space results all the same.
    let tilt = fields[1].clone();
    let w =
        wavelengths_at(&response(&[tilt.clone(), tilt], &points), 2, &layout, &DispersionOptions::default()).unwrap();
    assert!(w.local_summary.is_none() && w.local.iter().all(Result::is_err));
    assert_eq!(w.k_space_summary.actuators, 2);
    // A constant field has no k-space energy once its mean is removed: that is an error of the call.
    let flat = vec![Complex64::new(1.0, 0.0); NX * NY];
    let w = wavelengths_at(&response(&[flat.clone(), flat], &points), 2, &layout, &DispersionOptions::default());
    assert!(matches!(w, Err(AnalysisError::NoEnergy { .. })), "{w:?}");
}

#[test]
fn refuses_inconsistent_shapes() {
    let (mask, g, points) = (stadium_mask(), grid(), measured_points());
    let layout = FieldLayout { grid: &g, points: &points, mask: &mask, local_mask: &mask, exclusions: &[] };
    let opts = DispersionOptions::default();
    let r = response(&[plane_wave(0.05, 0.0), plane_wave(0.05, 1.0)], &points);
    assert!(matches!(wavelengths_at(&r, 0, &layout, &opts), Err(AnalysisError::InvalidParameter { .. })));
    assert!(matches!(wavelengths_at(&r, 3, &layout, &opts), Err(AnalysisError::LengthMismatch { .. })));
    assert!(matches!(wavelengths_at(&r[1..], 2, &layout, &opts), Err(AnalysisError::LengthMismatch { .. })));
    let short = FieldLayout { local_mask: &mask[1..], ..layout };
    assert!(matches!(wavelengths_at(&r, 2, &short, &opts), Err(AnalysisError::LengthMismatch { .. })));
    let mut off = points.clone();
    off[0] = NX * NY;
    let off_grid = FieldLayout { points: &off, ..layout };
    assert!(matches!(wavelengths_at(&r, 2, &off_grid, &opts), Err(AnalysisError::InvalidParameter { .. })));
    assert!(matches!(actuator_field(&r, 2, 2, &points, NX * NY), Err(AnalysisError::InvalidParameter { .. })));
    // A NaN in the response reaches the estimators, which refuse it.
    let mut bad = r.clone();
    bad[7] = Complex64::new(f64::NAN, 0.0);
    assert!(matches!(wavelengths_at(&bad, 2, &layout, &opts), Err(AnalysisError::NonFinite { .. })));
}

#[test]
fn scene_layout_of_the_lab_plate() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let layout = SceneLayout::new(&scene);
    // The figure: 1065 of the 1225 grid points are measured.
    assert_eq!(layout.points.len(), 1065);
    assert_eq!(layout.points, scene.measured_points());
    assert_eq!(layout.mask, scene.grid_mask());
    // The local mask only removes points, and only those within half a step of the outline.
    for (i, (&m, &l)) in layout.mask.iter().zip(&layout.local_mask).enumerate() {
        assert!(!l || m);
        if m && !l {
            let (x, y) = scene.grid.position_m(i);
            assert!(scene.plate.outline.distance_inside_m(x, y) < 0.5 * scene.grid.spacing_m);
        }
    }
    assert_eq!(layout.exclusions.len(), scene.actuators.len() + scene.supports.len());
    assert!(layout.exclusions[..scene.actuators.len()].iter().all(|e| e.radius_m == ACTUATOR_EXCLUSION_M));
    // A pad's circle holds its square: half-diagonal of 18 mm.
    assert!((layout.exclusions[scene.actuators.len()].radius_m - 0.018 / 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn a_regular_subset_is_measured_on_its_own_lattice() {
    // Every second point of the stadium (1 cm): on the full 5 mm grid the holes between would put images of a 6 cm
    // wave at high wavenumbers; on the subset's lattice the estimate is that of the full grid within 5 %.
    let (mask, g) = (stadium_mask(), grid());
    let points: Vec<usize> =
        measured_points().into_iter().filter(|&p| (p % NX).is_multiple_of(2) && (p / NX).is_multiple_of(2)).collect();
    let fields: Vec<Vec<Complex64>> = [0.3, 1.1, 2.0].iter().map(|&angle| plane_wave(0.06, angle)).collect();
    let layout = FieldLayout { grid: &g, points: &points, mask: &mask, local_mask: &mask, exclusions: &[] };
    let w = wavelengths_at(&response(&fields, &points), fields.len(), &layout, &DispersionOptions::default()).unwrap();
    let full = {
        let all = measured_points();
        let layout = FieldLayout { grid: &g, points: &all, mask: &mask, local_mask: &mask, exclusions: &[] };
        wavelengths_at(&response(&fields, &all), fields.len(), &layout, &DispersionOptions::default()).unwrap()
    };
    let (sub, whole) = (w.k_space_summary.median_m, full.k_space_summary.median_m);
    // What the subset read on the full grid, holes and all: an image, far from 6 cm.
    let mut holes = vec![false; NX * NY];
    for &p in &points {
        holes[p] = true;
    }
    let on_full = estimate_wavelength(&fields[0], &holes, NX, NY, SPACING_M, &KSpaceOptions::default()).unwrap();
    assert!((on_full.median_m / 0.06 - 1.0).abs() > 0.5, "{on_full:?}");
    assert!((sub / whole - 1.0).abs() < 0.05 && (sub / 0.06 - 1.0).abs() < 0.05, "subset {sub} m, full grid {whole} m");
}

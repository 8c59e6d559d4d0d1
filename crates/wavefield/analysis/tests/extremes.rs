//! The analyses at the extremes of their inputs (issue 20): a dead actuator (an all-zero column of `G`), a
//! condition number of 1e12, two coincident points, a band of one bin. Each gives a documented, finite result or a
//! typed error, never a NaN. (The control layer's extremes: wavefield/control/tests/solve_extremes.rs.)

#![allow(clippy::unwrap_used)] // helpers outside #[test] functions unwrap too: a failure is a failed test

use std::f64::consts::PI;

use metaplate_analysis::AnalysisError;
use metaplate_analysis::authority::{AuthorityOptions, domain_authority};
use metaplate_analysis::pixel::{PixelAreaOptions, pixel_area_map};
use metaplate_analysis::pod::{PodOptions, pod};
use metaplate_analysis::report::wavelength_at_bin;
use metaplate_control::PropagationMatrices;
use metaplate_control::target::TargetBand;
use metaplate_core::grid::GridSpec;
use num_complex::Complex64;

const NX: usize = 15;
const POINTS: usize = NX * NX;
const ACTUATORS: usize = 8;
/// Bins 150..=400 of a 1000-point DFT at 1 kHz: 1 Hz apart, 150 to 400 Hz.
const BINS: std::ops::Range<usize> = 150..401;

/// A travelling plane wave per actuator (direction `a * 45 deg / 2`, wavelength 4 cm at every bin) scaled by
/// `gain(a)`, on a 15 x 15 grid at 5 mm, listed at `points` (grid indices; a point may repeat).
fn matrices(points: &[u32], gain: impl Fn(usize) -> f64) -> (PropagationMatrices, GridSpec) {
    let grid = GridSpec::centred(NX, NX, 0.005);
    let k_rad_m = 2.0 * PI / 0.04;
    let mut data = Vec::new();
    for bin in BINS {
        for a in 0..ACTUATORS {
            let angle = a as f64 * PI / 8.0;
            for &p in points {
                let (x, y) = grid.position_m(p as usize);
                let phase = k_rad_m * (x * angle.cos() + y * angle.sin()) + 0.01 * bin as f64;
                data.push(Complex64::from_polar(gain(a), phase));
            }
        }
    }
    let g = PropagationMatrices::from_parts(BINS, 1000, 1000.0, points.to_vec(), (0..8).collect(), data).unwrap();
    (g, grid)
}

fn all_points() -> Vec<u32> {
    (0..POINTS as u32).collect()
}

fn assert_finite_pod(g: &PropagationMatrices, band_hz: (f64, f64)) -> usize {
    let p = pod(g, &PodOptions { band_hz, ..PodOptions::default() }).unwrap();
    assert!(p.energy.iter().all(|e| e.is_finite() && *e >= 0.0), "{:?}", p.energy);
    assert!((p.energy.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    p.components
}

fn pixel_map(g: &PropagationMatrices, grid: &GridSpec, band_hz: (f64, f64)) -> metaplate_analysis::pixel::PixelAreaMap {
    // The target's skirts must fit in the band: a brick wall for a band of one bin.
    let skirt_hz = if band_hz.1 - band_hz.0 < 2.0 { 0.0 } else { TargetBand::default().skirt_hz };
    let options =
        PixelAreaOptions { band_hz, threads: 1, target_band: TargetBand { skirt_hz }, ..PixelAreaOptions::default() };
    let map = pixel_area_map(g, grid, &vec![true; grid.len()], &options).unwrap();
    assert!(map.peak.iter().all(|p| p.is_finite()), "peaks finite");
    assert!(map.area_cm2.iter().flatten().all(|a| a.is_finite() && *a > 0.0), "areas finite and positive");
    map
}

#[test]
fn a_dead_actuator_is_left_out_of_the_wavelength_and_makes_the_authority_a_typed_error() {
    let (g, grid) = matrices(&all_points(), |a| if a == 3 { 0.0 } else { 1.0 });
    // The wavelength is the mean over the actuators that move the plate: the dead one is left out, and counted.
    let summary = wavelength_at_bin(&g, &grid, 100).unwrap();
    assert_eq!(summary.actuators, ACTUATORS - 1);
    assert!((summary.median_m - 0.04).abs() < 0.1 * 0.04, "{summary:?}");
    // POD of the actuator sum does not notice a dead actuator.
    assert!(assert_finite_pod(&g, (75.0, 400.0)) >= 1);
    // Authority over the actuators: G_D is singular at every bin, its condition number infinite: a typed error.
    let authority = domain_authority(&g, &grid, 0.05, &AuthorityOptions::default());
    assert!(matches!(authority, Err(AnalysisError::NonFiniteResult { .. })), "{authority:?}");
    // The pixel-area map solves with the seven live actuators: finite peaks and areas.
    pixel_map(&g, &grid, (75.0, 400.0));
    // Every actuator dead: no wavelength at all, said so.
    let (dead, grid) = matrices(&all_points(), |_| 0.0);
    assert!(matches!(wavelength_at_bin(&dead, &grid, 100), Err(AnalysisError::NoEnergy { .. })));
}

#[test]
fn a_condition_number_of_1e12_is_reported_finite_with_the_weak_direction_below_the_rank_threshold() {
    // Orthogonal columns of equal norm over the whole grid (DFT patterns), actuator 7's a million million times
    // weaker: singular values 1 (seven times) and 1e-12, so the condition number is 1e12 exactly.
    let grid = GridSpec::centred(NX, NX, 0.005);
    let mut data = Vec::new();
    for _ in BINS {
        for a in 0..ACTUATORS {
            let gain = if a == 7 { 1e-12 } else { 1.0 };
            data.extend((0..POINTS).map(|p| Complex64::from_polar(gain, 2.0 * PI * (p * a) as f64 / POINTS as f64)));
        }
    }
    let g = PropagationMatrices::from_parts(BINS, 1000, 1000.0, all_points(), (0..8).collect(), data).unwrap();
    let whole_grid_m = 0.08;
    let authority = domain_authority(&g, &grid, whole_grid_m, &AuthorityOptions::default()).unwrap();
    assert_eq!(authority.points.len(), POINTS);
    let condition = authority.mean_condition_number();
    assert!((condition / 1e12 - 1.0).abs() < 1e-3, "condition {condition:e}");
    assert_eq!(authority.mean_effective_rank(), 7.0, "the weak direction is 240 dB down, below the -30 dB threshold");
    for row in &authority.relative_energy_db {
        assert!(row.iter().all(|v| v.is_finite()), "{row:?}");
    }
    assert_finite_pod(&g, (75.0, 400.0));
    // Focusing with a 1e12-conditioned G stays finite (the regularisation caps the weak direction's gain).
    let (plane_waves, _) = matrices(&all_points(), |a| if a == 7 { 1e-12 } else { 1.0 });
    pixel_map(&plane_waves, &grid, (75.0, 400.0));
}

#[test]
fn coincident_points_give_the_same_results_as_the_points_once() {
    // The centre point listed twice (a re-measured point imported twice): its rows are equal.
    let mut points = all_points();
    points.push((POINTS / 2) as u32);
    let (twice, grid) = matrices(&points, |_| 1.0);
    let (once, _) = matrices(&all_points(), |_| 1.0);
    let a_twice = domain_authority(&twice, &grid, 0.035, &AuthorityOptions::default()).unwrap();
    let a_once = domain_authority(&once, &grid, 0.035, &AuthorityOptions::default()).unwrap();
    assert_eq!(a_twice.points.len(), a_once.points.len() + 1);
    assert_eq!(a_twice.mean_effective_rank(), a_once.mean_effective_rank());
    assert!(a_twice.mean_condition_number().is_finite());
    assert_finite_pod(&twice, (75.0, 400.0));
    let (w_twice, w_once) =
        (wavelength_at_bin(&twice, &grid, 100).unwrap(), wavelength_at_bin(&once, &grid, 100).unwrap());
    assert_eq!(w_twice.median_m, w_once.median_m, "the field is laid on the grid once per point");
    let (m_twice, m_once) = (pixel_map(&twice, &grid, (75.0, 400.0)), pixel_map(&once, &grid, (75.0, 400.0)));
    assert_eq!(m_twice.area_cm2.len(), POINTS + 1);
    assert_eq!(m_twice.area_cm2[POINTS], m_twice.area_cm2[POINTS / 2], "the repeated point is the same pixel");
    assert_eq!(m_once.area_cm2.len(), POINTS);
}

#[test]
fn a_band_of_one_bin_is_analysed_and_an_empty_band_is_refused_by_name() {
    let (g, grid) = matrices(&all_points(), |_| 1.0);
    let one_bin = (199.6, 200.4);
    // One bin: the actuator sum is one complex pattern, two real components at most.
    assert!((1..=2).contains(&assert_finite_pod(&g, one_bin)));
    let authority =
        domain_authority(&g, &grid, 0.035, &AuthorityOptions { band_hz: one_bin, ..AuthorityOptions::default() })
            .unwrap();
    assert_eq!(authority.condition_number.len(), 1);
    assert!(authority.mean_condition_number().is_finite());
    pixel_map(&g, &grid, one_bin);
    // A band between two bins holds none: refused, naming the band.
    let empty = (200.2, 200.8);
    let refused = pod(&g, &PodOptions { band_hz: empty, ..PodOptions::default() });
    assert!(matches!(refused, Err(AnalysisError::InvalidParameter { .. })), "{refused:?}");
    let refused =
        domain_authority(&g, &grid, 0.035, &AuthorityOptions { band_hz: empty, ..AuthorityOptions::default() });
    assert!(matches!(refused, Err(AnalysisError::InvalidParameter { .. })), "{refused:?}");
}

//! Physical properties of the simulated plate: reciprocity, decay set by the loss factor, convergence under grid
//! refinement.
#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_core::scene::Scene;
use metaplate_plate::{GreensRequest, ModelOptions, PlateModel};

#[test]
fn reciprocal_between_actuator_positions() {
    // Put two actuators exactly on grid points so each can also be observed: the response at B to a force at A must
    // equal the response at A to a force at B (the system matrix is complex symmetric; loads and observations use
    // the same interpolation weights).
    let mut scene = Scene::builtin("metamaterial").unwrap();
    let (a, b) = ((0.05, 0.02), (-0.07, -0.035));
    (scene.actuators[0].x_m, scene.actuators[0].y_m) = a;
    (scene.actuators[1].x_m, scene.actuators[1].y_m) = b;
    scene.validate().unwrap();
    let index_of = |(x, y): (f64, f64)| {
        let g = &scene.grid;
        let ix = ((x - g.origin_x_m) / g.spacing_m).round() as usize;
        let iy = ((y - g.origin_y_m) / g.spacing_m).round() as usize;
        g.index(ix, iy)
    };
    let (pa, pb) = (index_of(a), index_of(b));
    let model = PlateModel::from_scene(&scene, &ModelOptions::default()).unwrap();
    for f in [80.0, 333.0, 610.0] {
        let r = model.frequency_response(f, &[0, 1], &[pa, pb]).unwrap();
        let (b_from_a, a_from_b) = (r[2], r[1]); // [point * 2 + actuator]
        // LU with partial pivoting on a damped system: backward error ~1e-16 times a modest condition number; 1e-8
        // relative leaves ample room and still catches any asymmetry in assembly (those are O(1)).
        assert!((b_from_a - a_from_b).norm() < 1e-8 * b_from_a.norm(), "{f} Hz: {b_from_a} vs {a_from_b}");
    }
}

#[test]
fn ring_down_rate_is_set_by_the_loss_factor() {
    // A free plate (no pads) whose only loss is its structural loss factor eta: every mode at f rings down with
    // amplitude exp(-eta pi f t), energy exp(-2 eta pi f t). Summed over the grid, the modes' energies add (they are
    // orthogonal), so the energy is a mixture of exponentials whose rates lie between those at the band's edges, and
    // the slope of its logarithm between two windows lies between them too.
    let scene = common::free_homogeneous();
    let eta = scene.plate.loss_factor;
    let (lo, hi) = (300.0, 400.0);
    let request = GreensRequest {
        points: scene.measured_points(),
        actuators: vec![2],
        band_hz: (lo, hi),
        duration_s: 0.4,
        sample_rate_hz: 24_000.0,
    };
    let model = PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 2 }).unwrap();
    let g = model.greens_functions(&request).unwrap();
    let energy = |t0: f64, t1: f64| -> f64 {
        let (i0, i1) = ((t0 * 24_000.0) as usize, (t1 * 24_000.0) as usize);
        (0..g.points.len()).map(|p| g.ir(p, 0).unwrap()[i0..i1].iter().map(|v| v * v).sum::<f64>()).sum()
    };
    // Windows of 50 ms (15 to 20 periods, so the twice-per-period swing of kinetic energy averages out), after the
    // band-edge tapers' own ringing (about 1 / 40 Hz = 25 ms) and before the final fade-out.
    let (e1, e2) = (energy(0.10, 0.15), energy(0.25, 0.30));
    let rate = (e1 / e2).ln() / 0.15;
    let (slowest, fastest) = (2.0 * eta * std::f64::consts::PI * lo, 2.0 * eta * std::f64::consts::PI * hi);
    // 5 % beyond the bounds for what orthogonality over a finite grid leaves of the cross terms between modes.
    assert!(rate > 0.95 * slowest && rate < 1.05 * fastest, "rate {rate} /s outside [{slowest}, {fastest}]");
}

#[test]
fn converges_under_grid_refinement() {
    // The response at a few grid points must settle as the lattice is refined: successive differences shrink.
    let scene = Scene::builtin("metamaterial").unwrap();
    let points: Vec<usize> = [(10, 12), (24, 12), (40, 6)].iter().map(|&(ix, iy)| scene.grid.index(ix, iy)).collect();
    let responses: Vec<Vec<_>> = (1..=3)
        .map(|refinement| {
            let model = PlateModel::from_scene(&scene, &ModelOptions { refinement, threads: 1 }).unwrap();
            model.frequency_response(200.0, &[0, 5], &points).unwrap()
        })
        .collect();
    let diff = |a: &[num_complex::Complex64], b: &[num_complex::Complex64]| -> f64 {
        a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum::<f64>().sqrt()
    };
    let (d12, d23) = (diff(&responses[0], &responses[1]), diff(&responses[1], &responses[2]));
    assert!(d23 < d12, "not converging: |r2 - r1| = {d12}, |r3 - r2| = {d23}");
}

#[test]
fn driving_points_follow_the_grid() {
    // Actuator 0 on a grid point: its driving point (index grid.len() + 0) must give exactly what the grid point
    // gives (same interpolation weights: one node). Actuator 1 off the grid: its driving point is reciprocal with
    // actuator 0's (complex symmetric system, same weights for load and observation).
    let mut scene = Scene::builtin("metamaterial").unwrap();
    (scene.actuators[0].x_m, scene.actuators[0].y_m) = (0.05, 0.02);
    scene.validate().unwrap();
    let g = &scene.grid;
    let on_grid = g.index(
        ((0.05 - g.origin_x_m) / g.spacing_m).round() as usize,
        ((0.02 - g.origin_y_m) / g.spacing_m).round() as usize,
    );
    let model = PlateModel::from_scene(&scene, &ModelOptions::default()).unwrap();
    let (drive0, drive1) = (g.len(), g.len() + 1);
    assert_eq!(model.grid_len(), g.len());
    for f in [80.0, 610.0] {
        let r = model.frequency_response(f, &[0, 1], &[on_grid, drive0, drive1]).unwrap();
        assert_eq!(r[0], r[2], "{f} Hz: grid point vs driving point of actuator 0");
        // 1e-8 relative: as in the reciprocity test above.
        assert!((r[3] - r[4]).norm() < 1e-8 * r[3].norm(), "{f} Hz: {} vs {}", r[3], r[4]);
    }
    let beyond = g.len() + scene.actuators.len();
    assert!(model.frequency_response(100.0, &[0], &[beyond]).is_err());
}

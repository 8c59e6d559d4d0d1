//! Extremes of the per-bin solver and the drive solve on synthetic propagation matrices.
#![allow(clippy::unwrap_used)] // tests may unwrap (preamble rule); the workspace lint targets library code.

use faer::Mat;
use metaplate_control::render::{FocusOptions, normalise_peak, solve_drives};
use metaplate_control::solve::{Method, Regularisation, solve_bin};
use metaplate_control::target::{PixelTarget, Waveform};
use metaplate_control::{ControlError, PropagationMatrices};
use num_complex::Complex64;

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

/// A deterministic "random" C x N matrix.
fn matrix(rows: usize, cols: usize, seed: u64) -> Mat<Complex64> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    Mat::from_fn(rows, cols, |_, _| c(next(), next()))
}

fn residual(g: &Mat<Complex64>, a: &[Complex64], v: &[Complex64]) -> f64 {
    (0..g.nrows())
        .map(|r| ((0..g.ncols()).map(|j| g[(r, j)] * a[j]).sum::<Complex64>() - v[r]).norm_sqr())
        .sum::<f64>()
        .sqrt()
}

#[test]
fn alpha_zero_on_duplicated_rows_gives_the_minimum_norm_exact_solution() {
    // Rows 0 and 1 identical (a duplicated point) with consistent targets: rank 2 of 3 rows, exact solution exists.
    let mut g = matrix(3, 8, 1);
    for j in 0..8 {
        g[(1, j)] = g[(0, j)];
    }
    let v = [c(1.0, 0.0), c(1.0, 0.0), c(0.0, 0.5)];
    let a = solve_bin(g.as_ref(), &v, Regularisation::Absolute(0.0), Method::InverseFilter).unwrap();
    // Residual at rounding level (entries O(1), 8 columns): 1e-12 leaves 4 orders of margin over f64 rounding.
    assert!(residual(&g, &a, &v) < 1e-12, "residual {}", residual(&g, &a, &v));
}

#[test]
fn condition_number_1e12_stays_finite_and_regularisation_bounds_the_drive() {
    // Two nearly parallel rows: sigma_min / sigma_max about 1e-12.
    let mut g = matrix(2, 8, 2);
    for j in 0..8 {
        g[(1, j)] = g[(0, j)] * (1.0 + 1e-12) + c(1e-12, 0.0) * if j == 0 { 1.0 } else { 0.0 };
    }
    let v = [c(1.0, 0.0), c(-1.0, 0.0)];
    let exact = solve_bin(g.as_ref(), &v, Regularisation::Absolute(0.0), Method::InverseFilter).unwrap();
    assert!(exact.iter().all(|z| z.norm().is_finite()));
    let damped = solve_bin(g.as_ref(), &v, Regularisation::Relative(1e-3), Method::InverseFilter).unwrap();
    // With alpha = 1e-3 s_max the gain on any direction is at most 1 / (2 alpha) = 500 / s_max; |v| = sqrt 2.
    let s_max = g.as_ref().singular_values().unwrap()[0];
    let norm = damped.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    assert!(norm <= 500.0 / s_max * 2f64.sqrt() * (1.0 + 1e-9), "drive norm {norm}");
}

#[test]
fn more_pixels_than_actuators_gives_the_least_squares_solution() {
    let g = matrix(12, 8, 3);
    let v: Vec<Complex64> = (0..12).map(|i| c(i as f64, 0.0)).collect();
    let a = solve_bin(g.as_ref(), &v, Regularisation::Absolute(0.0), Method::InverseFilter).unwrap();
    // Least squares: the residual is orthogonal to the columns, G^H (G a - v) = 0 to rounding.
    let r: Vec<Complex64> = (0..12).map(|i| (0..8).map(|j| g[(i, j)] * a[j]).sum::<Complex64>() - v[i]).collect();
    for j in 0..8 {
        let dot: Complex64 = (0..12).map(|i| g[(i, j)].conj() * r[i]).sum();
        // Entries O(1) and O(10): 1e-9 is far above rounding, far below a wrong solution's O(1).
        assert!(dot.norm() < 1e-9, "column {j}: {dot}");
    }
}

fn synthetic(points: usize, seed: u64) -> PropagationMatrices {
    let bins = 3..40;
    let mut data = Vec::new();
    for k in bins.clone() {
        let m = matrix(points, 8, seed + k as u64);
        for j in 0..8 {
            data.extend((0..points).map(|i| m[(i, j)]));
        }
    }
    PropagationMatrices::from_parts(bins, 100, 1000.0, (0..points as u32).collect(), (0..8).collect(), data).unwrap()
}

#[test]
fn all_null_targets_give_zero_drives_and_an_unknown_pixel_is_an_error() {
    let g = synthetic(6, 4);
    let targets: Vec<PixelTarget> =
        (0..3).map(|p| PixelTarget { point_index: p, waveform: Waveform::Null, amplitude: 1.0 }).collect();
    let drives = solve_drives(&g, &targets, &FocusOptions::default()).unwrap();
    let mut signals = drives.signals(&g).unwrap();
    assert!(signals.iter().flatten().all(|&v| v == 0.0));
    assert_eq!(normalise_peak(&mut signals, 1.0).unwrap(), (0.0, 0.0));
    let off = [PixelTarget { point_index: 99, waveform: Waveform::Impulse { time_s: 0.05 }, amplitude: 1.0 }];
    assert!(matches!(
        solve_drives(&g, &off, &FocusOptions::default()),
        Err(ControlError::UnknownPoint { point_index: 99 })
    ));
}

#[test]
fn negative_or_nan_alpha_is_refused() {
    let g = matrix(1, 8, 5);
    for reg in [Regularisation::Absolute(-1.0), Regularisation::Relative(f64::NAN)] {
        assert!(matches!(
            solve_bin(g.as_ref(), &[c(1.0, 0.0)], reg, Method::InverseFilter),
            Err(ControlError::InvalidParameter { name: "alpha", .. })
        ));
    }
}

#[test]
fn a_dead_actuator_gets_no_drive_and_the_others_still_focus() {
    // Column 3 all zero: a coil that does not move the plate.
    let mut g = matrix(2, 8, 6);
    for r in 0..2 {
        g[(r, 3)] = c(0.0, 0.0);
    }
    let v = [c(1.0, 0.0), c(0.0, 0.0)];
    for reg in [Regularisation::Absolute(0.0), Regularisation::default()] {
        let a = solve_bin(g.as_ref(), &v, reg, Method::InverseFilter).unwrap();
        // The minimum-norm (and any Tikhonov) solution has no component on a zero column.
        assert!(a[3].norm() < 1e-12, "{reg:?}: dead actuator driven with {}", a[3]);
        assert!(a.iter().all(|z| z.re.is_finite() && z.im.is_finite()));
    }
    // Unregularised, the seven live actuators reach both targets exactly.
    let a = solve_bin(g.as_ref(), &v, Regularisation::Absolute(0.0), Method::InverseFilter).unwrap();
    assert!(residual(&g, &a, &v) < 1e-12);
    // Every actuator dead: zero drives, not NaN.
    let dead = Mat::<Complex64>::zeros(2, 8);
    let a = solve_bin(dead.as_ref(), &v, Regularisation::default(), Method::InverseFilter).unwrap();
    assert!(a.iter().all(|z| *z == c(0.0, 0.0)));
}

#[test]
fn regularisation_up_to_1e12_s_max_shrinks_the_drive_toward_zero_finitely() {
    let g = matrix(3, 8, 7);
    let v = [c(1.0, 0.0), c(0.0, 1.0), c(0.5, 0.0)];
    let s_max = g.as_ref().singular_values().unwrap()[0];
    let mut last = f64::INFINITY;
    for r in [1e-3, 1.0, 1e3, 1e6, 1e12] {
        let a = solve_bin(g.as_ref(), &v, Regularisation::Relative(r), Method::InverseFilter).unwrap();
        let norm = a.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
        assert!(norm.is_finite() && norm <= last, "r {r}: norm {norm} after {last}");
        // Each direction's gain sigma / (sigma^2 + alpha^2) is at most s_max / alpha^2 = 1 / (r^2 s_max).
        assert!(norm <= (v.iter().map(|z| z.norm_sqr()).sum::<f64>()).sqrt() / (r * r * s_max) * (1.0 + 1e-9));
        last = norm;
    }
    // At 1e12 s_max the drive is about 1e-24 of the target: far below anything audible, and not NaN or zero by
    // underflow of the whole vector.
    assert!(last > 0.0 && last < 1e-20, "{last}");
}

#[test]
fn coincident_pixels_with_different_targets_get_the_least_squares_compromise() {
    // Two pixels at one point asking for opposite things: no drive satisfies both; the minimum-norm least-squares
    // answer sends the mean (zero) there, finitely.
    let mut g = matrix(2, 8, 8);
    for j in 0..8 {
        g[(1, j)] = g[(0, j)];
    }
    let v = [c(1.0, 0.0), c(-1.0, 0.0)];
    let a = solve_bin(g.as_ref(), &v, Regularisation::Absolute(0.0), Method::InverseFilter).unwrap();
    let at_point: Complex64 = (0..8).map(|j| g[(0, j)] * a[j]).sum();
    assert!(at_point.norm() < 1e-12, "{at_point}");
    assert!(a.iter().all(|z| z.norm() < 1e-12), "the compromise needs no drive at all");
}

#[test]
fn a_band_of_one_bin_solves_and_renders_finite_drives() {
    let bins = 10..11;
    let m = matrix(4, 8, 9);
    let mut data = Vec::new();
    for j in 0..8 {
        data.extend((0..4).map(|i| m[(i, j)]));
    }
    let g = PropagationMatrices::from_parts(bins, 100, 1000.0, (0..4).collect(), (0..8).collect(), data).unwrap();
    assert_eq!(g.n_bins(), 1);
    let targets = [PixelTarget { point_index: 2, waveform: Waveform::Impulse { time_s: 0.05 }, amplitude: 1.0 }];
    let options =
        FocusOptions { target_band: metaplate_control::target::TargetBand { skirt_hz: 0.0 }, ..Default::default() };
    let drives = solve_drives(&g, &targets, &options).unwrap();
    let signals = drives.signals(&g).unwrap();
    assert_eq!(signals.len(), 8);
    assert!(signals.iter().flatten().all(|v| v.is_finite()));
    // The default 25 Hz skirts do not fit in a band of one bin: a typed refusal naming the parameter, not a
    // target tapered to nothing.
    assert!(matches!(
        solve_drives(&g, &targets, &FocusOptions::default()),
        Err(ControlError::InvalidParameter { name: "skirt_hz", .. })
    ));
}

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use num_complex::Complex64;

use faer::Mat;
use metaplate_control::solve::*;

/// Time reversal is the plain matched filter, bin by bin: `a = G^H v`, unscaled, so two bins whose responses
/// differ by a factor 10 get drives that differ by that factor (no per-bin normalisation), as in
/// `focal::single_pixel_focal_fields`.
#[test]
fn time_reversal_is_the_unnormalised_matched_filter() {
    let rows =
        [[Complex64::new(1.0, 2.0), Complex64::new(-0.5, 0.0)], [Complex64::new(0.0, 1.0), Complex64::new(3.0, -1.0)]];
    let g = Mat::from_fn(2, 2, |i, j| rows[i][j]);
    let v = [Complex64::new(1.0, 0.0), Complex64::new(0.0, -2.0)];
    for scale in [1.0, 10.0] {
        let gs = Mat::from_fn(2, 2, |i, j| rows[i][j] * scale);
        let a = solve_bin(gs.as_ref(), &v, Regularisation::Absolute(0.0), Method::TimeReversal).unwrap();
        for (j, aj) in a.iter().enumerate() {
            let expected: Complex64 = (0..2).map(|i| g[(i, j)].conj() * scale * v[i]).sum();
            assert!((aj - expected).norm() <= 1e-12 * expected.norm().max(1.0), "{aj} against {expected}");
        }
    }
}

/// The closed form is the SVD solver's one-pixel case: `a = conj(g) v single_pixel_gain(|g|^2)`.
#[test]
fn single_pixel_gain_is_the_svd_solution_for_one_pixel() {
    let row = [Complex64::new(0.3, -1.2), Complex64::new(-2.0, 0.5), Complex64::new(1e-3, 0.0)];
    let g = Mat::from_fn(1, row.len(), |_, j| row[j]);
    let norm_sqr: f64 = row.iter().map(|z| z.norm_sqr()).sum();
    let v = Complex64::new(0.7, 0.2);
    for reg in [Regularisation::Absolute(0.0), Regularisation::Absolute(0.8), Regularisation::Relative(0.1)] {
        let a = solve_bin(g.as_ref(), &[v], reg, Method::InverseFilter).unwrap();
        let c = single_pixel_gain(norm_sqr, reg);
        for (aj, gj) in a.iter().zip(&row) {
            // Two routes through double-precision arithmetic on O(1) numbers: 1e-12 relative is ~1e4 ulp.
            assert!((aj - gj.conj() * v * c).norm() <= 1e-12 * aj.norm().max(1e-300), "{reg:?}: {aj} vs {c}");
        }
    }
    // A zero row: zero gain, as the SVD path gives a zero drive.
    assert_eq!(single_pixel_gain(0.0, Regularisation::Absolute(0.0)), 0.0);
}

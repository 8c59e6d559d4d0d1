#![allow(clippy::unwrap_used)]

use metaplate_dsp::error::DspError;

use metaplate_dsp::lstsq::*;

#[test]
fn a_line_fit_recovers_its_coefficients_and_a_square_system_is_solved_exactly() {
    // y = 2 - 3 t at 50 points, exactly: the fit returns (2, -3) to rounding.
    let t: Vec<f64> = (0..50).map(|i| i as f64 / 7.0).collect();
    let a: Vec<f64> = t.iter().flat_map(|t| [1.0, *t]).collect();
    let b: Vec<f64> = t.iter().map(|t| 2.0 - 3.0 * t).collect();
    let x = least_squares(&a, 50, 2, &b).unwrap();
    assert!((x[0] - 2.0).abs() < 1e-12 && (x[1] + 3.0).abs() < 1e-12, "{x:?}");
    // Residual orthogonal to the columns: y = t^2 fitted by a line leaves A^T r = 0.
    let b2: Vec<f64> = t.iter().map(|t| t * t).collect();
    let x = least_squares(&a, 50, 2, &b2).unwrap();
    let r: Vec<f64> = t.iter().zip(&b2).map(|(t, y)| y - x[0] - x[1] * t).collect();
    assert!(r.iter().sum::<f64>().abs() < 1e-9 && r.iter().zip(&t).map(|(r, t)| r * t).sum::<f64>().abs() < 1e-9);
    let x = least_squares(&[0.0, 1.0, 1.0, 0.0], 2, 2, &[3.0, 4.0]).unwrap();
    assert_eq!(x, vec![4.0, 3.0], "a permutation: no rounding at all");
}

/// Householder QR on the row-major matrix, one column at a time: the textbook order of operations.
fn row_major_reference(a: &[f64], rows: usize, cols: usize, b: &[f64]) -> Vec<f64> {
    let (mut r, mut y) = (a.to_vec(), b.to_vec());
    for j in 0..cols {
        let norm = (j..rows).map(|i| r[i * cols + j].powi(2)).sum::<f64>().sqrt();
        let alpha = if r[j * cols + j] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = (j..rows).map(|i| r[i * cols + j]).collect();
        v[0] -= alpha;
        let v_norm_sqr: f64 = v.iter().map(|x| x * x).sum();
        for c in j..cols {
            let dot: f64 = v.iter().enumerate().map(|(i, vi)| vi * r[(j + i) * cols + c]).sum();
            v.iter().enumerate().for_each(|(i, vi)| r[(j + i) * cols + c] -= 2.0 * dot / v_norm_sqr * vi);
        }
        let dot: f64 = v.iter().enumerate().map(|(i, vi)| vi * y[j + i]).sum();
        v.iter().enumerate().for_each(|(i, vi)| y[j + i] -= 2.0 * dot / v_norm_sqr * vi);
    }
    let mut x = vec![0.0; cols];
    for j in (0..cols).rev() {
        let tail: f64 = (j + 1..cols).map(|c| r[j * cols + c] * x[c]).sum();
        x[j] = (y[j] - tail) / r[j * cols + j];
    }
    x
}

#[test]
fn the_result_is_the_row_major_algorithms_bit_for_bit_for_every_column_count() {
    // Column-major storage and four running sums at a time change no operation's order: the solution is the
    // same to the last bit (the calibration's fixed-seed datasets depend on it), for column counts that fill
    // the groups of four exactly, leave one to three over, and the single column.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for cols in [1, 2, 3, 4, 5, 8, 11, 37] {
        let rows = 3 * cols + 7;
        let a: Vec<f64> = (0..rows * cols).map(|_| next()).collect();
        let b: Vec<f64> = (0..rows).map(|_| next()).collect();
        let x = least_squares(&a, rows, cols, &b).unwrap();
        let reference = row_major_reference(&a, rows, cols, &b);
        assert_eq!(
            x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            reference.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            "{cols} columns"
        );
    }
}

#[test]
fn an_ill_conditioned_fit_stays_accurate_and_a_singular_one_is_refused() {
    // Columns 1 and 1 + 1e-7 t: condition number ~1e8, fine for QR (its square, 1e16, would ruin the normal
    // equations). The exact solution (1, 1) comes back to about cond * eps = 1e-8.
    let t: Vec<f64> = (0..20).map(|i| i as f64).collect();
    let a: Vec<f64> = t.iter().flat_map(|t| [1.0, 1.0 + 1e-7 * t]).collect();
    let b: Vec<f64> = t.iter().map(|t| 2.0 + 1e-7 * t).collect();
    let x = least_squares(&a, 20, 2, &b).unwrap();
    assert!((x[0] - 1.0).abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6, "{x:?}");
    let dup: Vec<f64> = t.iter().flat_map(|t| [*t, *t]).collect();
    assert!(matches!(least_squares(&dup, 20, 2, &b), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(least_squares(&[0.0; 4], 2, 2, &[1.0, 1.0]), Err(DspError::InvalidParameter { .. })));
}

#[test]
fn bad_shapes_and_values_are_refused() {
    assert!(matches!(least_squares(&[1.0; 4], 2, 3, &[1.0; 2]), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(least_squares(&[1.0; 4], 2, 0, &[1.0; 2]), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(least_squares(&[1.0; 3], 2, 2, &[1.0; 2]), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(least_squares(&[1.0; 4], 2, 2, &[1.0; 3]), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(least_squares(&[1.0, f64::NAN, 0.0, 1.0], 2, 2, &[1.0; 2]), Err(DspError::NonFinite { .. })));
}

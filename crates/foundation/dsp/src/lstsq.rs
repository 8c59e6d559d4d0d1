//! Real linear least squares by Householder QR, for the small dense problems inside the DSP routines (tens of
//! unknowns, hundreds or thousands of equations), where a linear-algebra crate would be a heavy dependency.

use crate::error::{DspError, check_signal};

/// The `x` minimising `|A x - b|` for the `rows x cols` matrix `a` (row-major) and `b` (`rows` values), by
/// Householder QR (never the normal equations, whose condition number is the square of `A`'s).
///
/// Valid range: `1 <= cols <= rows`, finite entries, `A` of full column rank: a column whose remaining norm falls
/// below `1e-12` times the largest column norm is refused (the problem is rank-deficient and `x` not unique).
///
/// # Errors
/// [`DspError::LengthMismatch`] for `a` or `b` of the wrong size, [`DspError::InvalidParameter`] for `cols` out of
/// range or a rank-deficient `A`, [`DspError::NonFinite`] for a non-finite entry.
pub fn least_squares(a: &[f64], rows: usize, cols: usize, b: &[f64]) -> Result<Vec<f64>, DspError> {
    if cols == 0 || cols > rows {
        return Err(DspError::InvalidParameter {
            name: "cols",
            reason: format!("must be 1 to rows ({rows}), got {cols}"),
        });
    }
    if a.len() != rows * cols {
        return Err(DspError::LengthMismatch {
            what: "matrix entries against rows x cols",
            a: a.len(),
            b: rows * cols,
        });
    }
    if b.len() != rows {
        return Err(DspError::LengthMismatch { what: "right-hand side against rows", a: b.len(), b: rows });
    }
    check_signal("matrix", a)?;
    check_signal("right-hand side", b)?;
    // Column-major, so that each reflection reads and updates contiguous memory; every sum runs in the same order
    // as on the row-major matrix (down a column), so the result does not depend on the layout.
    let mut r = vec![0.0; rows * cols];
    for (i, row) in a.chunks_exact(cols).enumerate() {
        for (c, &value) in row.iter().enumerate() {
            r[c * rows + i] = value;
        }
    }
    let mut y = b.to_vec();
    let largest = r.chunks_exact(rows).map(|col| col.iter().map(|v| v.powi(2)).sum::<f64>().sqrt()).fold(0.0, f64::max);
    let mut v = Vec::with_capacity(rows);
    for j in 0..cols {
        let rest = &mut r[j * rows..];
        let norm = rest[j..rows].iter().map(|x| x.powi(2)).sum::<f64>().sqrt();
        if norm <= 1e-12 * largest || norm == 0.0 {
            return Err(DspError::InvalidParameter {
                name: "a",
                reason: format!("is rank-deficient: column {j} is a combination of the ones before it"),
            });
        }
        // The reflection that maps column j below the diagonal onto -sign(r_jj) |.| e_j, avoiding cancellation.
        let alpha = if rest[j] > 0.0 { -norm } else { norm };
        v.clear();
        v.extend_from_slice(&rest[j..rows]);
        v[0] -= alpha;
        let v_norm_sqr: f64 = v.iter().map(|x| x * x).sum();
        // Columns j.. four at a time: four independent running sums hide the latency of one.
        for group in rest.chunks_mut(4 * rows) {
            reflect(&v, v_norm_sqr, group, rows, j);
        }
        reflect(&v, v_norm_sqr, &mut y, rows, j);
    }
    // Back substitution on the upper triangle R x = (Q^T b)[..cols].
    let mut x = vec![0.0; cols];
    for j in (0..cols).rev() {
        let tail: f64 = (j + 1..cols).map(|c| r[c * rows + j] * x[c]).sum();
        x[j] = (y[j] - tail) / r[j * rows + j];
    }
    crate::error::check_result("least-squares solution", &x)?;
    Ok(x)
}

/// Applies the Householder reflection `I - 2 v v^T / |v|^2` to rows `start..` of each column in `columns` (1 to 4
/// columns of `rows` values, column-major; `v` has `rows - start` values). The dot products run together, each
/// summed in order from the first element as `Iterator::sum` does (from -0.0), so the result is the same as one
/// column at a time.
fn reflect(v: &[f64], v_norm_sqr: f64, columns: &mut [f64], rows: usize, start: usize) {
    let count = columns.len() / rows;
    let column = |k: usize| k * rows + start..(k + 1) * rows;
    let mut dots = [-0.0; 4];
    if count == 4 {
        let (a, b, c, d) = (&columns[column(0)], &columns[column(1)], &columns[column(2)], &columns[column(3)]);
        for ((((vi, a), b), c), d) in v.iter().zip(a).zip(b).zip(c).zip(d) {
            dots[0] += vi * a;
            dots[1] += vi * b;
            dots[2] += vi * c;
            dots[3] += vi * d;
        }
    } else {
        for (k, dot) in dots.iter_mut().enumerate().take(count) {
            *dot = v.iter().zip(&columns[column(k)]).map(|(vi, x)| vi * x).sum();
        }
    }
    for (k, dot) in dots.iter().enumerate().take(count) {
        let scale = 2.0 * dot / v_norm_sqr;
        v.iter().zip(&mut columns[column(k)]).for_each(|(vi, x)| *x -= scale * vi);
    }
}

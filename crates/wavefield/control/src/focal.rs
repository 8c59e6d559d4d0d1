//! Single-pixel focal fields at focus time, for many targets at once.
//!
//! For one pixel `j` with a band-limited impulse target at time `T`, the closed-form inverse filter
//! `a_k = conj(g_jk) w_k e^{-i omega_k T} / (|g_jk|^2 + alpha_k^2)` puts, at every point `i` and at time `T`,
//! `v_i(T) = sum_k (c_k / N) w_k s_jk Re(G_ik . conj(g_jk))`, where `w_k` is the target gain, `s_jk` the solver's
//! per-bin scale, `c_k` 2 (1 at DC and Nyquist) and `N` the DFT length. The phase `omega_k T` cancels, so `T` does
//! not matter. With `Re(x . conj(y)) = Re x . Re y + Im x . Im y`, all targets' fields are one real GEMM:
//! `F = B A^T`, `A = [Re G_k, Im G_k]_k` (M x 2NK) and `B` the same rows scaled by `c_k w_k s_jk / N`.

use faer::{Accum, Mat, Par};

use crate::error::ControlError;
use crate::propagation::PropagationMatrices;
use crate::solve::{Method, Regularisation, single_pixel_gain};

/// Fields at focus time: row `t` is the field over all points of `g` (length `n_points`) when focusing on target
/// row `targets[t]`, units of the field per unit target gain.
#[derive(Debug, Clone)]
pub struct FocalFields {
    /// Number of points of every field.
    pub n_points: usize,
    /// The target rows (positions into the propagation matrices' points).
    pub targets: Vec<usize>,
    /// `targets.len() x n_points`, row-major.
    pub values: Vec<f64>,
}

impl FocalFields {
    /// The field when focusing on `targets[t]`, or `None` past the last target.
    pub fn field(&self, t: usize) -> Option<&[f64]> {
        self.values.get(t * self.n_points..(t + 1) * self.n_points)
    }
}

/// The focal fields at focus time for single-pixel impulse targets at each of `targets` (rows of `g`), with target
/// gains `gains` (one per bin, from [`crate::target::TargetBand::gains`]), solved by `method` with `reg`.
///
/// Valid range: finite gains, one per bin; targets `< g.n_points()`; any `reg` accepted by [`Regularisation`] (with
/// `alpha = 0` a point whose row is zero at a bin simply gets nothing from that bin). Cost: `4 N K M T` flops (M
/// points, T targets, N actuators, K bins) on `threads` threads; memory `8 (M + T) 2NK + 8 M T` bytes.
///
/// # Errors
/// [`ControlError::LengthMismatch`] for gains, [`ControlError::InvalidParameter`] for a target row or `reg`,
/// [`ControlError::Empty`] for no targets, [`ControlError::NonFiniteResult`] on overflow.
pub fn single_pixel_focal_fields(
    g: &PropagationMatrices,
    targets: &[usize],
    gains: &[f64],
    reg: Regularisation,
    method: Method,
    threads: usize,
) -> Result<FocalFields, ControlError> {
    reg.validate()?;
    let (m, n, k_bins) = (g.n_points(), g.n_actuators(), g.n_bins());
    if gains.len() != k_bins {
        return Err(ControlError::LengthMismatch { what: "target gains against bins", a: gains.len(), b: k_bins });
    }
    crate::error::check_finite("target gains", gains.iter().copied())?;
    if targets.is_empty() {
        return Err(ControlError::Empty { input: "targets" });
    }
    if let Some(&bad) = targets.iter().find(|&&t| t >= m) {
        return Err(ControlError::InvalidParameter { name: "targets", reason: format!("row {bad} >= {m} points") });
    }
    let width = 2 * n * k_bins;
    let fft_len = g.fft_len();
    let mut a = Mat::<f64>::zeros(m, width);
    let mut b = Mat::<f64>::zeros(targets.len(), width);
    for (k, bin) in g.bins().enumerate() {
        let Some(gk) = g.at_bin(k) else { continue };
        let edge = bin == 0 || 2 * bin == fft_len;
        let weight = if edge { 1.0 } else { 2.0 } * gains[k] / fft_len as f64;
        for col in 0..n {
            let (re_col, im_col) = (2 * (k * n + col), 2 * (k * n + col) + 1);
            for i in 0..m {
                let z = gk[(i, col)];
                a[(i, re_col)] = z.re;
                a[(i, im_col)] = z.im;
            }
        }
        for (t, &row) in targets.iter().enumerate() {
            let norm_sqr: f64 = (0..n).map(|col| gk[(row, col)].norm_sqr()).sum();
            let scale = weight
                * match method {
                    Method::InverseFilter => single_pixel_gain(norm_sqr, reg),
                    Method::TimeReversal => 1.0,
                };
            for col in 0..n {
                let (re_col, im_col) = (2 * (k * n + col), 2 * (k * n + col) + 1);
                b[(t, re_col)] = a[(row, re_col)] * scale;
                b[(t, im_col)] = a[(row, im_col)] * scale;
            }
        }
    }
    let mut f = Mat::<f64>::zeros(targets.len(), m);
    let par = if threads > 1 { Par::rayon(threads) } else { Par::Seq };
    faer::linalg::matmul::matmul(f.as_mut(), Accum::Replace, b.as_ref(), a.as_ref().transpose(), 1.0, par);
    let mut values = Vec::with_capacity(targets.len() * m);
    for t in 0..targets.len() {
        values.extend((0..m).map(|i| f[(t, i)]));
    }
    crate::error::check_finite("focal fields", values.iter().copied())
        .map_err(|_| ControlError::NonFiniteResult { what: "focal fields" })?;
    Ok(FocalFields { n_points: m, targets: targets.to_vec(), values })
}

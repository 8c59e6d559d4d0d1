//! Per-bin focusing solvers: Tikhonov-regularised least squares (spatiotemporal inverse filtering) by SVD, its closed
//! form for one pixel, and time reversal.
//!
//! Inverse filtering minimises `|G_C a - v_C|^2 + |alpha a|^2` at each frequency. Through the SVD
//! `G_C = U S V^H` the minimiser is `a = V diag(s / (s^2 + alpha^2)) U^H v_C`, which never forms `G_C^H G_C` (that
//! would square the condition number). With `alpha = 0` it is the minimum-norm least-squares solution (the
//! pseudo-inverse), singular values below `max(C, N) * eps * s_max` counting as zero, so a rank-deficient `G_C`
//! (duplicated points, more pixels than actuators) still gives a finite answer.

use faer::MatRef;
use num_complex::Complex64;

use crate::error::ControlError;

/// The Tikhonov regularisation `alpha` at each frequency.
///
/// Valid range: finite and `>= 0`. `Absolute(alpha)` is in the units of `G`; `Relative(r)` sets
/// `alpha(omega) = r * s_max(omega)`, the largest singular value of `G_C(omega)`, which makes the filter's dynamic
/// range `1 / r` whatever the plate's gain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Regularisation {
    /// `alpha` in the units of `G`.
    Absolute(f64),
    /// `alpha = r * s_max(omega)`.
    Relative(f64),
}

/// The default relative regularisation, 0.005 (-46 dB): about the error of a scanned Green's function (the demo's
/// quick scan: median -49 to -51 dB, p95 -45 to -47 dB against the truth on the two built-in plates), so singular directions the measurement resolves are
/// inverted and those below its error are damped. It also sets how deep a null goes: on the metamaterial ground
/// truth, five pixels with one null leave the null 31 dB below the weakest active pixel (20 dB at 0.01).
pub const DEFAULT_RELATIVE_ALPHA: f64 = 0.005;

impl Default for Regularisation {
    /// `Relative(DEFAULT_RELATIVE_ALPHA)`.
    fn default() -> Self {
        Self::Relative(DEFAULT_RELATIVE_ALPHA)
    }
}

impl Regularisation {
    /// Checks the valid range stated on the type.
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for a negative or non-finite value.
    pub fn validate(&self) -> Result<(), ControlError> {
        let (Self::Absolute(v) | Self::Relative(v)) = *self;
        if !(v.is_finite() && v >= 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "alpha",
                reason: format!("must be finite and >= 0, got {v}"),
            });
        }
        Ok(())
    }

    /// `alpha` for a matrix whose largest singular value is `s_max`.
    pub fn alpha(&self, s_max: f64) -> f64 {
        match *self {
            Self::Absolute(a) => a,
            Self::Relative(r) => r * s_max,
        }
    }
}

/// How drive signals are computed from the targets.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Method {
    /// Spatiotemporal inverse filtering (regularised least squares), the paper's method.
    #[default]
    InverseFilter,
    /// Time reversal: `a = G_C^H v_C`, the matched filter (the time-reversed responses), with no per-frequency
    /// normalisation: its spectrum keeps the colouring `|G|^2` that physical time reversal has, and its overall
    /// scale is arbitrary (renders are peak-normalised; `analysis::focus` scales by one band constant). The same
    /// convention as [`crate::focal`]. Exact only where the pixels' responses are orthogonal, but needs no inversion.
    TimeReversal,
}

/// Solves one bin: the drive vector `a` (length N) for `g_c` (C x N) and the targets `v_c` (length C).
///
/// Valid range: finite `g_c` and `v_c`, `C >= 1`, `N >= 1`, any rank and condition number (a zero `g_c` gives a zero
/// `a`); `reg` as [`Regularisation`].
///
/// # Errors
/// [`ControlError::LengthMismatch`] when `v_c.len() != C`, [`ControlError::InvalidParameter`] for `reg`,
/// [`ControlError::LinearAlgebra`] when the SVD does not converge, [`ControlError::NonFiniteResult`] on overflow.
pub fn solve_bin(
    g_c: MatRef<'_, Complex64>,
    v_c: &[Complex64],
    reg: Regularisation,
    method: Method,
) -> Result<Vec<Complex64>, ControlError> {
    reg.validate()?;
    let (c, n) = (g_c.nrows(), g_c.ncols());
    if v_c.len() != c {
        return Err(ControlError::LengthMismatch { what: "targets against pixels", a: v_c.len(), b: c });
    }
    if c == 0 || n == 0 {
        return Err(ControlError::Empty { input: "propagation matrix" });
    }
    let a = match method {
        Method::InverseFilter => tikhonov_svd(g_c, v_c, reg)?,
        Method::TimeReversal => time_reversal(g_c, v_c)?,
    };
    if a.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return Err(ControlError::NonFiniteResult { what: "drive solution" });
    }
    Ok(a)
}

fn tikhonov_svd(
    g_c: MatRef<'_, Complex64>,
    v_c: &[Complex64],
    reg: Regularisation,
) -> Result<Vec<Complex64>, ControlError> {
    let (c, n) = (g_c.nrows(), g_c.ncols());
    let svd =
        g_c.thin_svd().map_err(|e| ControlError::LinearAlgebra { what: "SVD of G_C", reason: format!("{e:?}") })?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    let s_max = (0..s.nrows()).map(|i| s[i].re).fold(0.0, f64::max);
    let alpha = reg.alpha(s_max);
    let tol = c.max(n) as f64 * f64::EPSILON * s_max;
    let mut a = vec![Complex64::new(0.0, 0.0); n];
    for i in 0..s.nrows() {
        let sigma = s[i].re;
        // alpha = 0: pseudo-inverse with a rank cut-off; alpha > 0: the Tikhonov filter factor is finite anyway,
        // but directions at rounding level still carry only rounding, so they are cut too.
        if sigma <= tol {
            continue;
        }
        let factor = sigma / (sigma * sigma + alpha * alpha);
        let mut proj = Complex64::new(0.0, 0.0);
        for (r, &vr) in v_c.iter().enumerate() {
            proj += u[(r, i)].conj() * vr;
        }
        let coef = proj * factor;
        for (j, aj) in a.iter_mut().enumerate() {
            *aj += v[(j, i)] * coef;
        }
    }
    Ok(a)
}

fn time_reversal(g_c: MatRef<'_, Complex64>, v_c: &[Complex64]) -> Result<Vec<Complex64>, ControlError> {
    let mut a = vec![Complex64::new(0.0, 0.0); g_c.ncols()];
    for (j, aj) in a.iter_mut().enumerate() {
        for (r, &vr) in v_c.iter().enumerate() {
            *aj += g_c[(r, j)].conj() * vr;
        }
    }
    Ok(a)
}

/// The closed form for one pixel (`C = 1`): `a = conj(g) v / (|g|^2 + alpha^2)`, with `g` the pixel's row (length N)
/// and `alpha` from `reg` (`s_max = |g|`). A zero row gives a zero `a`.
///
/// Valid range: finite `g`, `v`; `reg` as [`Regularisation`] (a `Relative(r)` only rescales by `1 / (1 + r^2)`).
pub fn single_pixel_gain(g_norm_sqr: f64, reg: Regularisation) -> f64 {
    let alpha = reg.alpha(g_norm_sqr.sqrt());
    let denom = g_norm_sqr + alpha * alpha;
    if denom > 0.0 { 1.0 / denom } else { 0.0 }
}

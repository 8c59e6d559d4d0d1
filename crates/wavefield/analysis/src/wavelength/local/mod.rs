//! Plate wavelength from the plate equation itself: a biharmonic Rayleigh quotient over the grid.
//!
//! In a source-free region of a homogeneous (or homogenised) Kirchhoff plate the field at one frequency obeys
//! `laplacian^2 u = k^4 u`, whatever mixture of propagating, standing and evanescent waves it holds, and whatever
//! the plate's size. So `k^4` is the least-squares ratio of `L2 u` to `u`:
//! `q = sum conj(u) L2(u) / sum |u|^2` over the usable points, `L2` the 13-point discrete bilaplacian (the 5-point
//! Laplacian applied twice). Unlike the k-space estimator ([`super::estimate_wavelength`]) nothing here depends on
//! the aperture: a 25 cm wave on a 24 x 12 cm grid is measured as well as a 5 cm one.
//!
//! A point is used when its whole 13-point stencil (a diamond of radius `2 h`) is measured and keeps clear of the
//! [`Exclusion`]s: the places where the plate equation does not hold (actuators, support pads, anything attached).
//!
//! Steps: `q` in grid units (`k^4 h^4`, complex: its phase is the loss of a damped plate, `k^4 = k0^4 / (1 + i eta)`);
//! the discrete wavenumber `Re(q^{1/4})` (the real part of the complex wavenumber of a lossy wave); the stencil's
//! own dispersion undone (`correction` module, [`StencilCorrection`]); `lambda = 2 pi / k`.
//!
//! Accuracy and valid range, on noise-free fields:
//! - discretisation: after the isotropic correction a plane wave at angle `t` reads the wavelength long by
//!   `(kh)^2 (c(t) - 3/4) / 24`, `c = cos^4 t + sin^4 t` (long along the axes, short along the diagonals): at
//!   most +-0.4 % at 10 points per wavelength, +-1.1 % at 6; a field mixing directions lies in between.
//!   Evanescent components (`e^{k x}`) see the stencil's error with the opposite sign and read the wavelength short
//!   by `(kh)^2 (c + 3/4) / 24` (2 to 3 % at 10 points per wavelength), in proportion to their share of the
//!   energy;
//! - valid from `lambda >= 6 h` ([`MIN_POINTS_PER_WAVELENGTH`]; shorter is flagged,
//!   [`LocalFlags::too_short`]; shorter than `2 h` is an error) up to about `6300 h` ([`MIN_K4H4`]): a wave much
//!   longer than the grid is measured from its curvature, to the precision of the field (below);
//! - noise: the stencil's weights have a root-sum-square of 26, so white noise of variance `s^2` per point adds
//!   `20 s^2` (the centre weight times the noise power) to `sum conj(u) L2 u` and biases `k^4` up by
//!   `20 / (SNR (kh)^4)`, SNR the field's power over the noise's per point: at 25 cm on a 5 mm grid ((kh)^4 =
//!   2.5e-4) a 1 % bias in k needs an SNR above 80 dB. Fit for simulated fields (rounding only); on measured ones the
//!   k-space estimator, which averages noise over the aperture, is the robust choice;
//! - the field must obey one plate equation over the points used. The residual
//!   [`LocalEstimate::residual`] `= ||L2 u - q u|| / ||L2 u||` says whether it does: when it does, the residual is
//!   the spread of the stencil's error over the field's directions, below about `(kh)^2 / 12` (0.03 at 10 points
//!   per wavelength); it approaches 1 when sources, supports, a change of medium or noise lie inside the region.
//!
//! Cost: 13 complex multiply-adds per grid point.

mod correction;
mod stencil;

use metaplate_core::grid::GridSpec;
use num_complex::Complex64;

use crate::error::AnalysisError;

/// Fewest grid steps per wavelength for the stated accuracy (`kh <= pi / 3`).
pub const MIN_POINTS_PER_WAVELENGTH: f64 = 6.0;

/// Smallest `Re(k^4 h^4)` taken for a wave: rounding leaves about `64 eps ~ 1.4e-14` (the stencil's absolute weights
/// times the machine epsilon) in the bilaplacian of a field whose own bilaplacian is zero (rigid-body motion, tilt,
/// static bending), so anything at or below 1e-12 cannot be told from it. The longest wavelength measured is thus
/// `2 pi h / 1e-3 ~ 6300 h` (31 m on a 5 mm grid).
pub const MIN_K4H4: f64 = 1e-12;

/// A disc the estimator keeps its stencils out of: where the plate equation does not hold (a point force, a support
/// pad, an attached mass). No stencil point lies closer than `radius_m` to `(x_m, y_m)`.
///
/// Valid range: finite coordinates (m, in the grid's frame), finite `radius_m >= 0` (0 excludes nothing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exclusion {
    /// Centre x, m.
    pub x_m: f64,
    /// Centre y, m.
    pub y_m: f64,
    /// Radius, m.
    pub radius_m: f64,
}

/// How the stencil's own dispersion is undone (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StencilCorrection {
    /// None: `k h = (q h^4)^{1/4}`. Reads the wavelength long by `(kh)^2 c(t) / 24`.
    None,
    /// Exact for waves along x or y; over-corrects other directions by up to `(kh)^2 / 48` (the diagonals).
    Axis,
    /// Exact for a field with equal energy in all directions (a diffuse, reverberant field); within
    /// `+-(kh)^2 / 96` for a single direction. The default.
    Isotropic,
}

/// Options of [`estimate_local_wavelength`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalOptions {
    /// How the stencil's dispersion is undone.
    pub correction: StencilCorrection,
    /// Fewest usable points (whole stencil measured and clear of exclusions) accepted; fewer is
    /// [`AnalysisError::TooFewPoints`]. One point suffices for a noise-free plane wave, but a field mixing waves
    /// needs its sums to run over a region at least a wavelength across for the quotient to average them. Valid: >= 1.
    pub min_points: usize,
}

impl Default for LocalOptions {
    fn default() -> Self {
        Self { correction: StencilCorrection::Isotropic, min_points: 1 }
    }
}

/// Where an estimate lies relative to the valid range. All `false` means inside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LocalFlags {
    /// Fewer than [`MIN_POINTS_PER_WAVELENGTH`] grid steps per wavelength: the stencil's dispersion is large and its
    /// correction uncertain (up to 1.1 % at 6 steps, growing fast below).
    pub too_short: bool,
}

impl LocalFlags {
    /// Whether the estimate lies inside the valid range (no flag raised).
    pub fn in_range(&self) -> bool {
        !self.too_short
    }
}

/// A plate-equation wavelength estimate for one field (one actuator, one frequency).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalEstimate {
    /// Wavelength `2 pi / k`, m, after the stencil correction.
    pub wavelength_m: f64,
    /// Wavenumber k, rad/m, after the stencil correction.
    pub wavenumber_rad_m: f64,
    /// The raw quotient `q = sum conj(u) L2 u / sum |u|^2`, rad^4/m^4, before any correction; its phase is minus
    /// the loss factor for a damped plate.
    pub k4_raw: Complex64,
    /// Points used (whole stencil measured, clear of exclusions).
    pub points_used: usize,
    /// `||L2 u - q u|| / ||L2 u||` over the points used (dimensionless, 0 to 1): how far the field is from obeying
    /// one plate equation there (0: exactly; see the module documentation for the expected levels).
    pub residual: f64,
    /// Range flags.
    pub flags: LocalFlags,
}

/// Estimates the plate wavelength of `field` from the plate equation.
///
/// `field`: one complex value per point of `grid` at one frequency, row-major (`iy * nx + ix`), any unit. `mask`:
/// `true` where measured; unmeasured points are never read (they may hold NaN). `exclusions`: discs (m, in the
/// grid's frame) that no stencil may touch. Valid range: see the module documentation (at least 6 grid steps per
/// wavelength for the stated accuracy; outside, the result is flagged).
///
/// # Errors
/// - [`AnalysisError::InvalidParameter`]: the grid fails [`GridSpec::validate`], an exclusion is not finite or has
///   a negative radius, or `opts.min_points` is 0;
/// - [`AnalysisError::LengthMismatch`]: `field` or `mask` is not `grid.len()` long;
/// - [`AnalysisError::NonFinite`]: a measured point holds NaN or an infinity;
/// - [`AnalysisError::TooFewPoints`]: fewer than `opts.min_points` usable points (`measured` counts usable ones);
/// - [`AnalysisError::NoEnergy`]: the field is zero over the usable points;
/// - [`AnalysisError::NotAPlateWave`]: `Re q <= 0` (a static, rigid-body or evanescent-dominated field), or the
///   wave is shorter than two grid steps (beyond the stencil's range);
/// - [`AnalysisError::NonFiniteResult`]: overflow despite finite input (not expected: the field is scaled first).
pub fn estimate_local_wavelength(
    field: &[Complex64],
    mask: &[bool],
    grid: &GridSpec,
    exclusions: &[Exclusion],
    opts: &LocalOptions,
) -> Result<LocalEstimate, AnalysisError> {
    check_inputs(field, mask, grid, exclusions, opts)?;
    let used = stencil::usable_points(grid, mask, exclusions);
    if used.len() < opts.min_points {
        return Err(AnalysisError::TooFewPoints { measured: used.len(), required: opts.min_points });
    }
    // Scale by the largest measured magnitude so that the sums of squares can neither overflow nor underflow.
    let scale = (0..field.len()).filter(|&i| mask[i]).map(|i| field[i].norm()).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(AnalysisError::NoEnergy { what: "local wavelength estimate" });
    }
    let scaled: Vec<Complex64> =
        field.iter().zip(mask).map(|(v, &m)| if m { v / scale } else { Complex64::ZERO }).collect();
    let pairs: Vec<(Complex64, Complex64)> =
        used.iter().map(|&i| (scaled[i], stencil::bilaplacian_at(&scaled, grid.nx, i))).collect();
    let energy: f64 = pairs.iter().map(|(u, _)| u.norm_sqr()).sum();
    if energy <= 0.0 {
        return Err(AnalysisError::NoEnergy { what: "local wavelength estimate" });
    }
    let q_grid = pairs.iter().map(|(u, l)| u.conj() * l).sum::<Complex64>() / energy;
    let bilaplacian_sq: f64 = pairs.iter().map(|(_, l)| l.norm_sqr()).sum();
    let misfit_sq: f64 = pairs.iter().map(|(u, l)| (l - q_grid * u).norm_sqr()).sum();
    let residual = if bilaplacian_sq > 0.0 { (misfit_sq / bilaplacian_sq).sqrt() } else { 0.0 };
    if !(q_grid.re.is_finite() && q_grid.im.is_finite() && residual.is_finite()) {
        return Err(AnalysisError::NonFiniteResult { what: "local wavelength estimate" });
    }
    if q_grid.re <= MIN_K4H4 {
        return Err(AnalysisError::NotAPlateWave {
            what: "local wavelength estimate",
            reason: format!(
                "Re(k^4 h^4) = {:e}, not above {MIN_K4H4:e}: no propagating plate wave over the points used, or one \
                 too long to tell from a static field",
                q_grid.re
            ),
        });
    }
    // Principal fourth root: for a lossy wave q = k^4 with k slightly complex; its real part sets the wavelength.
    let kh_raw = q_grid.powf(0.25).re;
    let kh = correction::invert(kh_raw.powi(4), opts.correction).ok_or_else(|| AnalysisError::NotAPlateWave {
        what: "local wavelength estimate",
        reason: format!("k h = {kh_raw:.3} is beyond the stencil's range (pi): the wave is shorter than 2 grid steps"),
    })?;
    let h = grid.spacing_m;
    let wavenumber_rad_m = kh / h;
    let wavelength_m = 2.0 * std::f64::consts::PI / wavenumber_rad_m;
    let k4_raw = q_grid / h.powi(4);
    if !(wavelength_m.is_finite() && wavenumber_rad_m.is_finite() && k4_raw.re.is_finite() && k4_raw.im.is_finite()) {
        return Err(AnalysisError::NonFiniteResult { what: "local wavelength estimate" });
    }
    Ok(LocalEstimate {
        wavelength_m,
        wavenumber_rad_m,
        k4_raw,
        points_used: used.len(),
        residual,
        flags: LocalFlags { too_short: wavelength_m < MIN_POINTS_PER_WAVELENGTH * h },
    })
}

fn check_inputs(
    field: &[Complex64],
    mask: &[bool],
    grid: &GridSpec,
    exclusions: &[Exclusion],
    opts: &LocalOptions,
) -> Result<(), AnalysisError> {
    grid.validate().map_err(|e| AnalysisError::InvalidParameter { name: "grid", reason: e.to_string() })?;
    if field.len() != grid.len() {
        return Err(AnalysisError::LengthMismatch { what: "field against grid points", a: field.len(), b: grid.len() });
    }
    if mask.len() != grid.len() {
        return Err(AnalysisError::LengthMismatch { what: "mask against grid points", a: mask.len(), b: grid.len() });
    }
    if opts.min_points == 0 {
        return Err(AnalysisError::InvalidParameter { name: "min_points", reason: "must be >= 1".to_owned() });
    }
    if let Some(e) = exclusions
        .iter()
        .find(|e| !(e.x_m.is_finite() && e.y_m.is_finite() && e.radius_m.is_finite() && e.radius_m >= 0.0))
    {
        return Err(AnalysisError::InvalidParameter {
            name: "exclusions",
            reason: format!("need finite x_m, y_m and radius_m >= 0, got {e:?}"),
        });
    }
    if let Some(index) = (0..field.len()).find(|&i| mask[i] && !(field[i].re.is_finite() && field[i].im.is_finite())) {
        return Err(AnalysisError::NonFinite { input: "field", index });
    }
    Ok(())
}

//! Plate wavelength from a k-space transform of the field at one frequency (the paper's Wave Field Analysis).
//!
//! The field measured on the grid at one frequency `omega` (one complex value per point: the Green's function of one
//! actuator) is transformed to k-space by a zero-padded 2-D FFT; the energy |G(k)|^2 peaks where the waves carrying
//! the response live. The half-maximum region around that peak gives a distribution of wavelengths 2 pi / |k|, whose
//! median and interquartile range are the estimate for that actuator; [`summarise`] combines actuators.
//!
//! Two ways to take the half-maximum region ([`KSpaceMethod`]): the paper's 2-D contour around the peak bin, and a
//! radial refinement that first averages |G(k)|^2 over angle (see `radial`).
//!
//! Valid range, for a grid of spacing `d` whose longer side measures `L = max(nx, ny) * d`:
//! - wavelengths below `2 d` (the spatial Nyquist limit, `|kx|, |ky| <= pi / d`; `sqrt(2) d` on the diagonal) cannot
//!   be told from longer ones: they alias, silently, since nothing in the samples tells them apart (9 mm on a 5 mm
//!   grid reads as 11.25 mm). An estimate whose region reaches the edge of the k-grid is flagged
//!   ([`EstimateFlags::near_nyquist`]);
//! - wavelengths above about `L / 2` are not resolved by the aperture (its resolution `2 pi / L` in k approaches |k|):
//!   the half-maximum region then spans |k| from near 0 to twice the peak, and the estimate is biased short (median
//!   -4 to -10 % at `0.6 L`, -10 to -20 % at `L`, on plane, cylindrical and reverberant test fields; a shorter
//!   grid side makes waves travelling along it worse). Such estimates are flagged
//!   ([`EstimateFlags::under_resolved`]). Below `L / 2` the measured bias is within about 3 % for plane and
//!   cylindrical waves. A reverberant field (random standing waves) is unbiased on average up to 10 cm, but single
//!   fields scatter (speckle: few independent k-samples): standard deviation 0.3, 1.0, 3.9, 8.4, 12 % at 2.5, 5,
//!   10, 15, 25 cm, with mean bias -2 % at 15 cm and -18 % at 25 cm.
//!   The table comes from `cargo run --release -p metaplate-analysis --example wavelength_bias`.
//!
//! Because of that bias, a second estimator that no aperture limits sits beside it: [`local`], the plate equation's
//! biharmonic Rayleigh quotient ([`estimate_local_wavelength`]), exact in principle for any wavelength in a
//! source-free region of one medium, but sensitive to noise at long wavelengths (see its documentation).
//!
//! Cost: one complex 2-D FFT of `m` x `m` bins with `m = fast_len(zero_pad_factor * max(nx, ny))` (392 x 392 for the
//! 49 x 25 grid padded x8 by default: about 3 M complex multiply-adds, well under 10 ms) plus a few passes over those bins.

mod aperture;
mod contour;
pub mod local;
mod radial;
mod region;
mod spectrum;
pub(crate) mod stats;
mod summary;

pub use aperture::{MAX_POINTS, MAX_SPACING_M, MIN_SPACING_M};
pub use local::{Exclusion, LocalEstimate, LocalFlags, LocalOptions, StencilCorrection, estimate_local_wavelength};
pub use spectrum::MAX_K_BINS;
pub use summary::{AcrossActuators, WavelengthSummary, summarise};

use num_complex::Complex64;

use crate::error::AnalysisError;

/// How the half-maximum region around the k-space peak is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KSpaceMethod {
    /// The paper's method: the peak bin of |G(k)|^2 and the 8-connected region of bins around it at or above half
    /// its value ("the full width at half maximum contour around the peak bin").
    HalfMaxContour,
    /// Refinement: the angular average E(|k|) of |G(k)|^2, its peak, and all bins whose |k| lies in the half-maximum
    /// interval of E around that peak. Tried against the long-wavelength bias; on the test fields it is no better
    /// than the contour (see `examples/wavelength_bias.rs`), so it is not the default.
    RadialProfile,
}

/// How each k-bin of the half-maximum region counts in the wavelength distribution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinWeighting {
    /// Every bin counts once (the region's area in k-space), as the paper's "distribution of wavelengths" reads.
    Uniform,
    /// Each bin counts with its energy |G(k)|^2.
    Energy,
}

/// Options of [`estimate_wavelength`]. The default is the paper's method (contour, every bin counted once, mean
/// removed, no taper) with zero padding x8, fine enough that the contour's median does not step with the bin grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KSpaceOptions {
    /// Zero padding: the k-grid has `fast_len(zero_pad_factor * max(nx, ny))` bins per resolved axis. Padding adds no
    /// resolution (that is set by the aperture) but samples the spectrum finely enough to place the peak and the
    /// contour. Valid range 1 to 64.
    pub zero_pad_factor: usize,
    /// Width (m) of the raised-cosine taper applied inward from the edge of the measured region (mask edges and
    /// grid border alike). 0 means no taper. A taper lowers side lobes but widens the main lobe: 2 cm on the lab
    /// grid roughly doubled the bias at 25 cm, so the default is 0. Valid: finite, >= 0.
    pub taper_width_m: f64,
    /// Remove the (taper-weighted) mean over the measured points first, so that a rigid-body component does not
    /// leak around k = 0.
    pub remove_mean: bool,
    /// Bins with |k| below this (rad/m) are neither a peak candidate nor part of a region. `None` takes
    /// `pi / L` (L the grid's longer side), i.e. excludes wavelengths above twice the aperture. Valid: finite, >= 0.
    pub min_k_rad_m: Option<f64>,
    /// Which half-maximum region.
    pub method: KSpaceMethod,
    /// How bins of the region weigh in the median and quartiles.
    pub weighting: BinWeighting,
}

impl Default for KSpaceOptions {
    fn default() -> Self {
        Self {
            zero_pad_factor: 8,
            taper_width_m: 0.0,
            remove_mean: true,
            min_k_rad_m: None,
            method: KSpaceMethod::HalfMaxContour,
            weighting: BinWeighting::Uniform,
        }
    }
}

/// Where an estimate lies relative to the estimator's valid range. All `false` means inside it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EstimateFlags {
    /// The peak or median wavelength exceeds half the grid's longer side: the aperture does not resolve it, and the
    /// estimate is biased short (see the module documentation).
    pub under_resolved: bool,
    /// The half-maximum region reaches the spatial Nyquist limit (wavelength near `2 * spacing`): shorter waves
    /// may be aliased into it.
    pub near_nyquist: bool,
    /// The half-maximum region runs into the excluded neighbourhood of k = 0: its long-wavelength side is cut.
    pub touches_dc_exclusion: bool,
}

impl EstimateFlags {
    /// Whether the estimate lies inside the valid range (no flag raised).
    pub fn in_range(&self) -> bool {
        !(self.under_resolved || self.near_nyquist || self.touches_dc_exclusion)
    }
}

/// A wavelength estimate for one field (one actuator, one frequency).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WavelengthEstimate {
    /// Wavelength (m) of the k-space peak, refined below the bin spacing.
    pub peak_m: f64,
    /// Median (m) of the wavelength distribution over the half-maximum region.
    pub median_m: f64,
    /// Interquartile range (m) of that distribution: (25th, 75th percentile).
    pub iqr_m: (f64, f64),
    /// Number of k-bins in the half-maximum region.
    pub bins_in_contour: usize,
    /// Range flags.
    pub flags: EstimateFlags,
}

/// Estimates the wavelength carrying the dominant energy of `field`.
///
/// `field`: one complex value per grid point at one frequency, row-major (`index = iy * nx + ix`), any unit.
/// `mask`: `true` where the point was measured; unmeasured points are ignored (they may hold NaN) and set to zero
/// after the mean over the measured points is removed. `spacing_m`: grid step in metres, the same along x and y,
/// [`MIN_SPACING_M`] to [`MAX_SPACING_M`].
/// A line scan (`nx` or `ny` = 1) is accepted: it measures the wavelength of the wave's trace along the line, which
/// is longer than the wavelength when waves cross the line obliquely.
///
/// # Errors
/// - [`AnalysisError::LengthMismatch`]: `field` or `mask` is not `nx * ny` long;
/// - [`AnalysisError::InvalidParameter`]: `nx` or `ny` is 0, `spacing_m` is outside its range, or an option is
///   out of its stated range;
/// - [`AnalysisError::NonFinite`]: a measured point holds NaN or an infinity;
/// - [`AnalysisError::TooFewPoints`]: fewer than 2 points are measured;
/// - [`AnalysisError::NoEnergy`]: the field is zero (or constant, with mean removal) over the measured points, or
///   all its energy lies at |k| below the DC exclusion;
/// - [`AnalysisError::TooLarge`]: more than [`MAX_POINTS`] grid points or [`MAX_K_BINS`] k-bins.
pub fn estimate_wavelength(
    field: &[Complex64],
    mask: &[bool],
    nx: usize,
    ny: usize,
    spacing_m: f64,
    opts: &KSpaceOptions,
) -> Result<WavelengthEstimate, AnalysisError> {
    check_options(opts)?;
    let aperture = aperture::prepare(field, mask, nx, ny, spacing_m, opts.taper_width_m, opts.remove_mean)?;
    let aperture_m = nx.max(ny) as f64 * spacing_m;
    let min_k_rad_m = opts.min_k_rad_m.unwrap_or(std::f64::consts::PI / aperture_m);
    let map = spectrum::power_map(&aperture.values, nx, ny, spacing_m, opts.zero_pad_factor)?;
    let region = match opts.method {
        KSpaceMethod::HalfMaxContour => contour::half_max_contour(&map, min_k_rad_m),
        KSpaceMethod::RadialProfile => radial::radial_half_max(&map, min_k_rad_m, std::f64::consts::PI / spacing_m),
    }
    .ok_or(AnalysisError::NoEnergy { what: "wavelength estimate" })?;

    let (lambdas, powers): (Vec<f64>, Vec<f64>) = region.samples.iter().copied().unzip();
    let weights = match opts.weighting {
        BinWeighting::Uniform => vec![1.0; lambdas.len()],
        BinWeighting::Energy => powers,
    };
    let q = stats::weighted_quantiles(&lambdas, &weights, &[0.25, 0.5, 0.75])
        .ok_or(AnalysisError::NoEnergy { what: "wavelength estimate" })?;
    let peak_m = 2.0 * std::f64::consts::PI / region.peak_k_rad_m;
    let estimate = WavelengthEstimate {
        peak_m,
        median_m: q[1],
        iqr_m: (q[0], q[2]),
        bins_in_contour: region.samples.len(),
        flags: EstimateFlags {
            under_resolved: peak_m.max(q[1]) > 0.5 * aperture_m,
            near_nyquist: region.touches_nyquist,
            touches_dc_exclusion: region.touches_dc,
        },
    };
    if [estimate.peak_m, estimate.median_m, q[0], q[2]].iter().all(|v| v.is_finite() && *v > 0.0) {
        Ok(estimate)
    } else {
        Err(AnalysisError::NonFiniteResult { what: "wavelength estimate" })
    }
}

fn check_options(opts: &KSpaceOptions) -> Result<(), AnalysisError> {
    if !(1..=64).contains(&opts.zero_pad_factor) {
        return Err(AnalysisError::InvalidParameter {
            name: "zero_pad_factor",
            reason: format!("must be 1 to 64, got {}", opts.zero_pad_factor),
        });
    }
    if let Some(k) = opts.min_k_rad_m
        && !(k.is_finite() && k >= 0.0)
    {
        return Err(AnalysisError::InvalidParameter {
            name: "min_k_rad_m",
            reason: format!("must be finite and >= 0, got {k}"),
        });
    }
    Ok(())
}

//! The plate: outline, thickness, material and loss; thin-plate (Kirchhoff) A0 dispersion.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::error::SceneError;
use super::outline::Outline;

/// A thin, homogeneous, isotropic plate.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): finite `thickness_m > 0` and below a tenth of the
/// outline's smallest dimension (thin-plate theory; also catches millimetres typed as metres);
/// `1e5 <= youngs_modulus_pa <= 1e12`; `-1 < poisson_ratio < 0.5`; `10 <= density_kg_m3 <= 1e5`;
/// `0 <= loss_factor <= 1`. The ranges bracket every solid a plate is made of, so a value outside them is almost
/// always a unit mistake (GPa for Pa, g/cm^3 for kg/m^3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSpec {
    /// Shape seen from above.
    pub outline: Outline,
    /// Thickness h, m.
    pub thickness_m: f64,
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio nu (dimensionless).
    pub poisson_ratio: f64,
    /// Density rho, kg/m^3.
    pub density_kg_m3: f64,
    /// Structural loss factor eta (dimensionless): the imaginary part of the complex modulus E (1 + i eta).
    pub loss_factor: f64,
}

impl PlateSpec {
    /// Bending stiffness `D = E h^3 / (12 (1 - nu^2))`, N m. Finite and positive for a plate in the valid range.
    pub fn bending_stiffness_n_m(&self) -> f64 {
        self.youngs_modulus_pa * self.thickness_m.powi(3) / (12.0 * (1.0 - self.poisson_ratio.powi(2)))
    }

    /// Mass per unit area `rho h`, kg/m^2.
    pub fn mass_per_area_kg_m2(&self) -> f64 {
        self.density_kg_m3 * self.thickness_m
    }

    /// Wavenumber of the lossless A0 (flexural) wave at `freq_hz`, rad/m, from `D k^4 = rho h omega^2`.
    ///
    /// Valid range: finite `freq_hz >= 0` (0 Hz gives k = 0), on a plate in its valid range.
    ///
    /// # Errors
    /// [`SceneError::InvalidArgument`] for a negative or non-finite frequency, or when the plate's parameters make
    /// the result non-finite (an unvalidated plate).
    pub fn a0_wavenumber_rad_m(&self, freq_hz: f64) -> Result<f64, SceneError> {
        if !(freq_hz.is_finite() && freq_hz >= 0.0) {
            return Err(SceneError::invalid_argument("freq_hz", format!("must be finite and >= 0, got {freq_hz}")));
        }
        // k = sqrt(2 pi) sqrt(f) (rho h / D)^(1/4): the same as (rho h omega^2 / D)^(1/4), but omega^2 would
        // underflow to 0 below ~1e-154 Hz and overflow above ~1e153 Hz; this is finite for every finite f.
        let k =
            (2.0 * PI).sqrt() * freq_hz.sqrt() * (self.mass_per_area_kg_m2() / self.bending_stiffness_n_m()).powf(0.25);
        if k.is_finite() {
            Ok(k)
        } else {
            Err(SceneError::invalid_argument("plate", "its parameters give a non-finite wavenumber".to_owned()))
        }
    }

    /// Wavelength of the lossless A0 wave at `freq_hz`, `2 pi / k`, m.
    ///
    /// Valid range: finite `freq_hz > 0` (the wavelength is infinite at 0 Hz), on a plate in its valid range.
    ///
    /// # Errors
    /// As [`PlateSpec::a0_wavenumber_rad_m`], and for `freq_hz == 0`.
    pub fn a0_wavelength_m(&self, freq_hz: f64) -> Result<f64, SceneError> {
        let k = self.a0_wavenumber_rad_m(freq_hz)?;
        let lambda = 2.0 * PI / k;
        if lambda.is_finite() {
            Ok(lambda)
        } else {
            Err(SceneError::invalid_argument("freq_hz", format!("must be > 0 for a finite wavelength, got {freq_hz}")))
        }
    }
}

//! Proper orthogonal decomposition (POD) of the actuator-summed response: how many spatial patterns carry the
//! plate's response (the paper's "spatial response dimensionality", Fig. 6A: 23 components for 99 % of the
//! variance on the metamaterial plate, 11 on the homogeneous one).
//!
//! Definition (paper, Wave Field Analysis): `h(x, t) = sum_i g_i(x, t)` over the actuators, band-limited to the
//! operating band, gathered over every measured point into a matrix `H` (points x time) and decomposed as
//! `H = U S V^T`; the squared singular values are the variance each spatial component (column of `U`) carries.
//!
//! Computed in the frequency domain: for a real signal band-limited to bins `k` (no DC, no Nyquist), Parseval gives
//! `H H^T = (2 / N) Re(Hf Hf^H)` with `Hf` the points x bins DFT, so the singular values of `H` are `sqrt(2 / N)`
//! times those of the real matrix `[Re Hf, Im Hf]` (points x 2 bins). That is exactly the time-domain POD of `h`
//! filtered by an ideal (brick-wall) band-pass on the DFT's period, at a fraction of the cost (hundreds of columns
//! instead of thousands of samples). The energy fractions reported do not depend on the scale.

use faer::Mat;
use metaplate_control::PropagationMatrices;

use crate::bands::{OPERATING_BAND_HZ, bins_in_band};
use crate::error::AnalysisError;
use crate::linalg::singular_values_real;

/// Options of [`pod`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PodOptions {
    /// Band over which `h` is kept, Hz (default: the operating band, 75 to 400 Hz).
    pub band_hz: (f64, f64),
    /// Fraction of the total energy the counted components must capture, in (0, 1] (default 0.99, the paper's).
    pub energy_fraction: f64,
}

impl Default for PodOptions {
    fn default() -> Self {
        Self { band_hz: OPERATING_BAND_HZ, energy_fraction: 0.99 }
    }
}

/// The POD spectrum of the actuator-summed response.
#[derive(Debug, Clone, PartialEq)]
pub struct Pod {
    /// Energy of each component as a fraction of the total, `sigma_i^2 / sum sigma^2`, non-increasing; as many as
    /// `min(points, 2 * bins)`. Sums to 1.
    pub energy: Vec<f64>,
    /// Smallest number of leading components whose energies add up to at least [`PodOptions::energy_fraction`].
    pub components: usize,
}

impl Pod {
    /// Smallest `n` such that the first `n` energies add up to at least `fraction` of the total (`fraction` is
    /// clamped to [0, 1]; 0 gives 0, 1 gives every component up to the last one with non-zero energy).
    pub fn components_for(&self, fraction: f64) -> usize {
        components_for(&self.energy, fraction)
    }
}

/// POD of `h = sum_i g_i` over every point of `g` (see the module documentation).
///
/// Valid range: `g` with at least one bin in `opts.band_hz`; `opts.energy_fraction` in (0, 1]. Cost: one SVD of a
/// `points x 2 bins` real matrix (about 950 x 330 for the paper's grid and a 0.5 s response: well under a second).
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for an energy fraction outside (0, 1] or a band holding none of `g`'s bins;
/// [`AnalysisError::NoEnergy`] when `h` is zero over the band; [`AnalysisError::NonFiniteResult`] if the SVD fails.
pub fn pod(g: &PropagationMatrices, opts: &PodOptions) -> Result<Pod, AnalysisError> {
    if !(opts.energy_fraction > 0.0 && opts.energy_fraction <= 1.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "energy_fraction",
            reason: format!("must lie in (0, 1], got {}", opts.energy_fraction),
        });
    }
    let bins = bins_in_band(g, opts.band_hz)?;
    let (m, n_act) = (g.n_points(), g.n_actuators());
    let mut h = Mat::<f64>::zeros(m, 2 * bins.len());
    for (c, &k) in bins.iter().enumerate() {
        let Some(gk) = g.at_bin(k) else { continue };
        for row in 0..m {
            let sum: num_complex::Complex64 = (0..n_act).map(|a| gk[(row, a)]).sum();
            h[(row, 2 * c)] = sum.re;
            h[(row, 2 * c + 1)] = sum.im;
        }
    }
    let sigma = singular_values_real(h.as_ref(), "POD singular values")?;
    let total: f64 = sigma.iter().map(|s| s * s).sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(AnalysisError::NoEnergy { what: "POD" });
    }
    let energy: Vec<f64> = sigma.iter().map(|s| s * s / total).collect();
    let components = components_for(&energy, opts.energy_fraction);
    Ok(Pod { energy, components })
}

/// Smallest `n` whose leading `n` fractions reach `fraction` of their sum.
fn components_for(energy: &[f64], fraction: f64) -> usize {
    let total: f64 = energy.iter().sum();
    let target = fraction.clamp(0.0, 1.0) * total;
    let mut cumulative = 0.0;
    for (i, e) in energy.iter().enumerate() {
        if cumulative >= target {
            return i;
        }
        cumulative += e;
    }
    energy.len()
}

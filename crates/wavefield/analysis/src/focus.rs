//! Single-pixel focusing as the analyses need it: the drive that focuses a band-limited impulse on one point, the
//! transfer it achieves there, and snapshots of the focused field.
//!
//! For one pixel `x0` with propagation vector `g(omega)` (1 x N actuators) both focusing laws drive
//! `a(omega) = conj(g(omega)) c(omega) s(omega)`, `s` the target's spectrum and `c` a real, positive scale:
//! - the Tikhonov-regularised inverse filter of the paper's Eq., solved by `metaplate-control`
//!   ([`metaplate_control::solve::single_pixel_gain`], the one-pixel case of its SVD solver) with an absolute
//!   `alpha^2` = `relative_regularisation` times the band mean of `|g|^2`, so that it scales with the plate:
//!   `c = 1 / (|g|^2 + alpha^2)`;
//! - time reversal: the matched filter `conj(g)` normalised to unit mean focus gain over the band,
//!   `c = 1 / mean(|g|^2)`.
//!
//! The field at the pixel is then `v(x0, omega) = F(omega) s(omega)` with the focal transfer `F = |g|^2 c`, real and
//! >= 0: the focused signal is the target passed through a zero-phase filter, symmetric about the focus time.

use metaplate_control::PropagationMatrices;
use metaplate_control::solve::{Regularisation, single_pixel_gain};
use metaplate_dsp::band::BandLimit;
use num_complex::Complex64;

use crate::error::AnalysisError;

/// How the drive that focuses on one pixel is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FocusMethod {
    /// Regularised inverse filter, `alpha^2 = relative_regularisation * mean |g|^2`. Valid: finite, >= 0 (0: the
    /// exact inverse, `F = 1` wherever `g` is non-zero).
    InverseFilter {
        /// `alpha^2` relative to the band mean of `|g|^2`.
        relative_regularisation: f64,
    },
    /// Time reversal (phase conjugation), normalised to unit mean focus gain.
    TimeReversal,
}

impl Default for FocusMethod {
    /// The inverse filter with `alpha^2` at 1 % of the mean `|g|^2` (-20 dB): bins 20 dB weaker than average get
    /// half the target's amplitude instead of a 100-fold drive.
    fn default() -> Self {
        FocusMethod::InverseFilter { relative_regularisation: 1e-2 }
    }
}

/// A band-limited impulse's bins in `g`: positions into `g`'s bins and the band's gain there.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] when the band is invalid, or has non-zero gain outside `g`'s bins (its
/// skirts would be cut off: build `g` over a wider band).
pub fn target_bins(g: &PropagationMatrices, band: &BandLimit) -> Result<Vec<(usize, f64)>, AnalysisError> {
    band.validate()?;
    let freqs = g.freqs_hz();
    let spacing_hz = g.sample_rate_hz() / g.fft_len() as f64;
    let (Some(&first), Some(&last)) = (freqs.first(), freqs.last()) else {
        return Err(AnalysisError::Empty { input: "propagation matrices' bins" });
    };
    let below = first - spacing_hz;
    let above = last + spacing_hz;
    if (below > 0.0 && band.gain(below) > 0.0) || band.gain(above) > 0.0 {
        return Err(AnalysisError::InvalidParameter {
            name: "band",
            reason: format!(
                "{} to {} Hz with its skirts reaches beyond the propagation matrices' bins ({first} to {last} Hz)",
                band.lo_hz, band.hi_hz
            ),
        });
    }
    let bins: Vec<(usize, f64)> =
        freqs.iter().enumerate().map(|(k, &f)| (k, band.gain(f))).filter(|&(_, w)| w > 0.0).collect();
    if bins.is_empty() {
        return Err(AnalysisError::InvalidParameter {
            name: "band",
            reason: "no bin of the propagation matrices has non-zero gain".to_owned(),
        });
    }
    Ok(bins)
}

/// Per bin of `bins` (positions into `g`'s bins): the drive scale `c` of the module documentation for focusing on
/// row `row` of `g`, and the focal transfer `F = |g|^2 c` (real, >= 0).
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for a row past the last point or a regularisation outside its range;
/// [`AnalysisError::NoEnergy`] when `g` is zero at the pixel over every bin.
pub fn focal_scale(
    g: &PropagationMatrices,
    row: usize,
    bins: &[usize],
    method: FocusMethod,
) -> Result<Vec<(f64, f64)>, AnalysisError> {
    if row >= g.n_points() {
        return Err(AnalysisError::InvalidParameter {
            name: "row",
            reason: format!("{row} is not below the {} points", g.n_points()),
        });
    }
    let norms: Vec<f64> = bins
        .iter()
        .map(|&k| g.at_bin(k).map_or(0.0, |gk| (0..g.n_actuators()).map(|a| gk[(row, a)].norm_sqr()).sum()))
        .collect();
    let mean_norm = norms.iter().sum::<f64>() / norms.len().max(1) as f64;
    if !(mean_norm > 0.0 && mean_norm.is_finite()) {
        return Err(AnalysisError::NoEnergy { what: "focusing (the pixel's response is zero)" });
    }
    // `None`: time reversal, whose scale is the band constant `1 / mean |g|^2`.
    let inverse = match method {
        FocusMethod::InverseFilter { relative_regularisation: beta } => {
            if !(beta.is_finite() && beta >= 0.0) {
                return Err(AnalysisError::InvalidParameter {
                    name: "relative_regularisation",
                    reason: format!("must be finite and >= 0, got {beta}"),
                });
            }
            Some(Regularisation::Absolute((beta * mean_norm).sqrt()))
        }
        FocusMethod::TimeReversal => None,
    };
    Ok(norms
        .iter()
        .map(|&n| {
            let c = inverse.map_or(1.0 / mean_norm, |reg| single_pixel_gain(n, reg));
            (c, n * c)
        })
        .collect())
}

/// The focused field at every point of `g` at time `tau_s` after the focus time, for a band-limited impulse target
/// `band` focused on row `row` by `method`: `v(x, T + tau) = (2 / L) sum_k w_k Re(v(x, omega_k) e^{i omega_k tau})`
/// with `L = g.fft_len()`, `w_k` the band's gain (the target's spectrum, unit magnitude in the band as
/// [`metaplate_dsp::impulse::band_limited_impulse`]) and `v = G a`. Units: those of `g` times the target's.
///
/// Valid range: `tau_s` finite (the field is periodic with the DFT's period, `fft_len / sample_rate_hz`).
///
/// # Errors
/// As [`target_bins`] and [`focal_scale`]; [`AnalysisError::InvalidParameter`] for a non-finite `tau_s`.
pub fn focus_snapshot(
    g: &PropagationMatrices,
    row: usize,
    band: &BandLimit,
    method: FocusMethod,
    tau_s: f64,
) -> Result<Vec<f64>, AnalysisError> {
    if !tau_s.is_finite() {
        return Err(AnalysisError::InvalidParameter { name: "tau_s", reason: format!("must be finite, got {tau_s}") });
    }
    let target = target_bins(g, band)?;
    let bins: Vec<usize> = target.iter().map(|&(k, _)| k).collect();
    let scales = focal_scale(g, row, &bins, method)?;
    let mut field = vec![0.0; g.n_points()];
    let norm = 2.0 / g.fft_len() as f64;
    for (&(k, w), &(c, _)) in target.iter().zip(&scales) {
        let Some(gk) = g.at_bin(k) else { continue };
        let phase = Complex64::from_polar(w * c * norm, 2.0 * std::f64::consts::PI * g.freqs_hz()[k] * tau_s);
        let drive: Vec<Complex64> = (0..g.n_actuators()).map(|a| gk[(row, a)].conj() * phase).collect();
        for (m, v) in field.iter_mut().enumerate() {
            *v += (0..g.n_actuators()).map(|a| gk[(m, a)] * drive[a]).sum::<Complex64>().re;
        }
    }
    Ok(field)
}

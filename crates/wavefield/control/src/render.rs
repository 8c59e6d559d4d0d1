//! From targets to drive signals and predicted fields.
//!
//! [`solve_drives`] solves every bin of the band for the pixels' targets; [`DriveSpectra::signals`] turns the
//! solution into one period of each actuator's drive; [`compensate`] runs each through its actuator's Kirkeby inverse
//! filter (the signal the audio interface plays); [`normalise_peak`] scales to full scale and reports the peak;
//! [`predicted_field`] gives `v(x, t)` from the dataset (`G a`, before compensation: the Green's functions were
//! measured through calibrated actuators).

use faer::Mat;
use num_complex::Complex64;

use metaplate_dsp::kirkeby::KirkebyFilter;

use crate::error::ControlError;
use crate::propagation::PropagationMatrices;
use crate::solve::{Method, Regularisation, solve_bin};
use crate::target::{PixelTarget, TargetBand, spectrum};

/// How drives are solved.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FocusOptions {
    /// Tikhonov regularisation.
    pub regularisation: Regularisation,
    /// Inverse filtering or time reversal.
    pub method: Method,
    /// Target band-limiting.
    pub target_band: TargetBand,
}

/// Drive spectra at `g`'s bins: `a[k * n_actuators + j]` for bin `k`, actuator column `j`.
#[derive(Debug, Clone)]
pub struct DriveSpectra {
    /// Number of actuators.
    pub n_actuators: usize,
    /// Spectra, bin-major.
    pub a: Vec<Complex64>,
}

/// Solves the drives for `targets` (one pixel each; at least 1, any number, also more than actuators) over every bin
/// of `g`.
///
/// # Errors
/// [`ControlError::Empty`] for no target, [`ControlError::UnknownPoint`] for a pixel outside `g`, and the errors
/// of [`spectrum`] and [`solve_bin`].
pub fn solve_drives(
    g: &PropagationMatrices,
    targets: &[PixelTarget],
    options: &FocusOptions,
) -> Result<DriveSpectra, ControlError> {
    if targets.is_empty() {
        return Err(ControlError::Empty { input: "pixel targets" });
    }
    let rows: Vec<usize> = targets
        .iter()
        .map(|t| g.row_of(t.point_index).ok_or(ControlError::UnknownPoint { point_index: t.point_index }))
        .collect::<Result<_, _>>()?;
    let gains = options.target_band.gains(g)?;
    let spectra: Vec<Vec<Complex64>> = targets.iter().map(|t| spectrum(t, g, &gains)).collect::<Result<_, _>>()?;
    let n = g.n_actuators();
    let mut a = Vec::with_capacity(g.n_bins() * n);
    let mut g_c = Mat::<Complex64>::zeros(rows.len(), n);
    for k in 0..g.n_bins() {
        let Some(gk) = g.at_bin(k) else { break };
        for (r, &row) in rows.iter().enumerate() {
            for j in 0..n {
                g_c[(r, j)] = gk[(row, j)];
            }
        }
        let v_c: Vec<Complex64> = spectra.iter().map(|s| s[k]).collect();
        a.extend(solve_bin(g_c.as_ref(), &v_c, options.regularisation, options.method)?);
    }
    Ok(DriveSpectra { n_actuators: n, a })
}

impl DriveSpectra {
    /// One period (`g.fft_len()` samples) of each actuator's drive, in actuator order of `g`.
    ///
    /// # Errors
    /// [`ControlError::LengthMismatch`] when the spectra do not fit `g`.
    pub fn signals(&self, g: &PropagationMatrices) -> Result<Vec<Vec<f64>>, ControlError> {
        self.check(g)?;
        (0..self.n_actuators)
            .map(|j| {
                let band: Vec<Complex64> = self.a.chunks_exact(self.n_actuators).map(|bin| bin[j]).collect();
                crate::target::band_signal(&band, g)
            })
            .collect()
    }

    fn check(&self, g: &PropagationMatrices) -> Result<(), ControlError> {
        let expected = g.n_bins() * g.n_actuators();
        if self.n_actuators != g.n_actuators() || self.a.len() != expected {
            return Err(ControlError::LengthMismatch {
                what: "drive spectra against bins x actuators",
                a: self.a.len(),
                b: expected,
            });
        }
        Ok(())
    }
}

/// Runs each drive through its actuator's Kirkeby inverse filter (full linear convolution, so each channel grows by
/// the filter length minus 1; shorter channels are zero-padded to the longest).
///
/// # Errors
/// [`ControlError::LengthMismatch`] when the counts differ; the filter's DSP errors (empty, non-finite).
pub fn compensate(drives: &[Vec<f64>], filters: &[KirkebyFilter]) -> Result<Vec<Vec<f64>>, ControlError> {
    if drives.len() != filters.len() {
        return Err(ControlError::LengthMismatch {
            what: "drives against Kirkeby filters",
            a: drives.len(),
            b: filters.len(),
        });
    }
    let mut out: Vec<Vec<f64>> = drives.iter().zip(filters).map(|(d, f)| f.apply(d)).collect::<Result<_, _>>()?;
    let len = out.iter().map(Vec::len).max().unwrap_or(0);
    for channel in &mut out {
        channel.resize(len, 0.0);
    }
    Ok(out)
}

/// Scales all channels by one factor so that the largest absolute sample is `full_scale`; returns the peak before
/// scaling and the factor applied. All-zero drives (every target null) stay zero, with peak 0 and factor 0.
///
/// Valid range: finite samples, finite `full_scale > 0`.
///
/// # Errors
/// [`ControlError::InvalidParameter`] for `full_scale`, [`ControlError::NonFinite`] for a sample.
pub fn normalise_peak(drives: &mut [Vec<f64>], full_scale: f64) -> Result<(f64, f64), ControlError> {
    if !(full_scale.is_finite() && full_scale > 0.0) {
        return Err(ControlError::InvalidParameter {
            name: "full_scale",
            reason: format!("must be finite and positive, got {full_scale}"),
        });
    }
    for channel in drives.iter() {
        crate::error::check_finite("drive signal", channel.iter().copied())?;
    }
    let peak = drives.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()));
    if peak == 0.0 {
        return Ok((0.0, 0.0));
    }
    let factor = full_scale / peak;
    for v in drives.iter_mut().flatten() {
        *v *= factor;
    }
    Ok((peak, factor))
}

/// The predicted field `v(x, t)` over one period at `rows` of `g` (all points when `None`), scaled by `scale` (the
/// factor [`normalise_peak`] applied): `rows.len() x fft_len`, row-major, units of `G` times drive units.
///
/// # Errors
/// [`ControlError::LengthMismatch`] for spectra that do not fit `g`, [`ControlError::InvalidParameter`] for a row.
pub fn predicted_field(
    g: &PropagationMatrices,
    drives: &DriveSpectra,
    rows: Option<&[usize]>,
    scale: f64,
) -> Result<Vec<Vec<f64>>, ControlError> {
    drives.check(g)?;
    let all: Vec<usize>;
    let rows = match rows {
        Some(r) => r,
        None => {
            all = (0..g.n_points()).collect();
            &all
        }
    };
    if let Some(&bad) = rows.iter().find(|&&r| r >= g.n_points()) {
        return Err(ControlError::InvalidParameter {
            name: "rows",
            reason: format!("row {bad} >= {} points", g.n_points()),
        });
    }
    let n = g.n_actuators();
    rows.iter()
        .map(|&row| {
            let band: Vec<Complex64> = (0..g.n_bins())
                .map(|k| {
                    let gk = g.at_bin(k);
                    let a = &drives.a[k * n..(k + 1) * n];
                    gk.map_or(Complex64::new(0.0, 0.0), |gk| {
                        (0..n).map(|j| gk[(row, j)] * a[j]).sum::<Complex64>() * scale
                    })
                })
                .collect();
            crate::target::band_signal(&band, g)
        })
        .collect()
}

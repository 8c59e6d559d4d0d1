//! The measured aperture: input checks, mean removal and the taper at the edge of the measured region.

use num_complex::Complex64;

use crate::error::AnalysisError;

/// A grid field made ready for the 2-D FFT: zero where unmeasured, mean-free and tapered where measured, and scaled
/// to a peak magnitude of 1 so that |G(k)|^2 can neither overflow nor underflow whatever the input's units.
pub(crate) struct Aperture {
    /// Row-major values, `iy * nx + ix`.
    pub values: Vec<Complex64>,
}

/// Checks the inputs and prepares the aperture (see [`super::estimate_wavelength`] for the contract).
pub(crate) fn prepare(
    field: &[Complex64],
    mask: &[bool],
    nx: usize,
    ny: usize,
    spacing_m: f64,
    taper_width_m: f64,
    remove_mean: bool,
) -> Result<Aperture, AnalysisError> {
    let n = nx.checked_mul(ny).ok_or(AnalysisError::TooLarge { what: "grid", len: usize::MAX, max: MAX_POINTS })?;
    if nx == 0 || ny == 0 {
        return Err(AnalysisError::InvalidParameter {
            name: "nx, ny",
            reason: format!("must be >= 1, got {nx} x {ny}"),
        });
    }
    if n > MAX_POINTS {
        return Err(AnalysisError::TooLarge { what: "grid", len: n, max: MAX_POINTS });
    }
    if field.len() != n {
        return Err(AnalysisError::LengthMismatch { what: "field against nx * ny", a: field.len(), b: n });
    }
    if mask.len() != n {
        return Err(AnalysisError::LengthMismatch { what: "mask against nx * ny", a: mask.len(), b: n });
    }
    // Any physical grid lies well inside this; outside it 2 pi / (m * spacing) can overflow or lose all precision.
    if !(MIN_SPACING_M..=MAX_SPACING_M).contains(&spacing_m) {
        return Err(AnalysisError::InvalidParameter {
            name: "spacing_m",
            reason: format!("must be {MIN_SPACING_M} to {MAX_SPACING_M} m, got {spacing_m}"),
        });
    }
    if !(taper_width_m.is_finite() && taper_width_m >= 0.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "taper_width_m",
            reason: format!("must be finite and >= 0, got {taper_width_m}"),
        });
    }
    // Unmeasured points may hold anything (NaN is a common placeholder); measured ones must be finite.
    if let Some(index) = (0..n).find(|&i| mask[i] && !(field[i].re.is_finite() && field[i].im.is_finite())) {
        return Err(AnalysisError::NonFinite { input: "field", index });
    }
    let measured = mask.iter().filter(|&&m| m).count();
    if measured < MIN_POINTS {
        return Err(AnalysisError::TooFewPoints { measured, required: MIN_POINTS });
    }

    let weights = taper(mask, nx, ny, spacing_m, taper_width_m);
    // Scale first (by the largest magnitude) so that the sums below cannot overflow for inputs near f64::MAX.
    let scale = (0..n).filter(|&i| mask[i]).map(|i| field[i].norm()).fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(AnalysisError::NoEnergy { what: "wavelength estimate" });
    }
    let scaled: Vec<Complex64> = (0..n).map(|i| if mask[i] { field[i] / scale } else { Complex64::ZERO }).collect();
    // The taper-weighted mean makes the tapered field sum to exactly zero, so G(k = 0) = 0: a rigid-body (piston)
    // component, which is no wave, cannot leak into the k-space neighbourhood of the origin.
    let mean = if remove_mean {
        let weight_sum: f64 = weights.iter().sum();
        scaled.iter().zip(&weights).map(|(v, w)| v * w).sum::<Complex64>() / weight_sum
    } else {
        Complex64::ZERO
    };
    let values: Vec<Complex64> =
        (0..n).map(|i| if mask[i] { (scaled[i] - mean) * weights[i] } else { Complex64::ZERO }).collect();
    // Relative to the unit peak, what is left of a constant field after removing its mean is rounding (~1e-16);
    // anything below 1e-10 cannot be told from that and carries no wave.
    if values.iter().all(|v| v.norm() <= CONSTANT_FIELD_RESIDUAL) {
        return Err(AnalysisError::NoEnergy { what: "wavelength estimate" });
    }
    Ok(Aperture { values })
}

/// The largest grid accepted: 2^20 points (a 1024 x 1024 scan, far beyond any LDV session).
pub const MAX_POINTS: usize = 1 << 20;

/// Smallest grid spacing accepted, m.
pub const MIN_SPACING_M: f64 = 1e-9;

/// Largest grid spacing accepted, m.
pub const MAX_SPACING_M: f64 = 1e6;

/// Largest residual (relative to the field's peak) treated as zero after mean removal.
const CONSTANT_FIELD_RESIDUAL: f64 = 1e-10;

/// Fewest measured points: one point has no spatial structure at all.
const MIN_POINTS: usize = 2;

/// Taper weights: 0 where unmeasured; a raised-cosine ramp from the edge of the measured region over
/// `taper_width_m`, 1 further in. The distance is the Euclidean distance to the nearest unmeasured point, counting
/// the ring of points just outside the grid as unmeasured, so that the taper follows any mask shape (a stadium, a
/// support hole), not only the grid's rectangle.
fn taper(mask: &[bool], nx: usize, ny: usize, spacing_m: f64, taper_width_m: f64) -> Vec<f64> {
    let unmeasured = |ix: isize, iy: isize| {
        ix < 0 || iy < 0 || ix >= nx as isize || iy >= ny as isize || !mask[iy as usize * nx + ix as usize]
    };
    // Only unmeasured points within the ramp matter; search a window of that radius (+1 for the grid border).
    let reach = (taper_width_m / spacing_m).ceil().min((nx.max(ny) + 1) as f64) as isize;
    let mut weights = vec![0.0; mask.len()];
    for iy in 0..ny as isize {
        for ix in 0..nx as isize {
            let i = iy as usize * nx + ix as usize;
            if !mask[i] {
                continue;
            }
            let mut nearest_sq = f64::INFINITY;
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    if unmeasured(ix + dx, iy + dy) {
                        nearest_sq = nearest_sq.min((dx * dx + dy * dy) as f64);
                    }
                }
            }
            let distance_m = nearest_sq.sqrt() * spacing_m;
            weights[i] = if distance_m >= taper_width_m {
                1.0
            } else {
                0.5 * (1.0 - (std::f64::consts::PI * distance_m / taper_width_m).cos())
            };
        }
    }
    weights
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn taper_is_one_inside_and_ramps_at_mask_edges() {
        let (nx, ny) = (11, 11);
        let mut mask = vec![true; nx * ny];
        mask[5 * nx + 5] = false; // a hole in the middle (a support)
        let w = taper(&mask, nx, ny, 1.0, 3.0);
        assert_eq!(w[5 * nx + 5], 0.0);
        // One step from the hole or the border: 0.5 (1 - cos(pi / 3)) = 0.25.
        assert!((w[5 * nx + 6] - 0.25).abs() < 1e-12);
        assert!((w[0] - 0.25).abs() < 1e-12);
        // Three or more steps from any unmeasured point: untouched.
        assert_eq!(w[2 * nx + 2], 1.0);
        // No taper: every measured point weighs 1.
        assert!(taper(&mask, nx, ny, 1.0, 0.0).iter().zip(&mask).all(|(w, m)| *w == if *m { 1.0 } else { 0.0 }));
    }
}

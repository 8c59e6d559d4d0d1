//! The k-space power map |G(k)|^2 of a prepared aperture: a zero-padded complex 2-D FFT, centred (fft-shifted).

use num_complex::Complex64;
use rustfft::FftPlanner;

use crate::error::AnalysisError;
use metaplate_dsp::fft::fast_len;

/// The largest k-grid accepted, in bins: 2^24 (128 MiB of `f64` power, twice that of complex spectrum).
pub const MAX_K_BINS: usize = 1 << 24;

/// |G(k)|^2 on a centred k-grid. Bin `(sx, sy)` (index `sy * mx + sx`) sits at
/// `kx = (sx - mx / 2) * dk_rad_m`, `ky = (sy - my / 2) * dk_rad_m`: k = 0 is at `(mx / 2, my / 2)`.
pub(crate) struct PowerMap {
    pub mx: usize,
    pub my: usize,
    /// Bin spacing in rad/m, the same along both axes (square bins make angular and radial sums unbiased).
    pub dk_rad_m: f64,
    pub power: Vec<f64>,
}

impl PowerMap {
    /// Wave-vector components (rad/m) of bin `(sx, sy)`.
    pub fn k_of(&self, sx: usize, sy: usize) -> (f64, f64) {
        ((sx as f64 - (self.mx / 2) as f64) * self.dk_rad_m, (sy as f64 - (self.my / 2) as f64) * self.dk_rad_m)
    }

    /// Whether `(sx, sy)` lies on the outer edge of the k-grid (the spatial Nyquist limit) along a resolved axis.
    pub fn on_edge(&self, sx: usize, sy: usize) -> bool {
        (self.mx > 1 && (sx == 0 || sx + 1 == self.mx)) || (self.my > 1 && (sy == 0 || sy + 1 == self.my))
    }
}

/// Zero-pads the `nx` x `ny` aperture to `m` x `m` (or `m` x 1 / 1 x `m` for a line scan), `m` the smallest fast
/// FFT length >= `zero_pad_factor * max(nx, ny)`, transforms, and returns |G|^2 centred.
pub(crate) fn power_map(
    values: &[Complex64],
    nx: usize,
    ny: usize,
    spacing_m: f64,
    zero_pad_factor: usize,
) -> Result<PowerMap, AnalysisError> {
    let m = fast_len(nx.max(ny).saturating_mul(zero_pad_factor))?;
    // A line scan carries no information across the line: keep that axis at one bin (k = 0) instead of padding it.
    let mx = if nx > 1 { m } else { 1 };
    let my = if ny > 1 { m } else { 1 };
    let bins = mx.checked_mul(my).filter(|&b| b <= MAX_K_BINS).ok_or(AnalysisError::TooLarge {
        what: "k-grid",
        len: mx.saturating_mul(my),
        max: MAX_K_BINS,
    })?;
    let mut grid = vec![Complex64::ZERO; bins];
    for iy in 0..ny {
        grid[iy * mx..iy * mx + nx].copy_from_slice(&values[iy * nx..(iy + 1) * nx]);
    }
    let mut planner = FftPlanner::<f64>::new();
    if mx > 1 {
        // Rows: only the first ny rows hold data; the padding rows transform to zero.
        let fft = planner.plan_fft_forward(mx);
        fft.process(&mut grid[..ny * mx]);
    }
    if my > 1 {
        let fft = planner.plan_fft_forward(my);
        let mut column = vec![Complex64::ZERO; my];
        for sx in 0..mx {
            for (sy, c) in column.iter_mut().enumerate() {
                *c = grid[sy * mx + sx];
            }
            fft.process(&mut column);
            for (sy, c) in column.iter().enumerate() {
                grid[sy * mx + sx] = *c;
            }
        }
    }
    // Centre: FFT index (s + m - m / 2) % m holds the frequency of centred index s.
    let mut power = vec![0.0; bins];
    for sy in 0..my {
        let fy = (sy + my - my / 2) % my;
        for sx in 0..mx {
            let fx = (sx + mx - mx / 2) % mx;
            power[sy * mx + sx] = grid[fy * mx + fx].norm_sqr();
        }
    }
    if power.iter().any(|p| !p.is_finite()) {
        return Err(AnalysisError::NonFiniteResult { what: "k-space power map" });
    }
    let dk_rad_m = 2.0 * std::f64::consts::PI / (m as f64 * spacing_m);
    Ok(PowerMap { mx, my, dk_rad_m, power })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn plane_wave_on_a_bin_lands_on_that_bin() {
        // 8 x 4 grid, pad factor 1 -> 8 x 8 k-grid; e^{i 2 pi (2 ix + 1 iy) / 8} sits at (kx, ky) = (2, 1) bins.
        let (nx, ny) = (8, 4);
        let values: Vec<Complex64> = (0..nx * ny)
            .map(|i| {
                let (ix, iy) = ((i % nx) as f64, (i / nx) as f64);
                Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * (2.0 * ix + iy) / 8.0)
            })
            .collect();
        let map = power_map(&values, nx, ny, 0.5, 1).unwrap();
        assert_eq!((map.mx, map.my), (8, 8));
        let peak = (0..map.power.len()).max_by(|&a, &b| map.power[a].total_cmp(&map.power[b])).unwrap();
        let (kx, ky) = map.k_of(peak % map.mx, peak / map.mx);
        let dk = 2.0 * std::f64::consts::PI / 4.0; // 2 pi / (8 * 0.5 m)
        assert!((kx - 2.0 * dk).abs() < 1e-12 && (ky - dk).abs() < 1e-12, "peak at ({kx}, {ky})");
        // Parseval: the sum of |G|^2 over an mx x my grid is mx * my times the field's energy.
        let energy: f64 = values.iter().map(|v| v.norm_sqr()).sum();
        let total: f64 = map.power.iter().sum();
        assert!((total - 64.0 * energy).abs() < 1e-9 * total);
    }

    #[test]
    fn a_line_scan_keeps_one_bin_across() {
        let values = vec![Complex64::ONE; 5];
        let map = power_map(&values, 5, 1, 0.01, 4).unwrap();
        assert_eq!(map.my, 1);
        assert_eq!(map.mx, 20);
    }
}

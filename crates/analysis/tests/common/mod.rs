//! Synthetic wave fields on the lab's 49 x 25 grid at 5 mm with a stadium-shaped mask, for the wavelength tests.
#![allow(dead_code)] // each test binary uses its own subset

use std::f64::consts::PI;

use num_complex::Complex64;

/// Grid points along x.
pub const NX: usize = 49;
/// Grid points along y.
pub const NY: usize = 25;
/// Grid step, m.
pub const SPACING_M: f64 = 0.005;

/// Centred coordinates (m) of grid point `i`.
pub fn xy_m(i: usize) -> (f64, f64) {
    let (ix, iy) = (i % NX, i / NX);
    ((ix as f64 - (NX / 2) as f64) * SPACING_M, (iy as f64 - (NY / 2) as f64) * SPACING_M)
}

/// Measured points of the 25 x 15 cm stadium plate (straight part 10 cm, end radius 7.5 cm), keeping 5 mm clear of
/// its edge: the rounded ends cut the grid's corners.
pub fn stadium_mask() -> Vec<bool> {
    (0..NX * NY)
        .map(|i| {
            let (x, y) = xy_m(i);
            let along = (x.abs() - 0.05).max(0.0);
            along.hypot(y) <= 0.075 - 0.005
        })
        .collect()
}

/// Plane wave exp(i k . x) of wavelength `lambda_m` travelling at `angle_rad` from the x axis.
pub fn plane_wave(lambda_m: f64, angle_rad: f64) -> Vec<Complex64> {
    let k = 2.0 * PI / lambda_m;
    (0..NX * NY)
        .map(|i| {
            let (x, y) = xy_m(i);
            Complex64::from_polar(1.0, k * (x * angle_rad.cos() + y * angle_rad.sin()))
        })
        .collect()
}

/// Outgoing cylindrical wave exp(i k r) / sqrt(r) from a point source at `(sx_m, sy_m)`. r is floored at 1 / k: a
/// plate's point-force Green's function is finite at its source, and the floor keeps the source point from becoming
/// a one-bin spike that is no wave.
pub fn cylindrical_wave(lambda_m: f64, sx_m: f64, sy_m: f64) -> Vec<Complex64> {
    let k = 2.0 * PI / lambda_m;
    (0..NX * NY)
        .map(|i| {
            let (x, y) = xy_m(i);
            let r = (x - sx_m).hypot(y - sy_m);
            Complex64::from_polar(1.0 / r.max(1.0 / k).sqrt(), k * r)
        })
        .collect()
}

/// A reverberant-plate stand-in: `waves` real standing waves `a_j cos(k . x + phi_j)` with random directions, random
/// phases and Rayleigh-distributed amplitudes, all at the same |k|, drawn from `seed`.
pub fn standing_mixture(lambda_m: f64, waves: usize, seed: u64) -> Vec<Complex64> {
    let k = 2.0 * PI / lambda_m;
    let mut rng = SplitMix64(seed);
    let components: Vec<(f64, f64, f64)> = (0..waves)
        .map(|_| {
            let angle = 2.0 * PI * rng.uniform();
            let phase = 2.0 * PI * rng.uniform();
            let amplitude = (-2.0 * (1.0 - rng.uniform()).ln()).sqrt();
            (angle, phase, amplitude)
        })
        .collect();
    (0..NX * NY)
        .map(|i| {
            let (x, y) = xy_m(i);
            let v: f64 = components
                .iter()
                .map(|(angle, phase, amplitude)| amplitude * (k * (x * angle.cos() + y * angle.sin()) + phase).cos())
                .sum();
            Complex64::new(v, 0.0)
        })
        .collect()
}

/// SplitMix64: a tiny, well-mixed deterministic generator, enough for test fields.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

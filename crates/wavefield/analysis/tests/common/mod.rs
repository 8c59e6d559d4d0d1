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

/// The lab grid as a [`metaplate_core::grid::GridSpec`]: the same points as [`xy_m`].
pub fn grid() -> metaplate_core::grid::GridSpec {
    metaplate_core::grid::GridSpec::centred(NX, NY, SPACING_M)
}

/// Hankel function of the first kind and order zero, `H0(x) = J0(x) + i Y0(x)`, for `x > 0`: the outgoing
/// cylindrical wave of the 2-D Helmholtz equation, hence an exact solution of the plate equation away from its source.
/// Power series below x = 15 (terms reach ~7e4 there, so ~1e-11 absolute error from cancellation), Hankel's
/// asymptotic expansion above (its smallest term, ~e^{-2x}, is below 1e-13 there).
pub fn hankel0(x: f64) -> Complex64 {
    if x < 15.0 {
        let q = x * x / 4.0;
        let (mut term, mut harmonic) = (1.0, 0.0);
        let (mut j0, mut y_sum) = (1.0, 0.0);
        for m in 1..200 {
            term *= -q / (m * m) as f64;
            harmonic += 1.0 / m as f64;
            j0 += term;
            y_sum -= harmonic * term;
            if term.abs() < 1e-18 {
                break;
            }
        }
        const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;
        let y0 = 2.0 / PI * (((x / 2.0).ln() + EULER_GAMMA) * j0 + y_sum);
        Complex64::new(j0, y0)
    } else {
        let mut sum = Complex64::ZERO;
        let mut term = Complex64::ONE;
        for k in 1..60 {
            sum += term;
            let next = term * Complex64::new(0.0, 1.0) * (-((2 * k - 1) as f64).powi(2) / (8.0 * k as f64 * x));
            if next.norm() >= term.norm() || next.norm() < 1e-18 {
                break;
            }
            term = next;
        }
        Complex64::from_polar((2.0 / (PI * x)).sqrt(), x - PI / 4.0) * sum
    }
}

/// Outgoing cylindrical wave `H0(k r)` from a point source at `(sx_m, sy_m)`, an exact solution of the plate equation
/// wherever `r > 0`.
pub fn hankel_wave(lambda_m: f64, sx_m: f64, sy_m: f64) -> Vec<Complex64> {
    let k = 2.0 * PI / lambda_m;
    (0..NX * NY)
        .map(|i| {
            let (x, y) = xy_m(i);
            hankel0(k * (x - sx_m).hypot(y - sy_m))
        })
        .collect()
}

/// Evanescent waves `b_j e^{k (x cos t_j + y sin t_j)}` with `waves` random directions, each scaled to a peak of
/// `b_j` (Rayleigh-distributed) over the grid: boundary layers decaying inward from an edge or a corner, as a free
/// edge makes them. Solutions of `laplacian^2 u = k^4 u` with `laplacian u = + k^2 u`.
pub fn evanescent_mixture(lambda_m: f64, waves: usize, seed: u64) -> Vec<Complex64> {
    let k = 2.0 * PI / lambda_m;
    let mut rng = SplitMix64(seed);
    let mut field = vec![Complex64::ZERO; NX * NY];
    for _ in 0..waves {
        let angle = 2.0 * PI * rng.uniform();
        let amplitude = (-2.0 * (1.0 - rng.uniform()).ln()).sqrt();
        let phase = 2.0 * PI * rng.uniform();
        let along = |i: usize| {
            let (x, y) = xy_m(i);
            x * angle.cos() + y * angle.sin()
        };
        let peak = (0..NX * NY).map(along).fold(f64::NEG_INFINITY, f64::max);
        for (i, v) in field.iter_mut().enumerate() {
            *v += Complex64::from_polar(amplitude * (k * (along(i) - peak)).exp(), phase);
        }
    }
    field
}

//! An independent reference: the plane-wave expansion of a thin (Kirchhoff) plate carrying a square lattice of
//! point spring-mass resonators (Xiao, Wen, Wen, "Flexural wave band gaps in locally resonant thin plates with
//! periodic arrays of spring-mass resonators", J. Sound Vib. 331, 5408-5424, 2012, section 2: the point
//! resonators' dispersion relation).
//!
//! With `w = sum_G W_G exp(i (k + G) r)` and a resonator at each lattice site pulling on the plate with
//! `F = k_s (u - w(0))`, the mass's `-omega^2 m u = -k_s (u - w(0))` gives `F = R(omega) w(0)` with
//! `R = k_s m omega^2 / (k_s - m omega^2)`, and the plate's `(D |k+G|^4 - rho h omega^2) W_G = F / A` summed over
//! G gives the dispersion relation
//! `1 = R(omega) / A * sum_G 1 / (D |k + G|^4 - rho h omega^2)`.
//! The sum converges as |G|^-4: truncating at |n| <= 80 leaves a relative tail below 1e-5.

/// The plate and resonators of the reference.
pub struct PointResonatorPlate {
    /// Flexural rigidity, N m.
    pub d_n_m: f64,
    /// Mass per area, kg/m^2.
    pub rho_h_kg_m2: f64,
    /// Lattice constant, m.
    pub a_m: f64,
    /// Resonator mass, kg.
    pub mass_kg: f64,
    /// Spring stiffness, N/m.
    pub stiffness_n_per_m: f64,
}

const TERMS: i32 = 80;

impl PointResonatorPlate {
    fn residual(&self, kx: f64, ky: f64, omega: f64) -> f64 {
        let g = 2.0 * std::f64::consts::PI / self.a_m;
        let w2 = omega * omega;
        let mut sum = 0.0;
        for i in -TERMS..=TERMS {
            for j in -TERMS..=TERMS {
                let q2 = (kx + g * f64::from(i)).powi(2) + (ky + g * f64::from(j)).powi(2);
                sum += 1.0 / (self.d_n_m * q2 * q2 - self.rho_h_kg_m2 * w2);
            }
        }
        let r = self.stiffness_n_per_m * self.mass_kg * w2 / (self.stiffness_n_per_m - self.mass_kg * w2);
        1.0 - r * sum / (self.a_m * self.a_m)
    }

    /// The lowest `count` eigenfrequencies at (kx, ky) below `max_hz`, Hz: sign changes of the residual on a fine
    /// grid, refined by bisection, keeping the roots (not the poles, where the residual diverges).
    pub fn frequencies_hz(&self, kx: f64, ky: f64, count: usize, max_hz: f64) -> Vec<f64> {
        let two_pi = 2.0 * std::f64::consts::PI;
        let steps = 4000;
        let mut roots = Vec::new();
        let mut prev_f = 1.0;
        let mut prev = self.residual(kx, ky, two_pi * prev_f);
        for s in 1..=steps {
            let f = 1.0 + (max_hz - 1.0) * f64::from(s) / f64::from(steps);
            let r = self.residual(kx, ky, two_pi * f);
            if prev.signum() != r.signum() {
                let (mut lo, mut hi, mut rlo) = (prev_f, f, prev);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    let rm = self.residual(kx, ky, two_pi * mid);
                    if rm.signum() == rlo.signum() {
                        lo = mid;
                        rlo = rm;
                    } else {
                        hi = mid;
                    }
                }
                let root = 0.5 * (lo + hi);
                if self.residual(kx, ky, two_pi * root).abs() < 1e-3 {
                    roots.push(root);
                    if roots.len() == count {
                        break;
                    }
                }
            }
            prev = r;
            prev_f = f;
        }
        roots
    }
}

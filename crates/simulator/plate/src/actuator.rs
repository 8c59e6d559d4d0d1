//! Voice-coil actuators: drive signal to force on the plate, with a non-flat response, unit-to-unit spread and a
//! weak nonlinearity, so that Kirkeby compensation and harmonic separation have real work to do.
//!
//! Model (a Hammerstein system): the drive `u` (normalised to full scale; 1.0 is taken as 1 V at the coil) passes a
//! static cubic `u + beta u^3` (`beta` = the scene's `nonlinearity`), then a linear filter: the unit's gain
//! `force_factor * 10^(g / 20)` (`g` the unit's spread, drawn from the scene seed: normal with standard deviation
//! `spread_db`, clipped at 3 sigma), a second-order high-pass at the suspension resonance (quality factor `Q`: the
//! response peaks at `Q` there) and a first-order low-pass at the roll-off corner. Both filters are the bilinear
//! transform prewarped at their corners (the RBJ cookbook high-pass), so the corner frequencies are exact at any
//! sample rate.

use std::f64::consts::PI;

use metaplate_core::scene::{Scene, VoiceCoilSpec};
use metaplate_dsp::error::{check_result, check_sample_rate, check_signal};
use num_complex::Complex64;

use crate::error::PlateError;
use metaplate_core::rng::SplitMix64;

/// Stream constant separating coil-gain draws from the scene's other random draws.
const COIL_STREAM: u64 = 0x636f_696c; // "coil"

/// A voice coil at a given sample rate.
#[derive(Debug, Clone, PartialEq)]
pub struct VoiceCoil {
    /// Linear gain in the pass band, N per unit drive (force factor with the unit's spread applied).
    pub gain_n: f64,
    /// This unit's gain offset from the nominal force factor, dB.
    pub spread_db: f64,
    /// Cubic coefficient on the normalised drive.
    pub nonlinearity: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// High-pass biquad `[b0, b1, b2, a1, a2]` (a0 normalised to 1).
    high_pass: [f64; 5],
    /// Low-pass first-order section `[b0, b1, a1]`.
    low_pass: [f64; 3],
}

impl VoiceCoil {
    /// Unit `unit` of a coil type `spec` at `sample_rate_hz`, its spread drawn from `seed`.
    ///
    /// Valid range: a spec in its valid range (see [`VoiceCoilSpec`]) whose suspension resonance and roll-off lie
    /// below `sample_rate_hz / 2`; finite positive `sample_rate_hz`.
    ///
    /// # Errors
    /// [`PlateError::InvalidParameter`] or [`PlateError::Dsp`] naming the offending value.
    pub fn new(spec: &VoiceCoilSpec, unit: usize, seed: u64, sample_rate_hz: f64) -> Result<Self, PlateError> {
        check_sample_rate(sample_rate_hz)?;
        let nyquist = sample_rate_hz / 2.0;
        let below = |name, v: f64| crate::error::check_range(name, v, f64::MIN_POSITIVE, nyquist * (1.0 - 1e-9));
        let f0 = below("suspension_resonance_hz", spec.suspension_resonance_hz)?;
        let fc = below("rolloff_hz", spec.rolloff_hz)?;
        let q = crate::error::check_range("suspension_q", spec.suspension_q, 1e-3, 1e3)?;
        crate::error::check_range("force_factor_n_per_v", spec.force_factor_n_per_v, f64::MIN_POSITIVE, 1e6)?;
        crate::error::check_range("spread_db", spec.spread_db, 0.0, 20.0)?;
        crate::error::check_range("nonlinearity", spec.nonlinearity, -1.0, 1.0)?;
        let mut rng = SplitMix64::new(seed ^ (unit as u64).wrapping_mul(0x9E37_79B9), COIL_STREAM);
        let spread_db = spec.spread_db * rng.normal().clamp(-3.0, 3.0);
        let w0 = 2.0 * PI * f0 / sample_rate_hz;
        let alpha = w0.sin() / (2.0 * q);
        let a0 = 1.0 + alpha;
        let c = w0.cos();
        let high_pass =
            [(1.0 + c) / 2.0 / a0, -(1.0 + c) / a0, (1.0 + c) / 2.0 / a0, -2.0 * c / a0, (1.0 - alpha) / a0];
        let t = (PI * fc / sample_rate_hz).tan();
        let low_pass = [t / (1.0 + t), t / (1.0 + t), (t - 1.0) / (1.0 + t)];
        Ok(Self {
            gain_n: spec.force_factor_n_per_v * 10f64.powf(spread_db / 20.0),
            spread_db,
            nonlinearity: spec.nonlinearity,
            sample_rate_hz,
            high_pass,
            low_pass,
        })
    }

    /// The voice coils of every actuator of `scene`, at `sample_rate_hz`.
    ///
    /// # Errors
    /// As [`VoiceCoil::new`].
    pub fn for_scene(scene: &Scene, sample_rate_hz: f64) -> Result<Vec<Self>, PlateError> {
        scene
            .actuators
            .iter()
            .enumerate()
            .map(|(k, a)| Self::new(&a.voice_coil, k, scene.seed, sample_rate_hz))
            .collect()
    }

    /// Complex gain of the linear part at `freq_hz`, N per unit drive (the discrete-time filter's exact response).
    ///
    /// Valid range: finite `0 <= freq_hz <= sample_rate_hz / 2`; outside it the result is NaN-free but meaningless.
    pub fn frequency_response(&self, freq_hz: f64) -> Complex64 {
        let z1 = Complex64::from_polar(1.0, -2.0 * PI * freq_hz / self.sample_rate_hz); // z^-1
        let [b0, b1, b2, a1, a2] = self.high_pass;
        let hp = (b0 + b1 * z1 + b2 * z1 * z1) / (1.0 + a1 * z1 + a2 * z1 * z1);
        let [c0, c1, d1] = self.low_pass;
        let lp = (c0 + c1 * z1) / (1.0 + d1 * z1);
        self.gain_n * hp * lp
    }

    /// Force on the plate (N) for the drive signal `drive` (normalised to full scale), sample by sample, from rest.
    ///
    /// Valid range: any finite drive (the cubic is meant for `|u| <= 1`, where it stays weak).
    ///
    /// # Errors
    /// [`PlateError::Dsp`] for an empty or non-finite drive, or a non-finite result.
    pub fn drive_to_force(&self, drive: &[f64]) -> Result<Vec<f64>, PlateError> {
        check_signal("voice-coil drive", drive)?;
        let [b0, b1, b2, a1, a2] = self.high_pass;
        let [c0, c1, d1] = self.low_pass;
        let (mut x1, mut x2, mut y1, mut y2) = (0.0, 0.0, 0.0, 0.0);
        let (mut h1, mut l1) = (0.0, 0.0);
        let force: Vec<f64> = drive
            .iter()
            .map(|&u| {
                let x = u + self.nonlinearity * u * u * u;
                let y = b0 * x + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
                (x2, x1, y2, y1) = (x1, x, y1, y);
                let l = c0 * y + c1 * h1 - d1 * l1;
                (h1, l1) = (y, l);
                self.gain_n * l
            })
            .collect();
        check_result("voice-coil force", &force)?;
        Ok(force)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> VoiceCoilSpec {
        VoiceCoilSpec {
            force_factor_n_per_v: 0.5,
            suspension_resonance_hz: 70.0,
            suspension_q: 2.0,
            rolloff_hz: 400.0,
            spread_db: 1.5,
            nonlinearity: 0.0,
        }
    }

    /// Amplitude and phase of `x` at `freq_hz` over its last 0.2 s (after the filters have settled): whole periods
    /// of every frequency tested here, so there is no leakage between them.
    fn tone(x: &[f64], freq_hz: f64, fs: f64) -> Complex64 {
        let n = (0.2 * fs) as usize;
        let start = x.len() - n;
        let s: Complex64 = x[start..]
            .iter()
            .enumerate()
            .map(|(i, &v)| v * Complex64::from_polar(1.0, -2.0 * PI * freq_hz * (start + i) as f64 / fs))
            .sum();
        s * 2.0 / n as f64
    }

    #[test]
    fn filtered_sine_matches_the_stated_response_and_resonance_peaks_at_q() {
        let fs = 24_000.0;
        let coil = VoiceCoil::new(&spec(), 0, 1, fs).unwrap();
        for f in [20.0, 75.0, 300.0, 2000.0] {
            let u: Vec<f64> = (0..fs as usize * 2).map(|i| (2.0 * PI * f * i as f64 / fs).cos()).collect();
            let got = tone(&coil.drive_to_force(&u).unwrap(), f, fs);
            let want = coil.frequency_response(f);
            // 2 s of signal: the slowest pole (70 Hz, Q 2) has decayed by e^-350 before the last 0.2 s; what is left
            // is the rounding of the sums: 1e-9 relative.
            assert!((got - want).norm() < 1e-9 * want.norm(), "{f} Hz: {got} vs {want}");
        }
        // At the suspension resonance the high-pass peaks at exactly Q (prewarped bilinear transform); the low-pass
        // there is 1 / sqrt(1 + (70 / 400)^2) to within its own prewarping (tan(pi 400 / fs) vs pi 400 / fs: 0.1 %).
        let at_f0 = coil.frequency_response(70.0).norm() / coil.gain_n;
        let lp = 1.0 / (1.0f64 + (70.0f64 / 400.0).powi(2)).sqrt();
        assert!((at_f0 / (2.0 * lp) - 1.0).abs() < 2e-3, "{at_f0}");
        // Two decades below the resonance the high-pass falls at 40 dB per decade: 1/100 in amplitude per decade.
        let ratio = coil.frequency_response(0.7).norm() / coil.frequency_response(7.0).norm();
        assert!((ratio - 0.01).abs() < 1e-4, "{ratio}");
    }

    #[test]
    fn units_spread_deterministically() {
        let gains: Vec<f64> = (0..8).map(|u| VoiceCoil::new(&spec(), u, 42, 24_000.0).unwrap().spread_db).collect();
        let again: Vec<f64> = (0..8).map(|u| VoiceCoil::new(&spec(), u, 42, 24_000.0).unwrap().spread_db).collect();
        assert_eq!(gains, again);
        let other: Vec<f64> = (0..8).map(|u| VoiceCoil::new(&spec(), u, 43, 24_000.0).unwrap().spread_db).collect();
        assert_ne!(gains, other);
        // Clipped at 3 sigma, and not all alike.
        assert!(gains.iter().all(|g| g.abs() <= 4.5));
        let range = gains.iter().fold(f64::MIN, |a, &b| a.max(b)) - gains.iter().fold(f64::MAX, |a, &b| a.min(b));
        assert!(range > 0.1, "{gains:?}");
        let flat = VoiceCoilSpec { spread_db: 0.0, ..spec() };
        assert_eq!(VoiceCoil::new(&flat, 3, 42, 24_000.0).unwrap().gain_n, 0.5);
    }

    #[test]
    fn cubic_nonlinearity_makes_the_expected_third_harmonic() {
        // A cosine of amplitude A through u + beta u^3 has a third harmonic beta A^3 / 4 beside a fundamental
        // A + 3 beta A^3 / 4; the linear filter then scales each by its own response.
        let fs = 24_000.0;
        let beta = 0.05;
        let coil = VoiceCoil::new(&VoiceCoilSpec { nonlinearity: beta, ..spec() }, 0, 1, fs).unwrap();
        let (f, a) = (100.0, 0.8);
        let u: Vec<f64> = (0..fs as usize * 2).map(|i| a * (2.0 * PI * f * i as f64 / fs).cos()).collect();
        let force = coil.drive_to_force(&u).unwrap();
        let h1 = tone(&force, f, fs).norm() / coil.frequency_response(f).norm();
        let h3 = tone(&force, 3.0 * f, fs).norm() / coil.frequency_response(3.0 * f).norm();
        // Settled filters and whole periods: rounding only, 1e-9 relative.
        assert!((h1 - (a + 0.75 * beta * a.powi(3))).abs() < 1e-9, "{h1}");
        assert!((h3 - 0.25 * beta * a.powi(3)).abs() < 1e-9, "{h3}");
    }

    #[test]
    fn refuses_bad_input() {
        let coil = VoiceCoil::new(&spec(), 0, 1, 24_000.0).unwrap();
        assert!(coil.drive_to_force(&[]).is_err());
        assert!(coil.drive_to_force(&[0.0, f64::NAN]).is_err());
        assert!(VoiceCoil::new(&spec(), 0, 1, 700.0).is_err(), "roll-off above Nyquist");
        assert!(VoiceCoil::new(&spec(), 0, 1, 0.0).is_err());
        assert!(VoiceCoil::new(&VoiceCoilSpec { suspension_q: 0.0, ..spec() }, 0, 1, 24_000.0).is_err());
    }
}

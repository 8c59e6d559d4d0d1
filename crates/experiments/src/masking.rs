//! The masking noise an experiment plays on its own output pair while each stimulus plays (the paper's
//! participants heard pink noise on circumaural headphones, to mask the plate's sound).
//!
//! Each ear gets its own pink noise (two independent draws), 20 Hz to 20 kHz, at the file's level as an RMS re
//! digital full scale, faded in and out over 10 ms so that a trial's masker starts and stops without a click. The
//! noise covers each playback of a stimulus, not the pauses between trials: the rig plays one buffer per
//! presentation.

use metaplate_core::rng::SplitMix64;
use metaplate_dsp::noise::pink_noise;
use metaplate_dsp::window::{fade_in, fade_out};

use crate::error::ExperimentError;
use crate::file::Masking;

/// The masker's band, Hz: the range of hearing.
pub const MASKING_BAND_HZ: (f64, f64) = (20.0, 20_000.0);

/// Fade at each end of a masker, s.
pub const MASKING_FADE_S: f64 = 0.010;

impl Masking {
    /// The two channels' noise (in the order of `self.channels`) for a playback of `frames` frames at
    /// `sample_rate_hz`, drawn from `seed` (a session's maskers differ by stimulus; a seed gives the same noise
    /// on every platform).
    ///
    /// # Errors
    /// [`ExperimentError::InvalidArgument`] when the noise cannot be made: fewer than 2 frames, a rate that puts
    /// the whole band above Nyquist, or a level whose peaks would clip (above about -12 dB FS RMS for pink noise's
    /// crest factor).
    pub fn render(&self, frames: usize, sample_rate_hz: f64, seed: u64) -> Result<[Vec<f64>; 2], ExperimentError> {
        let invalid = |reason: String| ExperimentError::InvalidArgument { name: "masking", reason };
        let rms = 10f64.powf(self.level_dbfs / 20.0);
        let fade = ((MASKING_FADE_S * sample_rate_hz).round() as usize).min(frames / 2);
        let (up, down) = (fade_in(fade), fade_out(fade));
        let ear = |stream: u64| -> Result<Vec<f64>, ExperimentError> {
            let mut rng = SplitMix64::new(seed, stream);
            let white: Vec<f64> = (0..frames).map(|_| rng.normal()).collect();
            let mut noise =
                pink_noise(&white, sample_rate_hz, MASKING_BAND_HZ, rms).map_err(|e| invalid(e.to_string()))?;
            noise[..fade].iter_mut().zip(&up).for_each(|(v, w)| *v *= w);
            let tail = frames - fade;
            noise[tail..].iter_mut().zip(&down).for_each(|(v, w)| *v *= w);
            let peak = noise.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if peak > 1.0 {
                return Err(invalid(format!(
                    "pink noise at {} dB FS RMS peaks at {peak:.2} of full scale and would clip: lower level_dbfs",
                    self.level_dbfs
                )));
            }
            Ok(noise)
        };
        Ok([ear(0x4d41_534b_4c45_4654)?, ear(0x4d41_534b_5249_4748)?])
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    fn masking(level_dbfs: f64) -> Masking {
        Masking { noise: "pink".into(), channels: [22, 23], level_dbfs }
    }

    fn rms(x: &[f64]) -> f64 {
        (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
    }

    #[test]
    fn each_ear_gets_its_own_pink_noise_at_the_level_faded_at_both_ends() {
        let [left, right] = masking(-20.0).render(48_000, 48e3, 5).unwrap();
        assert_eq!((left.len(), right.len()), (48_000, 48_000));
        // The fades (two half-Hann of 10 ms, keeping 3/8 of their power) take 1.25 % of a second's power:
        // -0.055 dB; the noise's own power within them varies by a few percent of that.
        let expected_db = -20.0 + 10.0 * (1.0 - 2.0 * 0.010 * 5.0 / 8.0f64).log10();
        for ear in [&left, &right] {
            let db = 20.0 * rms(ear).log10();
            assert!((db - expected_db).abs() < 0.01, "{db} against {expected_db}");
            assert_eq!(ear[0], 0.0);
            assert!(ear[..48].iter().all(|v| v.abs() < 0.05) && ear[47_990..].iter().all(|v| v.abs() < 0.05));
        }
        // Independent ears: their correlation is that of two independent draws (|r| < 4 / sqrt(48 000)).
        let r = left.iter().zip(&right).map(|(a, b)| a * b).sum::<f64>() / (rms(&left) * rms(&right) * 48_000.0);
        assert!(r.abs() < 0.02, "{r}");
        // The same seed gives the same noise; another seed another.
        assert_eq!(masking(-20.0).render(48_000, 48e3, 5).unwrap()[0], left);
        assert_ne!(masking(-20.0).render(48_000, 48e3, 6).unwrap()[0], left);
    }

    #[test]
    fn a_level_that_clips_and_a_playback_too_short_are_refused() {
        let err = masking(0.0).render(48_000, 48e3, 5).unwrap_err();
        assert!(err.to_string().contains("would clip"), "{err}");
        let err = masking(-20.0).render(1, 48e3, 5).unwrap_err();
        assert!(err.to_string().contains("at least 2 samples"), "{err}");
        // Two frames at 48 kHz hold no frequency in the band (bins at 0 and 24 kHz); three do (16 kHz): fades of
        // one frame each, finite.
        let err = masking(-20.0).render(2, 48e3, 5).unwrap_err();
        assert!(err.to_string().contains("holds no frequency bin"), "{err}");
        let [three, _] = masking(-20.0).render(3, 48e3, 5).unwrap();
        assert!(three.iter().all(|v| v.is_finite()) && three[0] == 0.0);
    }
}

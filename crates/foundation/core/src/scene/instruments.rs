//! The measurement chain: vibrometer, DAQ and audio interface.

use serde::{Deserialize, Serialize};

/// The laser Doppler vibrometer's imperfections.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): finite `noise_rms_m_s >= 0`,
/// `0 < speckle_mean_level <= 1`, `speckle_spread >= 0`, `0 <= dropout_probability <= 1`, `max_velocity_m_s > 0`,
/// `0 <= aim_error_rms_m <= 0.002`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LdvSpec {
    /// Velocity noise floor at full signal level, m/s rms over the DAQ bandwidth.
    pub noise_rms_m_s: f64,
    /// Mean returned signal level, as a fraction of the best possible (1 = a perfect retroreflector). The noise
    /// grows as the level falls.
    pub speckle_mean_level: f64,
    /// Relative spread (standard deviation / mean) of the signal level from point to point (speckle).
    pub speckle_spread: f64,
    /// Probability that one recording at one point suffers a signal dropout.
    pub dropout_probability: f64,
    /// Full-scale velocity of the selected range, m/s; faster motion clips.
    pub max_velocity_m_s: f64,
    /// Beam positioning error, m: the scanner's aim misses each commanded point by a random offset, normal in x and
    /// in y with this standard deviation, drawn once per point (the same at every playback there). Optional key;
    /// 0 (the default, not written) aims exactly.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub aim_error_rms_m: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_true(v: &bool) -> bool {
    *v
}

fn yes() -> bool {
    true
}

/// The data acquisition unit that records the vibrometer's analog output and the loopback reference.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): `bits` 0 (an ideal converter) or `1 <= bits <= 32`,
/// finite `range_v > 0`, `sample_rate_hz > 0`, `|clock_offset_ppm| <= 1000`, `volts_per_m_s > 0`.
///
/// The mock DAQ's wire protocol carries 16-bit codes: with `bits = 16` and `clipping` on (the built-in scenes) the
/// mock lab records through it; any other `bits`, or `clipping = false`, is served by an in-process converter that
/// quantises at `bits` (not at all for 0) and clips at the range (or not), without the USB link (and so without its
/// faults).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DaqSpec {
    /// ADC resolution, bits; 0 is an ideal converter that does not quantise.
    pub bits: u32,
    /// Input range +/- `range_v`, V; inputs beyond it clip.
    pub range_v: f64,
    /// Nominal sample rate, Hz.
    pub sample_rate_hz: f64,
    /// How far the DAQ's clock runs fast (positive) or slow of nominal, parts per million.
    pub clock_offset_ppm: f64,
    /// Vibrometer output sensitivity, V per m/s.
    pub volts_per_m_s: f64,
    /// Whether inputs beyond the range clip (and the vibrometer's output at its range's full scale): `false` is an
    /// ideal chain with unlimited range, for error budgets. Optional key; `true` (the default) is not written.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub clipping: bool,
}

/// The multichannel audio interface that drives the actuators.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): finite `sample_rate_hz > 0`, `channels` at least
/// the number of actuators plus one (the loopback reference), `latency_s >= 0`, `|clock_offset_ppm| <= 1000`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AudioSpec {
    /// Nominal sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Output channels.
    pub channels: u32,
    /// Delay from handing a buffer to the driver to sound at the outputs, s.
    pub latency_s: f64,
    /// How far the interface's clock runs fast (positive) or slow of nominal, parts per million.
    pub clock_offset_ppm: f64,
}

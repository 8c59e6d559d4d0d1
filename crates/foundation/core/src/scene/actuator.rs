//! Actuators: voice coils pushing magnets on the plate.

use serde::{Deserialize, Serialize};

/// A voice-coil actuator's electromechanical response, from drive voltage to force on the plate.
///
/// Model: force factor times a second-order high-pass at the suspension resonance (quality factor `suspension_q`)
/// times a first-order low-pass at `rolloff_hz` (coil inductance); for a drive `u` normalised to full scale the
/// force goes as `u + nonlinearity * u^3`. Valid range (checked by [`crate::scene::Scene::validate`]): finite `force_factor_n_per_v > 0`,
/// `suspension_resonance_hz > 0`, `suspension_q > 0`, `rolloff_hz > 0`, `spread_db >= 0`, `|nonlinearity| <= 1`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VoiceCoilSpec {
    /// Force per drive voltage in the flat part of the response, N/V.
    pub force_factor_n_per_v: f64,
    /// Resonance of the magnet on its suspension, Hz.
    pub suspension_resonance_hz: f64,
    /// Quality factor of that resonance (dimensionless).
    pub suspension_q: f64,
    /// Corner of the high-frequency roll-off, Hz.
    pub rolloff_hz: f64,
    /// Unit-to-unit standard deviation of the gain, dB (hand-wound coils differ).
    pub spread_db: f64,
    /// Cubic coefficient of the weak nonlinearity, on the drive normalised to full scale (dimensionless); 0 is
    /// linear.
    pub nonlinearity: f64,
}

/// One actuator: where it pushes, and its voice coil.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): on the plate, not on a support pad.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActuatorSpec {
    /// Magnet centre x, m.
    pub x_m: f64,
    /// Magnet centre y, m.
    pub y_m: f64,
    /// Its voice coil (the scene's default unless the file overrides it).
    pub voice_coil: VoiceCoilSpec,
}

/// Fields of a [`VoiceCoilSpec`] that one `[[actuators]]` entry overrides; the rest come from the top-level
/// `[voice_coil]` table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct VoiceCoilPatch {
    #[serde(skip_serializing_if = "Option::is_none")]
    force_factor_n_per_v: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    suspension_resonance_hz: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    suspension_q: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rolloff_hz: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    spread_db: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    nonlinearity: Option<f64>,
}

impl VoiceCoilPatch {
    /// The fields of `coil` that differ from `base` (all of them when there is no base).
    pub(crate) fn diff(base: Option<&VoiceCoilSpec>, coil: &VoiceCoilSpec) -> Self {
        let keep = |get: fn(&VoiceCoilSpec) -> f64| match base {
            Some(b) if get(b) == get(coil) => None,
            _ => Some(get(coil)),
        };
        Self {
            force_factor_n_per_v: keep(|c| c.force_factor_n_per_v),
            suspension_resonance_hz: keep(|c| c.suspension_resonance_hz),
            suspension_q: keep(|c| c.suspension_q),
            rolloff_hz: keep(|c| c.rolloff_hz),
            spread_db: keep(|c| c.spread_db),
            nonlinearity: keep(|c| c.nonlinearity),
        }
    }

    /// True when the patch overrides nothing.
    pub(crate) fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// `base` with this patch's fields replaced.
    ///
    /// # Errors
    /// The name of the first field that neither the patch nor a base gives.
    pub(crate) fn apply(&self, base: Option<&VoiceCoilSpec>) -> Result<VoiceCoilSpec, &'static str> {
        let pick = |name: &'static str, own: Option<f64>, get: fn(&VoiceCoilSpec) -> f64| {
            own.or_else(|| base.map(get)).ok_or(name)
        };
        Ok(VoiceCoilSpec {
            force_factor_n_per_v: pick("force_factor_n_per_v", self.force_factor_n_per_v, |c| c.force_factor_n_per_v)?,
            suspension_resonance_hz: pick("suspension_resonance_hz", self.suspension_resonance_hz, |c| {
                c.suspension_resonance_hz
            })?,
            suspension_q: pick("suspension_q", self.suspension_q, |c| c.suspension_q)?,
            rolloff_hz: pick("rolloff_hz", self.rolloff_hz, |c| c.rolloff_hz)?,
            spread_db: pick("spread_db", self.spread_db, |c| c.spread_db)?,
            nonlinearity: pick("nonlinearity", self.nonlinearity, |c| c.nonlinearity)?,
        })
    }
}

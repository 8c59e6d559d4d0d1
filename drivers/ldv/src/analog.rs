//! `AnalogVibrometer`: a vibrometer without a remote interface, its range set at the instrument by hand.

use metaplate_core::vibrometer::{Tracking, VelocityScale, Vibrometer, VibrometerError, VibrometerIdentity};
use metaplate_polytec_protocol::VelocityRange;

use crate::config::OUTPUT_FULL_SCALE_V;

/// A vibrometer seen only through its analog velocity output: the range the hardware file declares (set at the
/// instrument by hand) is what the dataset records; nothing is sent anywhere. A recipe that asks for more than the
/// declared range's full scale is refused, naming the range to set at the instrument.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalogVibrometer {
    identity: VibrometerIdentity,
    range: VelocityRange,
    output_full_scale_v: f64,
}

impl AnalogVibrometer {
    /// A vibrometer at `range` (`25mm/s/V`), its output swinging +/- `output_full_scale_v` volts (10 V when
    /// `None`), named by `identity` for the dataset.
    ///
    /// # Errors
    /// [`VibrometerError::InvalidArgument`] when `range` does not parse or the full scale is not a positive finite
    /// voltage.
    pub fn new(
        identity: VibrometerIdentity,
        range: &str,
        output_full_scale_v: Option<f64>,
    ) -> Result<Self, VibrometerError> {
        let range =
            VelocityRange::parse(range).map_err(|e| VibrometerError::InvalidArgument { detail: e.to_string() })?;
        let output_full_scale_v = output_full_scale_v.unwrap_or(OUTPUT_FULL_SCALE_V);
        if !(output_full_scale_v.is_finite() && output_full_scale_v > 0.0) {
            return Err(VibrometerError::InvalidArgument {
                detail: format!("output full scale {output_full_scale_v} V is not a positive voltage"),
            });
        }
        Ok(Self { identity, range, output_full_scale_v })
    }

    fn scale(&self) -> VelocityScale {
        VelocityScale {
            m_s_per_v: self.range.m_s_per_v(),
            full_scale_m_s: self.range.m_s_per_v() * self.output_full_scale_v,
        }
    }
}

impl Vibrometer for AnalogVibrometer {
    fn identify(&mut self) -> Result<VibrometerIdentity, VibrometerError> {
        Ok(self.identity.clone())
    }

    /// Always 1: an analog-only vibrometer reports no level (its own bar graph is for the person at the bench).
    fn signal_level(&mut self) -> Result<f64, VibrometerError> {
        Ok(1.0)
    }

    /// The declared range, if its full scale reaches `max_velocity_m_s`.
    fn set_velocity_range(&mut self, max_velocity_m_s: f64) -> Result<VelocityScale, VibrometerError> {
        let scale = self.scale();
        if !(max_velocity_m_s.is_finite() && max_velocity_m_s > 0.0 && max_velocity_m_s <= scale.full_scale_m_s) {
            return Err(VibrometerError::InvalidArgument {
                detail: format!(
                    "max_velocity_m_s = {max_velocity_m_s} is outside (0, {}] m/s, the full scale of the range {} \
                     declared in the hardware file (set a larger range at the instrument and declare it)",
                    scale.full_scale_m_s, self.range
                ),
            });
        }
        Ok(scale)
    }

    /// Only `Off`: there is nothing to switch.
    fn set_tracking(&mut self, tracking: Tracking) -> Result<(), VibrometerError> {
        match tracking {
            Tracking::Off => Ok(()),
            other => Err(VibrometerError::Device {
                code: 0,
                message: format!("tracking {other:?}: an analog-only vibrometer takes no settings"),
            }),
        }
    }

    fn reconnect(&mut self) -> Result<(), VibrometerError> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn id() -> VibrometerIdentity {
        VibrometerIdentity {
            vendor: "Polytec".into(),
            model: "OFV-505".into(),
            serial: "unknown".into(),
            firmware: "n/a".into(),
        }
    }

    #[test]
    fn the_declared_range_is_recorded_and_never_exceeded() {
        let mut ldv = AnalogVibrometer::new(id(), "25mm/s/V", None).unwrap();
        let scale = ldv.set_velocity_range(0.1).unwrap();
        assert!((scale.m_s_per_v - 0.025).abs() < 1e-15 && (scale.full_scale_m_s - 0.25).abs() < 1e-15);
        assert!(matches!(ldv.set_velocity_range(0.26), Err(VibrometerError::InvalidArgument { .. })));
        assert!(AnalogVibrometer::new(id(), "25 furlongs", None).is_err());
        assert_eq!(ldv.identify().unwrap(), id());
    }
}

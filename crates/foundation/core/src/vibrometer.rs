//! The `Vibrometer` capability: what a recipe may ask of a scanning laser Doppler vibrometer, in SI units.
//!
//! A recipe sees this trait, never a serial line: the real driver (`metaplate-ldv`) and any stand-in implement it.
//! Its error tells a recipe what it can do next: retry later, [`Vibrometer::reconnect`], or stop.

/// The instrument's identity, as reported by the controller (for the dataset manifest).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VibrometerIdentity {
    /// Manufacturer, for example `Ometron`.
    pub vendor: String,
    /// Model, for example `8330`.
    pub model: String,
    /// Serial number: what a reopen looks the instrument up by.
    pub serial: String,
    /// Firmware version.
    pub firmware: String,
}

/// The tracking filter that rides the velocity decoder through short speckle dropouts, at the cost of slew rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Tracking {
    /// No tracking filter.
    Off,
    /// Slow tracking: rejects the most dropouts, follows the least acceleration, longest lock time.
    Slow,
    /// Medium tracking.
    Medium,
    /// Fast tracking: rejects the fewest dropouts, shortest lock time.
    Fast,
}

/// The velocity range in force: how the analog velocity output maps to velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityScale {
    /// Velocity per volt of analog output, (m/s)/V: multiply a recorded voltage by it to get velocity.
    pub m_s_per_v: f64,
    /// The largest velocity the output represents before it clips, m/s.
    pub full_scale_m_s: f64,
}

/// Why a vibrometer call failed, grouped by what the caller can do about it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VibrometerError {
    /// The instrument did not answer properly within the driver's bounded retries (no reply, or only garbled or
    /// stale replies, and resynchronisation failed). The link may still be up: a recipe may
    /// [`Vibrometer::reconnect`] and repeat the step, or stop.
    #[error("vibrometer did not answer {command}: {detail}")]
    Timeout {
        /// The command that went unanswered, in its wire form.
        command: String,
        /// What happened on the way (attempts, last failure).
        detail: String,
    },
    /// The link to the instrument is gone (port vanished, cable pulled). Recoverable: [`Vibrometer::reconnect`]
    /// reopens it and re-applies the last settings.
    #[error("vibrometer disconnected: {reason}")]
    Disconnected {
        /// What the transport reported.
        reason: String,
    },
    /// The instrument refused the command with an error code of its own (for example laser off, not calibrated,
    /// hardware fault). Retrying the same command will fail the same way until the cause is fixed.
    #[error("vibrometer error {code}: {message}")]
    Device {
        /// The instrument's error code (for the LDV protocol: 1 to 8).
        code: u8,
        /// The instrument's text, and what the code means.
        message: String,
    },
    /// The instrument answered with something the driver cannot use even though it decoded (for example an
    /// out-of-range value). A driver or firmware mismatch: report it.
    #[error("vibrometer protocol error: {detail}")]
    Protocol {
        /// What was wrong.
        detail: String,
    },
    /// The caller asked for something outside the documented range (non-finite or out-of-range coordinate, a
    /// velocity range larger than any the instrument offers). Nothing was sent.
    #[error("invalid vibrometer request: {detail}")]
    InvalidArgument {
        /// Which argument, its value and its valid range.
        detail: String,
    },
}

impl VibrometerError {
    /// Whether [`Vibrometer::reconnect`] is the documented way out of this error ([`VibrometerError::Disconnected`]
    /// and [`VibrometerError::Timeout`]).
    pub fn suggests_reconnect(&self) -> bool {
        matches!(self, VibrometerError::Disconnected { .. } | VibrometerError::Timeout { .. })
    }
}

/// A scanning laser Doppler vibrometer as a recipe uses it. Coordinates are in the calibrated plate frame, metres.
pub trait Vibrometer {
    /// The instrument's identity.
    ///
    /// # Errors
    /// Any [`VibrometerError`] but `InvalidArgument`.
    fn identify(&mut self) -> Result<VibrometerIdentity, VibrometerError>;

    /// Moves the beam to (`x_m`, `y_m`) in the calibrated plate frame, m; returns once the beam has settled.
    /// Valid range: finite, within the instrument's field (for the LDV protocol plus or minus 0.5 m, rounded to
    /// 1 um, and mirror angles within plus or minus 25 degrees).
    ///
    /// # Errors
    /// `InvalidArgument` for a non-finite or out-of-field coordinate (nothing sent); `Device` when the instrument
    /// refuses (not calibrated, out of its mirrors' reach, hardware fault); `Timeout`, `Disconnected`, `Protocol`.
    fn move_to(&mut self, x_m: f64, y_m: f64) -> Result<(), VibrometerError>;

    /// The returned signal level at the current spot, as a fraction from 0 (no signal) to 1 (full scale). Below
    /// about 0.2 a recording risks dropouts.
    ///
    /// # Errors
    /// `Device` when the laser is off; `Timeout`, `Disconnected`, `Protocol`.
    fn signal_level(&mut self) -> Result<f64, VibrometerError>;

    /// Selects the most sensitive velocity range whose full scale is at least `max_velocity_m_s` and returns it.
    /// Valid range: finite, `0 < max_velocity_m_s <=` the instrument's largest full scale (10 m/s for the LDV
    /// protocol).
    ///
    /// # Errors
    /// `InvalidArgument` for a non-finite, non-positive or too-large velocity (nothing sent); `Device`, `Timeout`,
    /// `Disconnected`, `Protocol`.
    fn set_velocity_range(&mut self, max_velocity_m_s: f64) -> Result<VelocityScale, VibrometerError>;

    /// Sets the tracking filter.
    ///
    /// # Errors
    /// `Device`, `Timeout`, `Disconnected`, `Protocol`.
    fn set_tracking(&mut self, tracking: Tracking) -> Result<(), VibrometerError>;

    /// Switches the laser on (returns once it is stable, up to a few seconds) or off.
    ///
    /// # Errors
    /// `Device`, `Timeout`, `Disconnected`, `Protocol`.
    fn set_laser(&mut self, on: bool) -> Result<(), VibrometerError>;

    /// Reopens the link to the instrument and re-applies every setting made through this handle (laser, velocity
    /// range, tracking, beam position), so that a recipe can repeat the step that failed.
    ///
    /// # Errors
    /// `Disconnected` when the instrument cannot be reopened (yet); any error of re-applying a setting.
    fn reconnect(&mut self) -> Result<(), VibrometerError>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_link_failures_suggest_reconnect() {
        let timeout = VibrometerError::Timeout { command: "SIG?".into(), detail: "3 attempts".into() };
        let gone = VibrometerError::Disconnected { reason: "port vanished".into() };
        let device = VibrometerError::Device { code: 6, message: "laser off".into() };
        let bad = VibrometerError::InvalidArgument { detail: "x_m = NaN".into() };
        assert!(timeout.suggests_reconnect() && gone.suggests_reconnect());
        assert!(!device.suggests_reconnect() && !bad.suggests_reconnect());
        assert_eq!(device.to_string(), "vibrometer error 6: laser off");
    }
}

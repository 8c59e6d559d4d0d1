//! The `Vibrometer` capability: what a recipe may ask of a laser Doppler vibrometer's controller, in SI units.
//!
//! A recipe sees this trait, never a serial line: the real driver (`metaplate-ldv`: a Polytec controller over
//! RS-232, or an analog-only vibrometer) and any stand-in implement it. Where the beam lands is another
//! capability, [`Aim`](crate::aim::Aim).
//! Its error tells a recipe what it can do next: retry later, [`Vibrometer::reconnect`], or stop.

/// The instrument's identity, as reported by the controller (for the dataset manifest).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VibrometerIdentity {
    /// Manufacturer, for example `Polytec`.
    pub vendor: String,
    /// Model: for a Polytec, the controller's name, its sensor head and the velocity decoder in use.
    pub model: String,
    /// Serial number, where the instrument reports one (a Polytec's RS-232 interface does not: the text says so).
    pub serial: String,
    /// Firmware versions (controller, sensor head).
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
    /// The instrument refused the command or lacks what was asked (a range not on the unit's decoder, a setting
    /// it does not take). Retrying the same command will fail the same way until the cause is fixed.
    #[error("vibrometer error {code}: {message}")]
    Device {
        /// The driver's code for the refusal (0 when the instrument gives none).
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
    /// The caller asked for something outside the documented range (a non-finite velocity, a velocity range
    /// larger than any the instrument offers). Nothing was sent.
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

/// A laser Doppler vibrometer as a recipe uses it (the beam is aimed through [`Aim`](crate::aim::Aim)).
pub trait Vibrometer {
    /// The instrument's identity.
    ///
    /// # Errors
    /// Any [`VibrometerError`] but `InvalidArgument`.
    fn identify(&mut self) -> Result<VibrometerIdentity, VibrometerError>;

    /// The returned signal level at the current spot, as a fraction from 0 (no signal) to 1 (full scale). Below
    /// about 0.2 a recording risks dropouts.
    ///
    /// # Errors
    /// `Device` when the instrument reports no level; `Timeout`, `Disconnected`, `Protocol`.
    fn signal_level(&mut self) -> Result<f64, VibrometerError>;

    /// Selects the most sensitive velocity range whose full scale is at least `max_velocity_m_s` and returns it.
    /// Valid range: finite, `0 < max_velocity_m_s <=` the instrument's largest full scale (the ranges of the
    /// unit's decoder, as it reports them).
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

    /// Reopens the link to the instrument and re-applies every setting made through this handle (velocity range,
    /// tracking), so that a recipe can repeat the step that failed.
    ///
    /// # Errors
    /// `Disconnected` when the instrument cannot be reopened (yet); any error of re-applying a setting.
    fn reconnect(&mut self) -> Result<(), VibrometerError>;
}

//! The `Aim` capability: putting the vibrometer's beam on a point of the plate, apart from the vibrometer itself.
//!
//! A single-point vibrometer measures where its beam lands; what moves the beam is another instrument: galvanometer
//! mirrors driven by two analog outputs, motorised XY stages under the head or the plate, or (in the mock lab) the
//! lab itself. A recipe sees this trait and never the mechanism. Coordinates are in the plate frame, metres.

/// Why an aim failed, grouped by what the caller can do about it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AimError {
    /// The point is outside what the aimer can reach (beyond the mirrors' angles or the stages' travel). Nothing
    /// moved; [`Aim::check_reachable`] says so before a run starts.
    #[error("({x_m} m, {y_m} m) is out of the aimer's reach: {detail}")]
    Unreachable {
        /// The point asked for, m.
        x_m: f64,
        /// The point asked for, m.
        y_m: f64,
        /// The aimer's range, and which limit the point passes.
        detail: String,
    },
    /// A non-finite coordinate. Nothing moved.
    #[error("invalid aim request: {detail}")]
    InvalidArgument {
        /// Which argument and its value.
        detail: String,
    },
    /// The aimer's link is gone or it did not answer in time. Recoverable: [`Aim::reconnect`] reopens it and aims
    /// again at the last point.
    #[error("aimer disconnected: {reason}")]
    Disconnected {
        /// What the transport reported.
        reason: String,
    },
    /// The aimer refused or failed (a stage at a limit switch, a mirror driver fault): retrying fails the same way.
    #[error("aimer error: {message}")]
    Device {
        /// The instrument's report.
        message: String,
    },
    /// No aiming instrument is configured for this rig.
    #[error("no aiming instrument: {detail}")]
    Unavailable {
        /// What is missing and where to configure it.
        detail: String,
    },
}

impl AimError {
    /// Whether [`Aim::reconnect`] is the documented way out of this error ([`AimError::Disconnected`]).
    pub fn suggests_reconnect(&self) -> bool {
        matches!(self, AimError::Disconnected { .. })
    }
}

/// What puts the beam on a point of the plate.
pub trait Aim {
    /// Whether (`x_m`, `y_m`) is within reach, m; asks nothing of the instrument, so a recipe checks every point
    /// of a run before the run starts.
    ///
    /// # Errors
    /// `InvalidArgument` for a non-finite coordinate; `Unreachable` outside the aimer's range; `Unavailable` when
    /// there is no aimer.
    fn check_reachable(&self, x_m: f64, y_m: f64) -> Result<(), AimError>;

    /// Puts the beam on (`x_m`, `y_m`) in the plate frame, m; returns once it has settled.
    ///
    /// # Errors
    /// As [`Aim::check_reachable`] (nothing moved), then `Disconnected` or `Device`.
    fn aim_at(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError>;

    /// Reopens the link to the aimer and aims again at the last point reached, if any.
    ///
    /// # Errors
    /// `Disconnected` when the aimer cannot be reopened (yet); any error of aiming again.
    fn reconnect(&mut self) -> Result<(), AimError>;

    /// What aims the beam, for the dataset's rig record (for example "galvo mirrors (projective fit of 6 points,
    /// residual rms 0.041 mm) on NI USB-6211 s/n 01A2B3C4 ao0, ao1"): what identifies the aimer and its setup
    /// across reconnects, never a link's transient name (a pseudo-terminal's path).
    fn describe(&self) -> String;
}

/// Two analog outputs holding a static voltage each: what drives a pair of galvanometer mirrors (an NI DAQ's AO
/// channels on a rig, the mock lab's mirrors in a test). The galvo aimer maps plate coordinates to these volts.
pub trait MirrorOutputs: Send {
    /// Drives the X and Y mirrors to `x_v` and `y_v`, V; returns once the outputs hold them (the mirrors' own
    /// settling is the aimer's to wait for).
    ///
    /// # Errors
    /// `InvalidArgument` for a non-finite or out-of-range voltage (nothing written); `Disconnected` when the output
    /// device is gone; `Device` when it refused.
    fn set_volts(&mut self, x_v: f64, y_v: f64) -> Result<(), AimError>;

    /// The outputs' range, V: every written voltage lies in `[-limit, limit]`.
    fn limit_v(&self) -> f64;

    /// Reopens the output device after a `Disconnected` (the aimer writes the last voltages again).
    ///
    /// # Errors
    /// `Disconnected` when it cannot be reopened (yet).
    fn reconnect(&mut self) -> Result<(), AimError>;

    /// What drives the mirrors, for the dataset's rig record (for example "NI USB-6211 s/n 01A2B3C4 ao0, ao1").
    fn describe(&self) -> String;
}

/// The aimer of a rig that has none configured: every point is refused, naming why, so a run stops before it starts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NoAimer {
    /// Why there is none, for the error (for example which hardware-file section to add).
    pub detail: String,
}

impl Aim for NoAimer {
    fn check_reachable(&self, _x_m: f64, _y_m: f64) -> Result<(), AimError> {
        Err(AimError::Unavailable { detail: self.detail.clone() })
    }

    fn aim_at(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        self.check_reachable(x_m, y_m)
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        Ok(())
    }

    fn describe(&self) -> String {
        "none".to_owned()
    }
}

/// Checks that (`x_m`, `y_m`) is finite and within `half_width_m` of the origin on each axis: the usual first half
/// of an [`Aim::check_reachable`] for a rectangular range.
///
/// # Errors
/// `InvalidArgument` for a non-finite coordinate; `Unreachable` outside the rectangle.
pub fn check_within(x_m: f64, y_m: f64, half_width_m: f64) -> Result<(), AimError> {
    if !x_m.is_finite() || !y_m.is_finite() {
        return Err(AimError::InvalidArgument { detail: format!("x_m = {x_m}, y_m = {y_m}: not finite") });
    }
    if x_m.abs() > half_width_m || y_m.abs() > half_width_m {
        return Err(AimError::Unreachable { x_m, y_m, detail: format!("range is +/- {half_width_m} m on each axis") });
    }
    Ok(())
}

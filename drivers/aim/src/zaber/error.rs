//! The stage driver's errors, and what they are as an [`AimError`].

use metaplate_core::aim::AimError;
use metaplate_ldv::LineError;
use metaplate_zaber_protocol::WarningFlag;

/// Why the stages could not be opened or moved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ZaberError {
    /// A value of the configuration is out of range.
    #[error("Zaber stages: {key}: {reason}")]
    Config {
        /// The key as a hardware file's `[aim]` section spells it (`x.device`, `move_timeout_s`).
        key: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The serial line is gone.
    #[error("Zaber chain: {0}")]
    Line(LineError),
    /// No reply to a command within the reply timeout.
    #[error("Zaber device {device} axis {axis}: no reply to {command:?}")]
    NoReply {
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The command sent.
        command: String,
    },
    /// The device rejected a command (`RJ`), with its reason (`BADDATA`, `BADCOMMAND`, ...).
    #[error("Zaber device {device} axis {axis} rejected {command:?}: {reason}")]
    Rejected {
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The command sent.
        command: String,
        /// The reply's reason word.
        reason: String,
    },
    /// An axis reports faults or warnings that stop it: each flag by code and name (`WL (unexpected limit
    /// trigger)`, `FS (stalled and stopped)`, ...).
    #[error("Zaber {name} axis (device {device} axis {axis}): {}", flag_list(flags))]
    Flags {
        /// Which plate axis, "x" or "y".
        name: &'static str,
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The flags.
        flags: Vec<WarningFlag>,
    },
    /// A move or homing did not end within the move timeout.
    #[error("Zaber {name} axis (device {device} axis {axis}): still moving after {timeout_s} s")]
    MoveTimeout {
        /// Which plate axis.
        name: &'static str,
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The timeout, s.
        timeout_s: f64,
    },
    /// The axis stopped somewhere else than where it was sent.
    #[error("Zaber {name} axis: stopped at {position_us} microsteps, sent to {target_us}")]
    OffTarget {
        /// Which plate axis.
        name: &'static str,
        /// Where it is, microsteps.
        position_us: i64,
        /// Where it was sent, microsteps.
        target_us: i64,
    },
    /// A reply whose data is not what the command returns (a number for `get`, a flag list for `warnings`).
    #[error("Zaber device {device} axis {axis}: unexpected reply to {command:?}: {data:?}")]
    BadReply {
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The command sent.
        command: String,
        /// The reply's data.
        data: String,
    },
}

fn flag_list(flags: &[WarningFlag]) -> String {
    flags.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
}

impl From<ZaberError> for AimError {
    fn from(error: ZaberError) -> Self {
        match error {
            ZaberError::Line(_) | ZaberError::NoReply { .. } => AimError::Disconnected { reason: error.to_string() },
            ZaberError::Config { .. } => AimError::InvalidArgument { detail: error.to_string() },
            _ => AimError::Device { message: error.to_string() },
        }
    }
}

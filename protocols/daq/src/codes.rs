//! The coded one-byte fields: error codes, stop reasons and sample-packet flags.

use std::fmt;

use crate::error::DaqError;

/// Why the device refused a command or reports a fault (the `code` byte of an `Error` message).
///
/// Code 0 is invalid, so that a zeroed buffer never reads as an error code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorCode {
    /// 1: the configuration is malformed or unsupported (no channels, a channel index the device does not have, a
    /// duplicated channel, a range the device does not offer, a packet size of 0 or too large for one frame).
    BadConfig,
    /// 2: the sample rate is 0, or the rate times the number of channels exceeds the device's aggregate maximum.
    RateOutOfRange,
    /// 3: `Start` before any accepted `Configure` (or after `Reset`).
    NotConfigured,
    /// 4: `Configure` or `Start` while an acquisition runs.
    AlreadyRunning,
    /// 5: the device's sample buffer overflowed so badly that it stopped (a `Stopped` follows).
    BufferOverrun,
    /// 6: the acquisition hardware failed (a `Stopped` follows if an acquisition was running).
    HardwareFault,
    /// 7: a well-formed command of a type or protocol version the device does not support.
    UnsupportedCommand,
    /// 8: a command frame that failed its CRC or whose payload was malformed.
    MalformedCommand,
}

impl ErrorCode {
    /// All codes, in wire order.
    pub const ALL: [ErrorCode; 8] = [
        ErrorCode::BadConfig,
        ErrorCode::RateOutOfRange,
        ErrorCode::NotConfigured,
        ErrorCode::AlreadyRunning,
        ErrorCode::BufferOverrun,
        ErrorCode::HardwareFault,
        ErrorCode::UnsupportedCommand,
        ErrorCode::MalformedCommand,
    ];

    /// The wire byte (1 to 8).
    pub fn code(self) -> u8 {
        match self {
            ErrorCode::BadConfig => 1,
            ErrorCode::RateOutOfRange => 2,
            ErrorCode::NotConfigured => 3,
            ErrorCode::AlreadyRunning => 4,
            ErrorCode::BufferOverrun => 5,
            ErrorCode::HardwareFault => 6,
            ErrorCode::UnsupportedCommand => 7,
            ErrorCode::MalformedCommand => 8,
        }
    }

    /// The code for a wire byte.
    ///
    /// # Errors
    /// [`DaqError::InvalidField`] for 0 and for bytes above 8.
    pub fn from_code(code: u8) -> Result<Self, DaqError> {
        Self::ALL.into_iter().find(|c| c.code() == code).ok_or(DaqError::InvalidField {
            message: "Error",
            field: "code",
            value: u64::from(code),
            reason: "error codes are 1 to 8",
        })
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self:?} (code {})", self.code())
    }
}

/// Why an acquisition ended (the `reason` byte of a `Stopped` message). Code 0 is invalid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StopReason {
    /// 1: the host sent `Stop`.
    HostRequest,
    /// 2: the device's sample buffer overflowed and it could not continue.
    BufferOverrun,
    /// 3: the acquisition hardware failed.
    HardwareFault,
    /// 4: the host sent `Reset`.
    Reset,
}

impl StopReason {
    /// All reasons, in wire order.
    pub const ALL: [StopReason; 4] =
        [StopReason::HostRequest, StopReason::BufferOverrun, StopReason::HardwareFault, StopReason::Reset];

    /// The wire byte (1 to 4).
    pub fn code(self) -> u8 {
        match self {
            StopReason::HostRequest => 1,
            StopReason::BufferOverrun => 2,
            StopReason::HardwareFault => 3,
            StopReason::Reset => 4,
        }
    }

    /// The reason for a wire byte.
    ///
    /// # Errors
    /// [`DaqError::InvalidField`] for 0 and for bytes above 4.
    pub fn from_code(code: u8) -> Result<Self, DaqError> {
        Self::ALL.into_iter().find(|r| r.code() == code).ok_or(DaqError::InvalidField {
            message: "Stopped",
            field: "reason",
            value: u64::from(code),
            reason: "stop reasons are 1 to 4",
        })
    }
}

/// The flags byte of a `Samples` packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SampleFlags {
    /// Bit 0: samples were lost (the device's buffer overflowed) between the previous packet and this one; the
    /// packet's `first_sample_index` skips the lost samples.
    pub overrun: bool,
    /// Bit 1: at least one sample in this packet sits on a rail (`i16::MIN` or `i16::MAX`): the input exceeded the
    /// configured range.
    pub clipped: bool,
}

impl SampleFlags {
    const OVERRUN: u8 = 1 << 0;
    const CLIPPED: u8 = 1 << 1;

    /// The wire byte.
    pub fn bits(self) -> u8 {
        (if self.overrun { Self::OVERRUN } else { 0 }) | (if self.clipped { Self::CLIPPED } else { 0 })
    }

    /// The flags of a wire byte.
    ///
    /// # Errors
    /// [`DaqError::InvalidField`] if a reserved bit (2 to 7) is set.
    pub fn from_bits(bits: u8) -> Result<Self, DaqError> {
        if bits & !(Self::OVERRUN | Self::CLIPPED) != 0 {
            return Err(DaqError::InvalidField {
                message: "Samples",
                field: "flags",
                value: u64::from(bits),
                reason: "bits 2 to 7 are reserved and must be 0",
            });
        }
        Ok(Self { overrun: bits & Self::OVERRUN != 0, clipped: bits & Self::CLIPPED != 0 })
    }
}

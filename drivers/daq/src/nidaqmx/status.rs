//! NI-DAQmx's status codes: the ones a lab meets named ([`NiErrorKind`]), and a failed call turned into the
//! [`DaqError`] or [`AimError`] its caller reports, NI's extended error text kept.

use metaplate_core::aim::AimError;
use metaplate_core::daq::DaqError;

/// `DAQmxErrorSamplesNoLongerAvailable`: the input buffer was overwritten before it was read.
pub const ERROR_SAMPLES_NO_LONGER_AVAILABLE: i32 = -200279;
/// `DAQmxErrorSamplesNotYetAvailable`: a read timed out.
pub const ERROR_SAMPLES_NOT_YET_AVAILABLE: i32 = -200284;
/// `DAQmxErrorInvalidDeviceID`: no device of that name.
pub const ERROR_INVALID_DEVICE_ID: i32 = -200220;
/// `DAQmxErrorDevCannotBeAccessed`: the device is there by name but gone (unplugged, reset).
pub const ERROR_DEV_CANNOT_BE_ACCESSED: i32 = -201003;
/// `DAQmxErrorPALResourceReserved`: another task or program holds the channels or timing engine.
pub const ERROR_RESOURCE_RESERVED: i32 = -50103;

/// The NI-DAQmx errors a lab meets, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NiErrorKind {
    /// -200279: samples overwritten before they were read (the host did not keep up).
    Overrun,
    /// -200284: the samples asked for did not arrive within the read timeout (or the start trigger never came).
    Timeout,
    /// -200220: no device of that name (NI MAX lists the names).
    DeviceNotFound,
    /// -201003: the device is gone (unplugged, reset).
    DeviceGone,
    /// -50103: another task or program holds the resource.
    Reserved,
    /// Any other status.
    Other,
}

impl NiErrorKind {
    /// The kind of NI status `code`.
    pub fn of(code: i32) -> Self {
        match code {
            ERROR_SAMPLES_NO_LONGER_AVAILABLE => Self::Overrun,
            ERROR_SAMPLES_NOT_YET_AVAILABLE => Self::Timeout,
            ERROR_INVALID_DEVICE_ID => Self::DeviceNotFound,
            ERROR_DEV_CANNOT_BE_ACCESSED => Self::DeviceGone,
            ERROR_RESOURCE_RESERVED => Self::Reserved,
            _ => Self::Other,
        }
    }

    /// What it means, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Overrun => "overrun: samples no longer available (the buffer was overwritten before it was read)",
            Self::Timeout => {
                "timeout: samples not yet available (none arrived in time, or the start trigger never came)"
            }
            Self::DeviceNotFound => "device not found (is the name the one NI MAX shows?)",
            Self::DeviceGone => "the device cannot be accessed (unplugged or reset?)",
            Self::Reserved => {
                "resource reserved by another task or program (close NI MAX test panels or other programs)"
            }
            Self::Other => "NI-DAQmx error",
        }
    }
}

/// A failed NI-DAQmx call: its status, the call, NI's extended error text. `code` 0 is a failure of this side
/// (an argument that cannot be passed to C).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NiFailure {
    pub(crate) code: i32,
    pub(crate) call: &'static str,
    pub(crate) text: String,
}

impl NiFailure {
    /// A failure before any call (an argument C cannot take).
    pub(crate) fn local(text: String) -> Self {
        Self { code: 0, call: "argument", text }
    }

    /// The kind of this failure.
    pub(crate) fn kind(&self) -> NiErrorKind {
        NiErrorKind::of(self.code)
    }

    /// `DAQmxCall (device Dev1): the kind (code): NI's text`.
    pub(crate) fn detail(&self, device: &str) -> String {
        let text = self.text.trim().replace('\n', " ").replace("  ", " ");
        format!("{} (device {device}): {} ({}): {text}", self.call, self.kind().describe(), self.code)
    }

    /// As the DAQ capability reports it: overrun and timeout by their variants, a missing device `Unavailable`,
    /// a device gone `Disconnected` (a reopen may find it), a reserved resource and the rest `Device` with NI's
    /// code.
    pub(crate) fn daq_error(&self, device: &str) -> DaqError {
        let detail = self.detail(device);
        match self.kind() {
            _ if self.code == 0 => DaqError::Config { detail },
            NiErrorKind::Overrun => DaqError::Overrun { detail },
            NiErrorKind::Timeout => DaqError::Timeout { what: detail, attempts: 1 },
            NiErrorKind::DeviceNotFound => DaqError::Unavailable { detail },
            NiErrorKind::DeviceGone => DaqError::Disconnected { detail },
            NiErrorKind::Reserved | NiErrorKind::Other => DaqError::Device { code: i64::from(self.code), detail },
        }
    }

    /// As the aiming capability reports it: a device gone `Disconnected` (reconnect), a missing device
    /// `Unavailable`, the rest `Device`.
    pub(crate) fn aim_error(&self, device: &str) -> AimError {
        let detail = self.detail(device);
        match self.kind() {
            NiErrorKind::DeviceGone => AimError::Disconnected { reason: detail },
            NiErrorKind::DeviceNotFound => AimError::Unavailable { detail },
            _ => AimError::Device { message: detail },
        }
    }
}

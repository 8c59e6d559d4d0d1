//! The real transport: a HID device through the `hidapi` crate.
//!
//! On Linux the crate is built with its pure-Rust hidraw backend (`linux-native-basic-udev`: devices are found in
//! sysfs), so nothing but the Rust toolchain is needed to build it. Reading `/dev/hidraw*` needs permission: a udev
//! rule such as `KERNEL=="hidraw*", ATTRS{idVendor}=="VVVV", ATTRS{idProduct}=="PPPP", MODE="0660", GROUP="plugdev"`.

use ::hidapi::{DeviceInfo, HidApi, HidDevice, HidError};

use crate::transport::{HidInput, TransportError};

/// Usage page and usage of a keyboard collection (HID Usage Tables: Generic Desktop, Keyboard).
const KEYBOARD_USAGE: (u16, u16) = (0x01, 0x06);
/// Largest input report read at once, bytes (a boot report has 8; full-speed interrupt packets are at most 64).
const MAX_REPORT_LEN: usize = 64;

/// Which device to open. A hardware file writes it as `usb = "VID:PID[:SERIAL]"`, which the driver registry parses
/// (`metaplate_drivers::UsbIds`, the one parser of USB ids).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HidapiSelector {
    /// USB vendor ID.
    pub vendor_id: u16,
    /// USB product ID.
    pub product_id: u16,
    /// Serial number, when several identical pads are plugged in.
    pub serial: Option<String>,
}

/// An open HID device.
pub struct HidapiInput {
    selector: HidapiSelector,
    device: Option<HidDevice>,
    names: (String, String, String),
}

impl HidapiInput {
    /// Opens the device `selector` names. Among its HID interfaces, the keyboard collection (usage page 0x01,
    /// usage 0x06) is preferred: a response pad often also has a consumer-control or vendor interface.
    ///
    /// # Errors
    /// [`TransportError::Disconnected`] when no such device is plugged in; `Unavailable` when it cannot be opened
    /// (permissions); `Io`.
    pub fn open(selector: HidapiSelector) -> Result<Self, TransportError> {
        let mut input = Self { selector, device: None, names: Default::default() };
        input.connect()?;
        Ok(input)
    }

    fn connect(&mut self) -> Result<(), TransportError> {
        self.device = None;
        let wanted = &self.selector;
        let ids = format!("{:04x}:{:04x}", wanted.vendor_id, wanted.product_id);
        let api = HidApi::new().map_err(|e| map_error(&format!("enumerating HID devices to find {ids}"), e))?;
        let matches = |info: &&DeviceInfo| {
            info.vendor_id() == wanted.vendor_id
                && info.product_id() == wanted.product_id
                && wanted.serial.as_deref().is_none_or(|serial| info.serial_number() == Some(serial))
        };
        let candidates: Vec<&DeviceInfo> = api.device_list().filter(matches).collect();
        let info = candidates
            .iter()
            .find(|info| (info.usage_page(), info.usage()) == KEYBOARD_USAGE)
            .or(candidates.first())
            .ok_or_else(|| {
                TransportError::Disconnected(format!(
                    "no HID device {ids}{}",
                    wanted.serial.as_deref().map(|s| format!(" with serial {s}")).unwrap_or_default()
                ))
            })?;
        let device = info.open_device(&api).map_err(|e| map_error(&format!("opening {ids}"), e))?;
        self.names = (
            info.manufacturer_string().unwrap_or_default().to_string(),
            info.product_string().unwrap_or_default().to_string(),
            info.serial_number().unwrap_or_default().to_string(),
        );
        self.device = Some(device);
        Ok(())
    }
}

/// A HID device that looks like a keypad, as `metaplate devices` lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HidListing {
    /// `VID:PID` or `VID:PID:SERIAL` (hex ids), as the hardware file's `keypad.usb` takes it.
    pub usb: String,
    /// Manufacturer and product as the device names itself.
    pub description: String,
}

/// Every HID interface with a keyboard or keypad collection (usage page 0x01, usage 0x06 or 0x07), once per
/// device.
///
/// # Errors
/// As [`HidapiInput::open`] when the HID devices cannot be enumerated.
pub fn keypads() -> Result<Vec<HidListing>, TransportError> {
    let api = HidApi::new().map_err(|e| map_error("enumerating HID devices", e))?;
    let mut found: Vec<HidListing> = Vec::new();
    for info in api.device_list() {
        if info.usage_page() != KEYBOARD_USAGE.0 || !matches!(info.usage(), 0x06 | 0x07) {
            continue;
        }
        let ids = format!("{:04x}:{:04x}", info.vendor_id(), info.product_id());
        let usb = match info.serial_number().filter(|s| !s.is_empty()) {
            Some(serial) => format!("{ids}:{serial}"),
            None => ids,
        };
        let description = [info.manufacturer_string().unwrap_or_default(), info.product_string().unwrap_or_default()]
            .join(" ")
            .trim()
            .to_owned();
        if !found.iter().any(|f| f.usb == usb) {
            found.push(HidListing { usb, description });
        }
    }
    Ok(found)
}

/// Maps a hidapi error to a [`TransportError`].
fn map_error(doing: &str, error: HidError) -> TransportError {
    let detail = format!("{doing}: {error}");
    match &error {
        HidError::IoError { error } => match error.raw_os_error() {
            Some(libc::ENODEV | libc::ENOENT | libc::EIO | libc::ESHUTDOWN) => TransportError::Disconnected(detail),
            Some(libc::EACCES | libc::EPERM) => {
                TransportError::Unavailable(format!("{detail} (no permission on /dev/hidraw*: see the udev rule)"))
            }
            _ => TransportError::Io(detail),
        },
        // The hidraw backend reports a hang-up on the file as this message.
        HidError::HidApiError { message } if message.contains("disconnected") || message.contains("not found") => {
            TransportError::Disconnected(detail)
        }
        HidError::InitializationError => TransportError::Unavailable(detail),
        _ => TransportError::Io(detail),
    }
}

impl HidInput for HidapiInput {
    fn describe(&self) -> (String, String, String) {
        self.names.clone()
    }

    fn read_report(&mut self, timeout_s: f64) -> Result<Option<Vec<u8>>, TransportError> {
        let device = self.device.as_ref().ok_or_else(|| TransportError::Disconnected("device closed".into()))?;
        // Whole milliseconds, rounded up so that a short timeout still waits; capped at hidapi's i32.
        let timeout_ms = if timeout_s.is_finite() && timeout_s > 0.0 {
            (timeout_s * 1e3).ceil().min(f64::from(i32::MAX)) as i32
        } else {
            0
        };
        let mut buffer = [0_u8; MAX_REPORT_LEN];
        match device.read_timeout(&mut buffer, timeout_ms) {
            Ok(0) => Ok(None),
            Ok(len) => Ok(Some(buffer[..len.min(MAX_REPORT_LEN)].to_vec())),
            Err(error) => {
                let error = map_error("reading a report", error);
                if matches!(error, TransportError::Disconnected(_)) {
                    self.device = None;
                }
                Err(error)
            }
        }
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        self.connect()
    }
}

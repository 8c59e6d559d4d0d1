//! The real transport: an RS-232 port (usually a USB adapter) through `serialport`, built without libudev.

use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use serialport::{DataBits, FlowControl, Parity, SerialPort, SerialPortType, StopBits};

use crate::line::{BAUD_RATE, LineError, PortSelector, SerialLine};

/// The controller's serial port. Reads wait in real time; after a disconnect every call fails with
/// [`LineError::Disconnected`] until [`SerialLine::reopen`] succeeds.
pub struct SerialPortLine {
    selector: PortSelector,
    baud_rate: u32,
    port: Option<Box<dyn SerialPort>>,
}

impl std::fmt::Debug for SerialPortLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SerialPortLine")
            .field("selector", &self.selector)
            .field("baud_rate", &self.baud_rate)
            .field("open", &self.port.is_some())
            .finish()
    }
}

impl SerialPortLine {
    /// Opens the port named by `selector` at 115200 baud 8N1, no flow control.
    ///
    /// # Errors
    /// [`LineError::Disconnected`] when no port matches or it cannot be opened (absent, busy, no permission).
    pub fn open(selector: PortSelector) -> Result<Self, LineError> {
        Self::open_at(selector, BAUD_RATE)
    }

    /// Opens the port named by `selector` at `baud_rate` 8N1, no flow control (another instrument on the same
    /// transport: Zaber stages, whose rate the hardware file names).
    ///
    /// # Errors
    /// [`LineError::Disconnected`] when no port matches or it cannot be opened (absent, busy, no permission).
    pub fn open_at(selector: PortSelector, baud_rate: u32) -> Result<Self, LineError> {
        let port = open_port(&selector, baud_rate)?;
        Ok(Self { selector, baud_rate, port: Some(port) })
    }

    /// The selector this line reopens with.
    pub fn selector(&self) -> &PortSelector {
        &self.selector
    }

    fn port(&mut self) -> Result<&mut Box<dyn SerialPort>, LineError> {
        self.port.as_mut().ok_or_else(|| LineError::Disconnected { reason: "port closed after an error".into() })
    }

    /// Marks the port gone, so that later calls fail fast until a reopen.
    fn lost(&mut self, reason: String) -> LineError {
        self.port = None;
        LineError::Disconnected { reason }
    }
}

impl SerialLine for SerialPortLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        let port = self.port()?;
        match port.write_all(bytes).and_then(|()| port.flush()) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == ErrorKind::TimedOut => Err(LineError::Timeout),
            Err(e) => Err(self.lost(format!("write failed: {e}"))),
        }
    }

    fn read(&mut self, buf: &mut [u8], timeout_s: f64) -> Result<usize, LineError> {
        // A bad timeout (negative, NaN, beyond Duration) waits nothing rather than forever.
        let timeout = Duration::try_from_secs_f64(timeout_s).unwrap_or(Duration::ZERO);
        let port = self.port()?;
        if let Err(e) = port.set_timeout(timeout) {
            return Err(self.lost(format!("cannot set the read timeout: {e}")));
        }
        match port.read(buf) {
            // A tty that polls readable and then reads nothing has hung up.
            Ok(0) => Err(self.lost("end of file (hang-up)".into())),
            Ok(n) => Ok(n),
            Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted) => {
                Err(LineError::Timeout)
            }
            Err(e) => Err(self.lost(format!("read failed: {e}"))),
        }
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        // Close first: the port is opened exclusively (TIOCEXCL), so the old handle would block the new one.
        self.port = None;
        self.port = Some(open_port(&self.selector, self.baud_rate)?);
        Ok(())
    }
}

fn open_port(selector: &PortSelector, baud_rate: u32) -> Result<Box<dyn SerialPort>, LineError> {
    let path = match selector {
        PortSelector::Path(path) => path.clone(),
        PortSelector::UsbSerial(serial) => find_by_usb_serial(serial)?,
    };
    let name = path.to_string_lossy().into_owned();
    serialport::new(name.clone(), baud_rate)
        .data_bits(DataBits::Eight)
        .parity(Parity::None)
        .stop_bits(StopBits::One)
        .flow_control(FlowControl::None)
        .timeout(Duration::from_millis(250))
        .open()
        .map_err(|e| LineError::Disconnected { reason: format!("cannot open {name}: {e}") })
}

/// A serial port the system lists, with its USB adapter's identity where it has one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PortListing {
    /// The device path to name in a hardware file (`ldv.port`).
    pub path: PathBuf,
    /// USB vendor and product id of the adapter, if it is one.
    pub usb_ids: Option<(u16, u16)>,
    /// USB serial number of the adapter (usable as [`PortSelector::UsbSerial`]), if it reports one.
    pub usb_serial: Option<String>,
    /// Manufacturer and product strings of the adapter, empty when unknown.
    pub description: String,
}

/// The serial ports this system lists (empty when it lists none).
///
/// # Errors
/// [`LineError::Disconnected`] with the operating system's reason when the ports cannot be listed (on Linux
/// without `/sys/class/tty`, say a container, the list is empty instead: `serialport` would panic there).
pub fn available_ports() -> Result<Vec<PortListing>, LineError> {
    if !Path::new("/sys/class/tty").is_dir() && cfg!(target_os = "linux") {
        return Ok(Vec::new());
    }
    let ports = serialport::available_ports()
        .map_err(|e| LineError::Disconnected { reason: format!("cannot list serial ports: {e}") })?;
    Ok(ports
        .into_iter()
        .map(|port| {
            let (usb_ids, usb_serial, description) = match port.port_type {
                SerialPortType::UsbPort(usb) => {
                    let names = [usb.manufacturer.unwrap_or_default(), usb.product.unwrap_or_default()];
                    (Some((usb.vid, usb.pid)), usb.serial_number, names.join(" ").trim().to_string())
                }
                _ => (None, None, String::new()),
            };
            PortListing { path: PathBuf::from(port.port_name), usb_ids, usb_serial, description }
        })
        .collect())
}

/// The port whose USB adapter reports serial number `serial` (exact match).
fn find_by_usb_serial(serial: &str) -> Result<PathBuf, LineError> {
    // Without libudev, serialport lists ports from sysfs and panics when /sys/class/tty is missing: look first.
    if !Path::new("/sys/class/tty").is_dir() && cfg!(target_os = "linux") {
        return Err(LineError::Disconnected {
            reason: "no /sys/class/tty to look up USB serial numbers: open by /dev/serial/by-id/... path".into(),
        });
    }
    let ports = serialport::available_ports()
        .map_err(|e| LineError::Disconnected { reason: format!("cannot list serial ports: {e}") })?;
    ports
        .into_iter()
        .find(|port| matches!(&port.port_type, SerialPortType::UsbPort(usb) if usb.serial_number.as_deref() == Some(serial)))
        .map(|port| PathBuf::from(port.port_name))
        .ok_or_else(|| LineError::Disconnected {
            reason: format!(
                "no serial port with USB serial number {serial:?} (if the system lists no USB metadata, open by \
                 /dev/serial/by-id/... path)"
            ),
        })
}

//! The narrow transport the driver needs: a byte line with timed reads, that can be reopened; and how a real port
//! is named (built without the `serial` backend, so that a hardware file can be checked anywhere).

use std::path::PathBuf;

/// The controller's line settings: 115200 baud, 8N1, no flow control (the rate PLACE opens a Polytec controller at:
/// `place/automate/polytec/vibrometer.py`, `baudPolytec=115200`; the interface's `BaudRate` attribute can change it).
pub const BAUD_RATE: u32 = 115_200;

/// Where to find the controller's port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PortSelector {
    /// A device path: `/dev/ttyUSB0`, or better a stable one such as `/dev/serial/by-id/usb-FTDI_..._SN04512-if00-port0`
    /// (udev's by-id links name the adapter's serial number and survive re-enumeration).
    Path(PathBuf),
    /// The USB serial number of the adapter, looked up with `serialport::available_ports()` at every open. Without
    /// libudev that listing reads sysfs (`/sys/class/tty`); where sysfs carries no USB metadata (some containers,
    /// non-Linux systems without it), the lookup finds nothing: use a `/dev/serial/by-id/...` [`PortSelector::Path`]
    /// instead.
    UsbSerial(String),
}

/// Why a line operation failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    /// No byte arrived within the read's timeout. The line is still up.
    #[error("no data within the timeout")]
    Timeout,
    /// The line is gone (device unplugged, port closed, I/O error); only [`SerialLine::reopen`] can bring it back.
    #[error("line disconnected: {reason}")]
    Disconnected {
        /// What the operating system or the mock reported.
        reason: String,
    },
}

/// A serial line to one device: the real port (`SerialPortLine`, feature `serial`) or a mock.
///
/// Reads are bounded: an implementation waits at most the timeout it is given, in real time for a real port; a
/// mock that has decided not to answer returns [`LineError::Timeout`] at once, so simulated faults cost no wall
/// time.
pub trait SerialLine: Send {
    /// Writes every byte of `bytes` (and flushes them to the device).
    ///
    /// # Errors
    /// [`LineError::Disconnected`] when the line is gone; [`LineError::Timeout`] when the device does not take the
    /// bytes in time.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError>;

    /// Reads the bytes available, at most `buf.len()`, waiting up to `timeout_s` seconds for the first one;
    /// returns how many were read, at least 1. Valid range: `timeout_s >= 0` (a negative or NaN timeout waits
    /// nothing).
    ///
    /// # Errors
    /// [`LineError::Timeout`] when nothing arrived in time; [`LineError::Disconnected`] when the line is gone.
    fn read(&mut self, buf: &mut [u8], timeout_s: f64) -> Result<usize, LineError>;

    /// Closes the line (if open) and opens it again, finding the device afresh (a USB adapter may come back under
    /// another name). Bytes in flight are lost.
    ///
    /// # Errors
    /// [`LineError::Disconnected`] when the device cannot be opened (yet).
    fn reopen(&mut self) -> Result<(), LineError>;
}

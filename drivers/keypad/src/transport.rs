//! The narrow transport of the keypad driver: HID input reports from one device.

/// Why the HID link failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TransportError {
    /// The device is gone (unplugged) or not found; reopening may bring it back.
    #[error("HID device disconnected or absent: {0}")]
    Disconnected(String),
    /// The device exists but cannot be used here (permissions on `/dev/hidraw*`, another backend missing).
    #[error("HID device unavailable: {0}")]
    Unavailable(String),
    /// Any other I/O failure.
    #[error("HID I/O error: {0}")]
    Io(String),
}

/// Input reports from one HID device.
pub trait HidInput: Send {
    /// Short names of the device: (manufacturer, product, serial number), empty when unknown.
    fn describe(&self) -> (String, String, String);

    /// Waits at most `timeout_s` seconds (valid range: finite, >= 0; 0 polls) for one input report and returns its
    /// bytes (with the report ID first only if the device uses report IDs), or `None` when none came in time.
    ///
    /// # Errors
    /// [`TransportError`].
    fn read_report(&mut self, timeout_s: f64) -> Result<Option<Vec<u8>>, TransportError>;

    /// Closes and reopens the device by the identity it was opened with.
    ///
    /// # Errors
    /// [`TransportError::Disconnected`] while it is still absent.
    fn reopen(&mut self) -> Result<(), TransportError>;
}

/// A boxed transport is a transport, so that a keypad can be built on whichever backend a hardware file names.
impl<T: HidInput + ?Sized> HidInput for Box<T> {
    fn describe(&self) -> (String, String, String) {
        (**self).describe()
    }

    fn read_report(&mut self, timeout_s: f64) -> Result<Option<Vec<u8>>, TransportError> {
        (**self).read_report(timeout_s)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        (**self).reopen()
    }
}

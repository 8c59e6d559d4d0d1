//! The narrow transport a bulk DAQ driver needs: one OUT and one IN bulk endpoint, with timeouts, and a way to
//! reconnect.

use std::time::Duration;

/// Why a transfer failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TransportError {
    /// Nothing was transferred within the timeout (for IN: the device had nothing to send). The exchange may be
    /// retried.
    #[error("transfer timed out")]
    Timeout,
    /// The endpoint stalled (the device signalled an error on it); the transport has cleared the halt, so the
    /// exchange may be retried.
    #[error("endpoint stalled")]
    Stall,
    /// The device is gone; only [`BulkTransport::reopen`] can help.
    #[error("device disconnected: {0}")]
    Disconnected(String),
    /// Any other failure of the transport (permissions, a fault on the bus).
    #[error("transport failure: {0}")]
    Other(String),
}

/// One bulk OUT and one bulk IN endpoint of a device.
///
/// Implemented by [`crate::UsbTransport`] (a real device through nusb) and by the mock DAQ's in-process
/// transport.
pub trait BulkTransport {
    /// Sends `bytes` as one OUT transfer, waiting at most `timeout`.
    ///
    /// # Errors
    /// [`TransportError`]: `Timeout` or `Stall` (retryable), `Disconnected`, `Other`.
    fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), TransportError>;

    /// Receives one IN transfer (the bytes of zero or more whole or partial frames), waiting at most `timeout` for
    /// it to begin.
    ///
    /// # Errors
    /// As [`write`](Self::write); `Timeout` when the device had nothing to send.
    fn read(&mut self, timeout: Duration) -> Result<Vec<u8>, TransportError>;

    /// Closes and opens the same device again (found by its serial number), for recovery after
    /// [`TransportError::Disconnected`].
    ///
    /// # Errors
    /// `Disconnected` if the device is still absent, `Other` if it cannot be claimed.
    fn reopen(&mut self) -> Result<(), TransportError>;
}

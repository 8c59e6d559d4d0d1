//! The narrow transport the U6 driver needs: the bulk OUT endpoint of commands, the bulk IN endpoint of their
//! responses and the bulk IN endpoint of stream data, with timeouts, and a way to reconnect.

use std::time::Duration;

/// Which device, interface and endpoints to use.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UsbSelector {
    /// USB vendor id.
    pub vendor_id: u16,
    /// USB product id.
    pub product_id: u16,
    /// Serial number string descriptor; `None` takes the first device with these ids (only for a lab with one).
    pub serial: Option<String>,
    /// Interface number that carries the bulk endpoints.
    pub interface: u8,
    /// Bulk OUT endpoint address (commands): `0x01` on a U6.
    pub endpoint_out: u8,
    /// Bulk IN endpoint address of command responses: `0x82` on a U6.
    pub endpoint_in: u8,
    /// Bulk IN endpoint address of stream data: `0x83` on a U6.
    pub endpoint_stream: u8,
}

impl UsbSelector {
    /// A LabJack U6 (vendor `0x0CD5`, product `0x0006`, interface 0, endpoints `0x01`, `0x82`, `0x83`: the
    /// Exodriver's `labjackusb.h`), by its serial number if given.
    pub fn u6(serial: Option<String>) -> Self {
        use metaplate_u6_protocol as u6;
        Self {
            vendor_id: u6::VENDOR_ID,
            product_id: u6::PRODUCT_ID,
            serial,
            interface: 0,
            endpoint_out: u6::ENDPOINT_COMMAND_OUT,
            endpoint_in: u6::ENDPOINT_RESPONSE_IN,
            endpoint_stream: u6::ENDPOINT_STREAM_IN,
        }
    }
}

/// Replaces the open handle in `slot` by a fresh one from `open`, dropping the old one *first*: a device's
/// interface (or a port) can be claimed by one handle at a time, so opening before closing fails against a device
/// that is there. On failure the slot stays empty (the transport reports `Disconnected` until a reopen succeeds).
///
/// # Errors
/// `open`'s error.
pub fn reopen_dropping_first<H, E>(slot: &mut Option<H>, open: impl FnOnce() -> Result<H, E>) -> Result<(), E> {
    drop(slot.take());
    *slot = Some(open()?);
    Ok(())
}

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

/// The bulk endpoints of a U6: commands out, responses in, stream data in.
///
/// Implemented by `UsbTransport` (feature `usb`: a real device through nusb), by the mock U6's in-process
/// transport and by the replay's cassette transport.
pub trait BulkTransport {
    /// Sends `bytes` as one OUT transfer, waiting at most `timeout`.
    ///
    /// # Errors
    /// [`TransportError`]: `Timeout` or `Stall` (retryable), `Disconnected`, `Other`.
    fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), TransportError>;

    /// Receives one IN transfer on the response endpoint (one response), waiting at most `timeout` for it.
    ///
    /// # Errors
    /// As [`write`](Self::write); `Timeout` when the device had nothing to send.
    fn read(&mut self, timeout: Duration) -> Result<Vec<u8>, TransportError>;

    /// Receives one IN transfer of at most `max_len` bytes on the stream endpoint (whole StreamData packets),
    /// waiting at most `timeout` for it.
    ///
    /// # Errors
    /// As [`read`](Self::read).
    fn read_stream(&mut self, max_len: usize, timeout: Duration) -> Result<Vec<u8>, TransportError>;

    /// Closes and opens the same device again (found by its serial number), for recovery after
    /// [`TransportError::Disconnected`].
    ///
    /// # Errors
    /// `Disconnected` if the device is still absent, `Other` if it cannot be claimed.
    fn reopen(&mut self) -> Result<(), TransportError>;
}

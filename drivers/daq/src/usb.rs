//! The real bulk transport: a LabJack U6 (or any device with the same three bulk endpoints) found by vendor id,
//! product id and serial number, through nusb (blocking calls, no async runtime). Never exercised in CI; the
//! opt-in real-device test uses it.

use std::time::Duration;

use nusb::transfer::{Buffer, Bulk, Completion, In, Out, TransferError};
use nusb::{Endpoint, Interface, MaybeFuture};

use crate::transport::{BulkTransport, TransportError, UsbSelector, reopen_dropping_first};

/// A U6 on USB, found by vendor id, product id and serial number; its handles are absent between a failed reopen
/// and the next successful one (every transfer is then `Disconnected`).
pub struct UsbTransport {
    selector: UsbSelector,
    link: Option<UsbLink>,
}

/// The open device: its claimed interface and its three bulk endpoints.
struct UsbLink {
    ep_out: Endpoint<Bulk, Out>,
    ep_in: Endpoint<Bulk, In>,
    ep_stream: Endpoint<Bulk, In>,
    /// Kept so the interface stays claimed while the endpoints are in use.
    _interface: Interface,
}

/// A device this system lists on USB (for `metaplate devices`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UsbListing {
    /// USB vendor id.
    pub vendor_id: u16,
    /// USB product id.
    pub product_id: u16,
    /// Serial number string descriptor, if the device has one.
    pub serial: Option<String>,
    /// Manufacturer and product strings, empty when unknown.
    pub description: String,
}

/// The USB devices this system lists (empty when there are none, and on Linux when the machine has no USB bus:
/// no `/sys/bus/usb`, as in many virtual machines and containers).
///
/// # Errors
/// [`TransportError::Other`] when the bus cannot be listed.
pub fn usb_devices() -> Result<Vec<UsbListing>, TransportError> {
    if cfg!(target_os = "linux") && !std::path::Path::new("/sys/bus/usb/devices").exists() {
        return Ok(Vec::new());
    }
    let devices = nusb::list_devices().wait().map_err(|e| nusb_error("listing USB devices", e))?;
    Ok(devices
        .map(|d| {
            let names = [d.manufacturer_string().unwrap_or_default(), d.product_string().unwrap_or_default()];
            UsbListing {
                vendor_id: d.vendor_id(),
                product_id: d.product_id(),
                serial: d.serial_number().map(str::to_string),
                description: names.join(" ").trim().to_string(),
            }
        })
        .collect())
}

impl std::fmt::Debug for UsbTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("UsbTransport").field("selector", &self.selector).finish_non_exhaustive()
    }
}

fn other(context: &str, e: impl std::fmt::Display) -> TransportError {
    TransportError::Other(format!("{context}: {e}"))
}

fn nusb_error(context: &str, e: nusb::Error) -> TransportError {
    match e.kind() {
        nusb::ErrorKind::Disconnected => TransportError::Disconnected(format!("{context}: {e}")),
        _ => other(context, e),
    }
}

impl UsbTransport {
    /// Finds the device, opens it and claims the interface and endpoints.
    ///
    /// # Errors
    /// [`TransportError::Disconnected`] if no device matches; [`TransportError::Other`] if it cannot be opened or
    /// claimed (permissions, a kernel driver holding it, no such endpoint).
    pub fn open(selector: UsbSelector) -> Result<Self, TransportError> {
        let link = open_link(&selector)?;
        Ok(Self { selector, link: Some(link) })
    }

    /// The open link, or `Disconnected` after a failed reopen.
    fn link(&mut self) -> Result<&mut UsbLink, TransportError> {
        self.link.as_mut().ok_or_else(|| TransportError::Disconnected("the device is closed (reopen failed)".into()))
    }
}

/// Finds the device, opens it and claims the interface and endpoints (see [`UsbTransport::open`]).
fn open_link(selector: &UsbSelector) -> Result<UsbLink, TransportError> {
    let found = nusb::list_devices()
        .wait()
        .map_err(|e| nusb_error("listing USB devices", e))?
        .find(|d| {
            d.vendor_id() == selector.vendor_id
                && d.product_id() == selector.product_id
                && selector.serial.as_deref().is_none_or(|s| d.serial_number() == Some(s))
        })
        .ok_or_else(|| {
            TransportError::Disconnected(format!(
                "no USB device {:04x}:{:04x} with serial {:?}",
                selector.vendor_id, selector.product_id, selector.serial
            ))
        })?;
    let device = found.open().wait().map_err(|e| nusb_error("opening the device", e))?;
    let interface =
        device.claim_interface(selector.interface).wait().map_err(|e| nusb_error("claiming the interface", e))?;
    let ep_out = interface
        .endpoint::<Bulk, Out>(selector.endpoint_out)
        .map_err(|e| nusb_error("opening the bulk OUT endpoint", e))?;
    let ep_in = interface
        .endpoint::<Bulk, In>(selector.endpoint_in)
        .map_err(|e| nusb_error("opening the bulk IN endpoint", e))?;
    let ep_stream = interface
        .endpoint::<Bulk, In>(selector.endpoint_stream)
        .map_err(|e| nusb_error("opening the bulk IN stream endpoint", e))?;
    Ok(UsbLink { ep_out, ep_in, ep_stream, _interface: interface })
}

/// Maps a completed transfer's status; a stall is cleared here so the caller may retry.
fn status<Dir: nusb::transfer::EndpointDirection>(
    completion: &Completion,
    endpoint: &mut Endpoint<Bulk, Dir>,
) -> Result<(), TransportError> {
    match completion.status {
        Ok(()) => Ok(()),
        Err(TransferError::Cancelled) => Err(TransportError::Timeout),
        Err(TransferError::Stall) => {
            endpoint.clear_halt().wait().map_err(|e| nusb_error("clearing a stall", e))?;
            Err(TransportError::Stall)
        }
        Err(TransferError::Disconnected) => Err(TransportError::Disconnected("during a transfer".into())),
        Err(e) => Err(other("transfer", e)),
    }
}

impl BulkTransport for UsbTransport {
    fn write(&mut self, bytes: &[u8], timeout: Duration) -> Result<(), TransportError> {
        // `transfer_blocking` asserts that nothing is pending; this transport never leaves a transfer pending.
        let link = self.link()?;
        if link.ep_out.pending() != 0 {
            return Err(TransportError::Other("a previous OUT transfer is still pending".into()));
        }
        let completion = link.ep_out.transfer_blocking(Buffer::from(bytes.to_vec()), timeout);
        status(&completion, &mut link.ep_out)
    }

    fn read(&mut self, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        // The longest U6 response (ReadMem, 40 bytes) fits one 64-byte packet.
        read_in(&mut self.link()?.ep_in, 64, timeout)
    }

    fn read_stream(&mut self, max_len: usize, timeout: Duration) -> Result<Vec<u8>, TransportError> {
        read_in(&mut self.link()?.ep_stream, max_len, timeout)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        // The old handle still claims the interface: it must be released before the device is claimed again.
        let selector = &self.selector;
        reopen_dropping_first(&mut self.link, || open_link(selector))
    }
}

/// One IN transfer of up to `max_len` bytes (rounded up to whole max-size packets, as IN requests must be).
fn read_in(endpoint: &mut Endpoint<Bulk, In>, max_len: usize, timeout: Duration) -> Result<Vec<u8>, TransportError> {
    // `transfer_blocking` asserts that nothing is pending; this transport never leaves a transfer pending.
    if endpoint.pending() != 0 {
        return Err(TransportError::Other("a previous IN transfer is still pending".into()));
    }
    let packet = endpoint.max_packet_size().max(1);
    let len = max_len.max(1).div_ceil(packet) * packet;
    let completion = endpoint.transfer_blocking(endpoint.allocate(len), timeout);
    let received = completion.buffer.get(..completion.actual_len).map(<[u8]>::to_vec).unwrap_or_default();
    match status(&completion, endpoint) {
        // A transfer cancelled at the timeout may still have carried bytes: keep them.
        Err(TransportError::Timeout) if !received.is_empty() => Ok(received),
        Err(e) => Err(e),
        Ok(()) => Ok(received),
    }
}

//! DAQ drivers: the [`Daq`](metaplate_core::daq::Daq) capability on real and simulated hardware.
//!
//! - [`DaqDriver`]: metaplate's documented DAQ bulk protocol (`metaplate-daq-protocol`) over any
//!   [`BulkTransport`]: command/reply matching by sequence number, timeouts with bounded retries, draining of
//!   stale replies, stream integrity (lost packets, overruns, clipping), and reopen with the configuration
//!   re-applied. The mock DAQ (`metaplate-mock-daq`) provides an in-process transport.
//! - `UsbTransport` (feature `usb`): a real device on USB bulk endpoints through nusb.
//! - `NiDaqmx` (feature `nidaqmx`): NI DAQs (the paper's USB-6211 speaks a proprietary protocol) through NI's
//!   NI-DAQmx C library, loaded at run time.
//!
//! Without features the crate holds the transport trait and the driver logic only (what the mock DAQ needs).
//!
//! Unsafe code: the workspace forbids it; this crate lowers that to `deny` in its `Cargo.toml` and allows it in
//! the `nidaqmx` module only (foreign calls into NI-DAQmx).

pub mod driver;
#[cfg(feature = "nidaqmx")]
pub mod nidaqmx;
pub mod transport;
#[cfg(feature = "usb")]
pub mod usb;

pub use driver::{DaqDriver, DriverSettings, DriverStats, to_wire};
#[cfg(feature = "nidaqmx")]
pub use nidaqmx::{NiDaqmx, device_names as nidaqmx_device_names};
pub use transport::{BulkTransport, TransportError, UsbSelector, reopen_dropping_first};
#[cfg(feature = "usb")]
pub use usb::{UsbListing, UsbTransport, usb_devices};

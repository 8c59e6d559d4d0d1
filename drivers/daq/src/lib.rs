//! DAQ drivers: the [`Daq`](metaplate_core::daq::Daq) capability on real and simulated hardware.
//!
//! - [`U6Driver`]: a LabJack U6 over its documented low-level USB functions (`metaplate-u6-protocol`), over any
//!   [`BulkTransport`], the narrow transport trait this crate defines (the command, response and stream
//!   endpoints): the identity (serial number, firmware) and calibration constants read at opening, command and
//!   response matching, timeouts with bounded retries, draining of stale responses, the stream checked per packet
//!   (missed packets, auto-recovery overflows, errorcodes that end it) and cut into blocks, and reopen with the
//!   configuration re-applied. The mock U6 (`metaplate-mock-daq`) provides an in-process transport.
//! - `UsbTransport` (feature `usb`): a real U6 on its USB bulk endpoints through nusb. A reopen drops the old
//!   handle before claiming the interface again ([`reopen_dropping_first`]).
//! - `NiDaqmx` (feature `nidaqmx`): NI DAQs (the paper's USB-6211 speaks a proprietary protocol) through NI's
//!   NI-DAQmx C library, loaded at run time (libloading): inputs with terminal configuration and range per input,
//!   an output waveform whose start triggers the inputs, identity read from the device, NI's errors named; and
//!   `NiMirrorOutputs`, two analog outputs holding static volts for galvanometer mirrors. CI runs it against the
//!   stand-in library of `metaplate-mock-nidaqmx`.
//!
//! Without features the crate holds the transport trait and the driver logic only (what the mock U6 needs). Both
//! features are on by default for this crate's own tests; the workspace depends on the crate without them, and the
//! binary turns them on (through `metaplate-drivers`' `hardware` feature).
//!
//! Unsafe code: the workspace forbids it; this crate lowers that to `deny` in its `Cargo.toml` and allows it in
//! the `nidaqmx::ffi` module only (foreign calls into NI-DAQmx), the only unsafe code of the workspace's drivers.

mod blocks;
pub mod driver;
pub mod nidaqmx;
mod stream_config;
pub mod transport;
#[cfg(feature = "usb")]
pub mod usb;

pub use driver::{DriverSettings, DriverStats, U6Driver};
#[cfg(feature = "nidaqmx")]
pub use nidaqmx::{
    NiDaqmx, NiDevice, NiErrorKind, NiMirrorOutputs, NiOutputWaveform, device_names as nidaqmx_device_names,
    devices as nidaqmx_devices,
};
pub use nidaqmx::{NiInput, NiSettings, StartTrigger, TerminalConfig};
pub use stream_config::to_stream_config;
pub use transport::{BulkTransport, TransportError, UsbSelector, reopen_dropping_first};
#[cfg(feature = "usb")]
pub use usb::{UsbListing, UsbTransport, usb_devices};

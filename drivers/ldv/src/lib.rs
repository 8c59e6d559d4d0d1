//! Drivers of the vibrometer: a Polytec controller over RS-232, or an analog-only vibrometer.
//!
//! - [`PolytecDriver`] implements [`metaplate_core::vibrometer::Vibrometer`] over any [`SerialLine`], the narrow
//!   transport trait this crate defines: the real port (`SerialPortLine`, feature `serial`: `serialport` built
//!   without libudev) or a mock (`metaplate-mock-ldv`, in process, or on a pseudo-terminal through the real
//!   `SerialPortLine`). The command syntax is `metaplate-polytec-protocol`'s; this crate adds the I/O, the bounded
//!   retries ([`RetryPolicy`]), the decoder found by query ([`PolytecConfig`]) and the reconnect.
//! - [`AnalogVibrometer`]: a vibrometer without a remote interface; the range declared in the hardware file is
//!   recorded and nothing is sent.
//!
//! Error policy: before each request the bytes already waiting are discarded; a missing, garbled or unusable
//! reply is sent again, up to [`RetryPolicy::attempts`], then it is a `Timeout`. A `Set` is read back with its
//! `Get`. A vanished line is `Disconnected` at once; `reconnect` reopens it (by path or USB serial number,
//! [`PortSelector`]), connects again and re-applies the settings.
//!
//! The feature `serial` is on by default for this crate's own tests; the workspace depends on the crate without
//! it, so the mock devices and the mock lab link no serial backend. The binary turns it on (through
//! `metaplate-drivers`' `hardware` feature), and so does `metaplate-lab`'s feature `pty`.

mod analog;
mod config;
mod line;
mod link;
mod policy;
mod polytec;
#[cfg(feature = "serial")]
mod serial;

pub use analog::AnalogVibrometer;
pub use config::{DecoderChoice, FocusSpan, MAX_DECODERS, OUTPUT_FULL_SCALE_V, PolytecConfig};
pub use line::{BAUD_RATE, LineError, PortSelector, SerialLine};
pub use policy::RetryPolicy;
pub use polytec::{AppliedSettings, DecoderInfo, PolytecDriver, probe_polytec};
#[cfg(feature = "serial")]
pub use serial::{PortListing, SerialPortLine, available_ports};

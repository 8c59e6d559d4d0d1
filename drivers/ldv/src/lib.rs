//! Driver for the scanning laser Doppler vibrometer's controller on a serial line.
//!
//! [`LdvDriver`] implements [`metaplate_core::vibrometer::Vibrometer`] over any [`SerialLine`], the narrow transport
//! trait this crate defines: the real port (`SerialPortLine`, feature `serial`: `serialport` built without libudev)
//! or a mock (`metaplate-mock-ldv`, in process, or on a pseudo-terminal through the real `SerialPortLine`). The
//! wire protocol, its timeouts and its `SYNC` resynchronisation are specified in `metaplate-ldv-protocol`; this
//! crate adds the I/O, the bounded retries ([`RetryPolicy`]) and the reconnect.
//!
//! Error policy: a missing, garbled or stale reply is retried after a resynchronisation (sending `SYNC <t>` and
//! draining every reply until it comes back); after [`RetryPolicy::attempts`] it is a `Timeout`. A vanished line
//! is `Disconnected` at once; `reconnect` reopens it (by path or USB serial number, [`PortSelector`]) and
//! re-applies the last settings.
//!
//! The feature `serial` is on by default for this crate's own tests; the workspace depends on the crate without
//! it, so the mock devices and the mock lab link no serial backend. The binary turns it on (through
//! `metaplate-drivers`' `hardware` feature), and so does `metaplate-lab`'s feature `pty`.

mod driver;
mod line;
mod policy;
#[cfg(feature = "serial")]
mod serial;

pub use driver::{AppliedSettings, LdvDriver};
pub use line::{BAUD_RATE, LineError, PortSelector, SerialLine};
pub use policy::RetryPolicy;
#[cfg(feature = "serial")]
pub use serial::{PortListing, SerialPortLine, available_ports};

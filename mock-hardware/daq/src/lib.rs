//! The mock DAQ: the device side of metaplate's DAQ bulk protocol, for the simulated lab and for driver tests.
//!
//! - [`MockDaq`]: the device state machine (identity, configuration checked with `Configure::check`, start, stop,
//!   reset, sample packets digitised to 16 bits with clipping from a caller's [`SignalSource`]).
//! - [`MockTransport`]: the device behind an in-process `BulkTransport`, never blocking (fast-forward: samples
//!   are produced as fast as they are read; the sample index is the device's clock).
//! - [`FaultSchedule`]: faults by IN-transfer number, by hand or drawn from a seed: USB stall, disconnect and
//!   reconnect, overrun (recoverable, or fatal).
//!
//! Like every mock device here, it implements the device side of the same protocol behind the same transport trait
//! as the real instrument, so the real driver's code runs against it: in the driver's tests, and in the mock lab
//! (`metaplate-lab`).
//! The wire protocol carries 16-bit codes: the mock lab serves a DAQ of other than 16 bits, or one without clipping,
//! in process instead (`metaplate-lab`'s `direct_daq`).

pub mod device;
pub mod faults;
pub mod transport;

pub use device::{MockDaq, SignalSource, usb6211_info};
pub use faults::{Fault, FaultRates, FaultSchedule};
pub use transport::{MAX_TRANSFER_LEN, MockTransport};

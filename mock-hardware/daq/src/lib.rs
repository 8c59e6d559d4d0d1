//! The mock LabJack U6: the device side of the U6's low-level USB functions, for the simulated lab and for driver
//! tests.
//!
//! - [`MockU6`]: the device state machine (ConfigU6 identity, calibration memory blocks 0-3, StreamConfig checked
//!   with `StreamConfig::check`, StreamStart, StreamStop, StreamData packets digitised with the calibration
//!   constants from a caller's [`SignalSource`], auto-recovery after an overflow as the User's Guide describes it).
//! - [`MockTransport`]: the device behind an in-process `BulkTransport` (commands, responses, stream), never
//!   blocking (fast-forward: scans are produced as fast as they are read; the scan index is the device's clock).
//! - [`FaultSchedule`]: faults by IN-transfer number, by hand or drawn from a seed: USB stall, disconnect and
//!   reconnect, overflow (auto-recovered, or beyond counting), a stream packet lost in transit.
//!
//! Like every mock device here, it implements the device side of the same protocol behind the same transport trait
//! as the real instrument, so the real driver's code runs against it: in the driver's tests, and in the mock lab
//! (`metaplate-lab`). The U6 streams 16-bit codes: the mock lab serves a DAQ of other than 16 bits, or one without
//! clipping, in process instead (`metaplate-lab`'s `direct_daq`).

pub mod device;
pub mod faults;
pub mod transport;

pub use device::{MockU6, SignalSource, u6_info};
pub use faults::{Fault, FaultRates, FaultSchedule};
pub use transport::MockTransport;

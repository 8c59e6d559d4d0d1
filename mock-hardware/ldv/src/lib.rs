//! Mock scanning LDV controller: the device side of the LDV serial protocol (`metaplate-ldv-protocol`), for the
//! mock lab and the driver's tests.
//!
//! - [`MockController`]: the state machine (beam, velocity range, tracking filter, laser, calibration, latched
//!   fault; the signal level from the scene's speckle model under a seed, [`SpeckleModel`]).
//! - [`MockDevice`]: the controller on its link: decodes host bytes with `CommandDecoder`, answers with
//!   `encode_reply`, applies a [`FaultSchedule`] (no reply, late reply, garbled or partial reply, busy, disconnect
//!   with or without power cycle, dropout), deterministic under its seed, and optionally advances a
//!   `VirtualClock` by each command's specified response time.
//! - Served two ways: [`MockLine`], an in-process `SerialLine` for fast tests (timeouts cost no wall time), and
//!   [`PtyServer`], a pseudo-terminal in raw mode served by a background thread (Unix only; elsewhere it refuses to
//!   start), so that the real `SerialPortLine` transport (`metaplate-ldv`'s feature `serial`) is exercised.
//!
//! Like every mock device here, it implements the device side of the same protocol behind the same transport trait
//! as the real instrument, so the real driver's code runs against it: in the driver's tests, and in the mock lab
//! (`metaplate-lab`).

mod controller;
mod device;
mod faults;
mod inprocess;
#[cfg(unix)]
mod pty;
#[cfg(not(unix))]
#[path = "pty_unsupported.rs"]
mod pty;
mod speckle;

pub use controller::{MockController, STANDOFF_M};
pub use device::MockDevice;
pub use faults::{Fault, FaultSchedule, TimedFaults};
pub use inprocess::MockLine;
pub use pty::{PtyError, PtyServer};
pub use speckle::{DROPOUT_LEVEL_PERCENT, SpeckleModel};

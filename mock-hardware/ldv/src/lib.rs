//! Mock Polytec vibrometer controller (OFV-5000 class): the device side of Polytec's RS-232 command syntax
//! (`metaplate-polytec-protocol`), for the mock lab and the driver's tests.
//!
//! - [`UnitSpec`]: what a unit carries (controller and head names and versions, which velocity decoders at which
//!   indices with which ranges and filters, autofocus, echo at power-up); [`UnitSpec::lab_default`] and
//!   [`UnitSpec::place_example`] (the decoder layout of PLACE's example configuration).
//! - [`MockController`]: the state machine (each decoder's range and filters, remote, echo, autofocus; the
//!   signal level from the scene's speckle model at the beam's spot under a seed, [`SpeckleModel`]). The beam is
//!   put on a spot by whoever aims it ([`MockController::set_beam`]: in the mock lab, the lab's in-process aimer):
//!   a Polytec controller does not move the beam.
//! - [`MockDevice`]: the controller on its link: decodes host bytes with `RequestDecoder`, echoes and answers per
//!   the unit's state, applies a [`FaultSchedule`] (a lost line, late, garbled or partial reply, disconnect with
//!   or without power cycle, dropout), deterministic under its seed, and optionally advances a `VirtualClock`.
//! - Served two ways: [`MockLine`], an in-process `SerialLine` for fast tests (timeouts cost no wall time), and
//!   [`PtyServer`], a pseudo-terminal in raw mode served by a background thread (Unix only; elsewhere it refuses to
//!   start), so that the real `SerialPortLine` transport (`metaplate-ldv`'s feature `serial`) is exercised.
//!
//! The transcripts in this crate's tests say where each exchange comes from (PLACE's plugin, the OFV-3001 manual's
//! appendix E.2); what the public sources do not show (the filters' attribute names, the signal level's bounds)
//! is marked as this mock's reading of the syntax.

mod controller;
mod device;
mod faults;
mod inprocess;
#[cfg(unix)]
mod pty;
#[cfg(not(unix))]
#[path = "pty_unsupported.rs"]
mod pty;
mod served;
mod speckle;
mod unit;

pub use controller::{BEAM_RESOLUTION_M, MockController};
pub use device::MockDevice;
pub use faults::{Fault, FaultSchedule, TimedFaults};
pub use inprocess::MockLine;
pub use pty::{PtyError, PtyServer};
pub use served::ServedDevice;
pub use speckle::{DROPOUT_LEVEL_PERCENT, SpeckleModel, quiet_spec};
pub use unit::{DecoderSpec, UnitSpec};

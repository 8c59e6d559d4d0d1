//! Mock chain of Zaber motorised stages: the device side of Zaber's ASCII protocol
//! (`metaplate-zaber-protocol`), for the stage driver's tests (`metaplate-aim`, feature `zaber`) and the stand-in
//! rig.
//!
//! - [`ChainSpec`], [`DeviceSpec`], [`AxisSpec`]: the devices on the line, their addresses and axes, each axis's
//!   travel limits, resolution, speed and power-up position ([`ChainSpec::xy_lsm100`]: two 100 mm linear stages).
//! - [`MockChain`]: the state machine. Replies with device and axis addressing and message ids, `OK`/`RJ` with the
//!   manual's rejection reasons, `BUSY` while a move runs (moves take distance / speed on the clock it is given),
//!   the warning flag of highest priority (`WR` until homed, latched faults from an [`ArmedFault`]), `warnings`
//!   and `warnings clear`, `get` of the settings the driver reads. The module documentation of `chain` cites the
//!   manual's section for each behaviour.
//! - Served two ways: [`ChainLine`], an in-process `SerialLine` (with a `VirtualClock`, moves cost no wall time),
//!   and `metaplate_mock_ldv::PtyServer`, the pseudo-terminal server shared with the mock Polytec controller
//!   ([`MockChain`] implements its `ServedDevice`), so that the real serial transport is exercised.

mod axis;
mod chain;
mod inprocess;
mod spec;

pub use axis::ArmedFault;
pub use chain::MockChain;
pub use inprocess::ChainLine;
pub use metaplate_mock_ldv::{PtyError, PtyServer};
pub use spec::{AxisSpec, ChainSpec, DeviceSpec};

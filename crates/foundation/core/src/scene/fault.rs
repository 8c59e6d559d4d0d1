//! The fault schedule: what the simulated lab breaks, and when.

use serde::{Deserialize, Serialize};

/// A kind of fault the mock hardware can inject. TOML: the snake_case name, e.g. `kind = "serial_timeout"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// The LDV controller stops answering on its serial line.
    SerialTimeout,
    /// The LDV controller answers with corrupted bytes.
    GarbledReply,
    /// The LDV controller's reply is cut short.
    PartialReply,
    /// The DAQ's USB bulk transfers stall.
    UsbStall,
    /// A device disappears from its bus.
    Disconnect,
    /// The DAQ's buffer overflows and samples are lost.
    DaqOverrun,
    /// The audio output runs dry and plays silence.
    AudioUnderrun,
    /// The vibrometer loses its signal (speckle or a dropped beam).
    LdvDropout,
    /// A motorised stage stalls and stops (Zaber's `FS` warning): the stand-in rig's (`metaplate lab serve`) Y
    /// stage on its first move, homing included. Its stages run on the wall clock, so the window's times are not
    /// used.
    StageStall,
}

/// One scheduled fault.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): finite `at_s >= 0`, finite `duration_s >= 0`
/// (0 is an instantaneous event).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// What breaks.
    pub kind: FaultKind,
    /// When it starts, in simulated time since the lab was switched on, s.
    pub at_s: f64,
    /// How long it lasts, s.
    pub duration_s: f64,
}

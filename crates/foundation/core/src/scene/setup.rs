//! How the simulated lab is set up: the mistakes of a bench that a pre-flight check (`metaplate check`) must catch
//! before a night is lost.

use serde::{Deserialize, Serialize};

/// The lab's setup beyond its instruments' specifications. TOML: an optional `[setup]` table; every key is optional
/// and its default is a rig set up correctly. A scene whose setup is correct writes no `[setup]` table, so its
/// identity is the same as before the table existed.
///
/// A low LDV signal (a plate without retroreflective tape, a defocused beam) is not here: it is the vibrometer's
/// `ldv.speckle_mean_level`.
///
/// Valid range (checked by [`crate::scene::Scene::validate`]): the two swapped actuators distinct and existing;
/// finite `audio_device_rate_hz > 0`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SetupSpec {
    /// Two actuators (indices from 0) whose cables are swapped at the amplifier: the audio channel wired to either
    /// drives the other.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swapped_actuators: Option<[usize; 2]>,
    /// The loopback cable is missing: the DAQ's loopback input records nothing.
    #[serde(skip_serializing_if = "is_false")]
    pub loopback_disconnected: bool,
    /// The rate the audio interface is clocked at (set in its control panel), Hz, when it differs from
    /// `audio.sample_rate_hz`, the rate the rig asks for: it then opens at this rate and the driver refuses it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub audio_device_rate_hz: Option<f64>,
    /// Free space on the disk the runs write to, bytes, as the lab computer reports it (absent: the real free
    /// space of the output directory).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disk_free_bytes: Option<u64>,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's `skip_serializing_if` passes a reference.
fn is_false(value: &bool) -> bool {
    !*value
}

impl SetupSpec {
    /// Whether every key is at its default: a rig set up correctly.
    pub fn is_correct(&self) -> bool {
        *self == Self::default()
    }

    /// The audio channel that physically drives each actuator, given the channels the wiring names for them
    /// (indexed by actuator): the wiring with the swapped pair exchanged.
    pub fn physical_channels(&self, wired: &[u32]) -> Vec<u32> {
        let mut channels = wired.to_vec();
        if let Some([a, b]) = self.swapped_actuators
            && a < channels.len()
            && b < channels.len()
        {
            channels.swap(a, b);
        }
        channels
    }
}

//! The on-disk form of a scene, and its conversion to and from [`Scene`].
//!
//! It differs from [`Scene`] in one place: a top-level `[voice_coil]` table gives every actuator's default, and an
//! `[[actuators]]` entry's own `voice_coil` table overrides some or all of its fields.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::Scene;
use super::actuator::{ActuatorSpec, VoiceCoilPatch, VoiceCoilSpec};
use super::fault::FaultSpec;
use super::instruments::{AudioSpec, DaqSpec, LdvSpec};
use super::plate::PlateSpec;
use super::resonator::ResonatorFile;
use super::setup::SetupSpec;
use super::support::SupportSpec;
use super::validate::Problem;
use crate::grid::GridSpec;

/// A scene as written in TOML. Field order is the order of [`Scene::to_toml_string`]'s output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    name: String,
    description: String,
    seed: u64,
    plate: PlateSpec,
    #[serde(default)]
    supports: Vec<SupportSpec>,
    #[serde(default = "ResonatorFile::none")]
    resonators: ResonatorFile,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    voice_coil: Option<VoiceCoilSpec>,
    actuators: Vec<ActuatorEntry>,
    grid: GridSpec,
    ldv: LdvSpec,
    daq: DaqSpec,
    audio: AudioSpec,
    #[serde(default)]
    faults: Vec<FaultSpec>,
    #[serde(default, skip_serializing_if = "SetupSpec::is_correct")]
    setup: SetupSpec,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ActuatorEntry {
    x_m: f64,
    y_m: f64,
    #[serde(default, skip_serializing_if = "VoiceCoilPatch::is_empty")]
    voice_coil: VoiceCoilPatch,
}

impl SceneFile {
    /// The scene this file describes: each actuator's voice coil is its overrides on the default; a design file the
    /// resonators name is read relative to `base` (the scene file's folder; the working directory without one).
    ///
    /// # Errors
    /// A [`Problem`] when an actuator's voice coil lacks a field that no top-level `[voice_coil]` gives, or the
    /// resonator lattice is incomplete or its design unreadable.
    pub(crate) fn resolve(self, base: Option<&Path>) -> Result<Scene, Problem> {
        let default = self.voice_coil.as_ref();
        let actuators = self
            .actuators
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let voice_coil = a.voice_coil.apply(default).map_err(|field| Problem {
                    key_path: format!("actuators[{i}].voice_coil"),
                    message: format!(
                        "missing key `{field}`: give it in this actuator's voice_coil or in a top-level [voice_coil]"
                    ),
                })?;
                Ok(ActuatorSpec { x_m: a.x_m, y_m: a.y_m, voice_coil })
            })
            .collect::<Result<_, Problem>>()?;
        Ok(Scene {
            name: self.name,
            description: self.description,
            seed: self.seed,
            plate: self.plate,
            supports: self.supports,
            resonators: self.resonators.resolve(base).map_err(|(key_path, message)| Problem { key_path, message })?,
            actuators,
            grid: self.grid,
            ldv: self.ldv,
            daq: self.daq,
            audio: self.audio,
            faults: self.faults,
            setup: self.setup,
        })
    }
}

impl From<Scene> for SceneFile {
    /// The canonical form: the first actuator's voice coil is the default, and each actuator lists only the fields
    /// where its own differs.
    fn from(scene: Scene) -> Self {
        let voice_coil = scene.actuators.first().map(|a| a.voice_coil);
        let actuators = scene
            .actuators
            .iter()
            .map(|a| ActuatorEntry {
                x_m: a.x_m,
                y_m: a.y_m,
                voice_coil: VoiceCoilPatch::diff(voice_coil.as_ref(), &a.voice_coil),
            })
            .collect();
        Self {
            name: scene.name,
            description: scene.description,
            seed: scene.seed,
            plate: scene.plate,
            supports: scene.supports,
            resonators: ResonatorFile::from(&scene.resonators),
            voice_coil,
            actuators,
            grid: scene.grid,
            ldv: scene.ldv,
            daq: scene.daq,
            audio: scene.audio,
            faults: scene.faults,
            setup: scene.setup,
        }
    }
}

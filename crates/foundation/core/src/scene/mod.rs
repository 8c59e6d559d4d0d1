//! Scenes: one TOML file that describes a whole (simulated) lab.
//!
//! A scene gives the plate (outline, material, thickness, loss), its supports, its resonator lattice, the
//! actuators and their voice coils, the measurement grid, the vibrometer, the DAQ, the audio interface, a fault
//! schedule and a random seed. All quantities are SI (lengths in metres, frequencies in hertz); the unit is in each
//! key's name. Coordinates are centred on the plate's centre, x along the long axis.
//!
//! An optional `[setup]` table ([`SetupSpec`]) injects the mistakes of a bench that `metaplate check` must catch:
//! `swapped_actuators = [a, b]` (two actuators' cables swapped at the amplifier), `loopback_disconnected = true`
//! (no loopback cable), `audio_device_rate_hz = 44100.0` (the interface clocked at another rate than the rig asks
//! for) and `disk_free_bytes = N` (the free space the lab computer reports). A low LDV signal is the vibrometer's
//! `ldv.speckle_mean_level` (a plate without retroreflective tape reads 0.05 to 0.1). A correct setup is the
//! default and writes no table.
//!
//! Every imperfection the simulated lab models can be switched off ([`Imperfection`], [`Scene::without`],
//! [`Scene::with_only`]), for error budgets: besides the keys every scene gives, `daq.bits = 0` (no quantisation)
//! and the optional key `daq.clipping = false` (no clipping at the vibrometer's or the DAQ's range) exist for that.
//! One imperfection is optional: `ldv.aim_error_rms_m`, the scanner's beam positioning error (m rms per axis, drawn
//! once per point; 0, the default, aims exactly). An optional key at its default is not written, so it changes no
//! scene's identity.
//!
//! A resonator lattice may name a unit-cell design (`[resonators] design = "paper"`, a built-in, or a design file's
//! path relative to the scene file; [`crate::design`]): the design gives the lattice constant and the rods, the
//! scene's plate must be the design's, and the simulated plate takes the rods' dynamics from the cell. The scene's
//! text as written back holds the design inline, so that a dataset's copy of it stands alone.
//!
//! The built-in scenes are the paper's two plates, `metamaterial` and `homogeneous` (files in `foundation/core/scenes/`).
//! A user's file is checked key by key: an unknown key, a missing key, a value of the wrong type or outside its
//! valid range is a [`SceneError`] naming the file, line and key path, never a panic.

mod actuator;
mod canonical;
mod error;
mod fault;
mod file;
mod imperfection;
mod instruments;
mod outline;
mod plate;
mod resonator;
mod setup;
mod support;
mod validate;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use actuator::{ActuatorSpec, VoiceCoilSpec};
pub use canonical::CANONICAL_FORM_VERSION;
pub use error::SceneError;
pub use fault::{FaultKind, FaultSpec};
pub use imperfection::Imperfection;
pub use instruments::{AudioSpec, DaqSpec, LdvSpec};
pub use outline::{EDGE_TOLERANCE_M, Outline};
pub use plate::PlateSpec;
pub use resonator::{MAX_RESONATORS, ResonatorModel, ResonatorSpec};
pub use setup::SetupSpec;
pub use support::SupportSpec;

use crate::grid::GridSpec;
use crate::toml_locate::DocIndex;
use file::SceneFile;
use validate::Problem;

/// Prefix of the hash in a [`SceneId`] that [`Scene::id`] makes: the hash algorithm's name.
pub const SCENE_HASH_PREFIX: &str = "fnv1a64:";

/// Identity of the plate: a scene file of the simulated lab, or a real plate.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct SceneId {
    /// Human-readable name (the scene file's name, or the plate's label).
    pub name: String,
    /// Hash of the scene's content, as its producer writes it: [`Scene::id`] writes `fnv1a64:<16 hex digits>`, a
    /// real plate's producer whatever identifies it (for example `"sha256:<hex>"`).
    pub hash: String,
}

/// The built-in scenes: name and TOML text.
const BUILTINS: &[(&str, &str)] = &[
    ("metamaterial", include_str!("../../scenes/metamaterial.toml")),
    ("homogeneous", include_str!("../../scenes/homogeneous.toml")),
    ("metamaterial-untaped", include_str!("../../scenes/metamaterial-untaped.toml")),
];

/// The built-in names, in the order of [`BUILTINS`].
const BUILTIN_NAMES: &[&str] = &["metamaterial", "homogeneous", "metamaterial-untaped"];

/// A whole simulated lab. See the module documentation for the file format; every field's valid range is on its
/// type, and [`Scene::validate`] checks them all.
///
/// Serialises (to TOML, JSON, ...) in the file's form, the same as [`Scene::to_toml_string`]; deserialising
/// resolves voice-coil defaults and validates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(into = "SceneFile", try_from = "SceneFile")]
pub struct Scene {
    /// Short name (a built-in's name, or the file's own).
    pub name: String,
    /// One line on what the scene is.
    pub description: String,
    /// Seed of every random draw the simulated lab makes (at most 2^63 - 1: TOML integers are signed).
    pub seed: u64,
    /// The plate.
    pub plate: PlateSpec,
    /// The pads the plate rests on (none: a free plate).
    pub supports: Vec<SupportSpec>,
    /// The resonator lattice, or none.
    pub resonators: ResonatorSpec,
    /// The actuators, in audio-channel order (actuator i is on output i).
    pub actuators: Vec<ActuatorSpec>,
    /// The measurement grid (points off the plate or on a support are masked).
    pub grid: GridSpec,
    /// The vibrometer.
    pub ldv: LdvSpec,
    /// The DAQ.
    pub daq: DaqSpec,
    /// The audio interface.
    pub audio: AudioSpec,
    /// Faults the mock hardware injects, in any order.
    pub faults: Vec<FaultSpec>,
    /// How the lab is set up (cabling, clocking, disk): correct by default.
    pub setup: SetupSpec,
}

impl Scene {
    /// The names of the built-in scenes.
    pub fn builtin_names() -> &'static [&'static str] {
        BUILTIN_NAMES
    }

    /// A built-in scene by name.
    ///
    /// # Errors
    /// [`SceneError::NotFound`] for an unknown name. (A built-in that failed to parse would be a
    /// [`SceneError::Schema`] or [`SceneError::Invalid`]; the tests make sure none does.)
    pub fn builtin(name: &str) -> Result<Scene, SceneError> {
        match BUILTINS.iter().find(|(n, _)| *n == name) {
            Some((n, text)) => Self::from_toml_str(text, &format!("<built-in {n}>")),
            None => Err(SceneError::NotFound { name: name.to_owned(), known: BUILTIN_NAMES.join(", ") }),
        }
    }

    /// Parses and validates a scene from TOML text; `origin` (a path, or a built-in's name) prefixes every error
    /// message.
    ///
    /// # Errors
    /// [`SceneError::Syntax`] (not TOML), [`SceneError::Schema`] (unknown key, missing key, wrong type, unknown
    /// fault kind...) or [`SceneError::Invalid`] (a value outside its valid range), each with the line and key path.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        Self::from_toml_in(text, origin, None)
    }

    /// As [`Scene::from_toml_str`], with a design file the resonators name read relative to `base`.
    fn from_toml_in(text: &str, origin: &str, base: Option<&Path>) -> Result<Scene, SceneError> {
        let doc = DocIndex::parse(text, origin)
            .map_err(|l| SceneError::Syntax { location: l.location, message: l.message })?;
        let file: SceneFile = toml::from_str(text).map_err(|e| {
            let l = doc.schema_error(&e);
            SceneError::Schema { location: l.location, key_path: l.key_path, message: l.message }
        })?;
        let at = |p: Problem| SceneError::Invalid {
            location: doc.location_of_path(&p.key_path),
            key_path: p.key_path,
            message: p.message,
        };
        let scene = file.resolve(base).map_err(at)?;
        scene.check().map_err(at)?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file.
    ///
    /// # Errors
    /// [`SceneError::Io`] when the file cannot be read; otherwise as [`Scene::from_toml_str`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| SceneError::Io { path: origin.clone(), reason: e.to_string() })?;
        Self::from_toml_in(&text, &origin, path.parent())
    }

    /// A built-in scene when `name_or_path` is a built-in's name (a built-in wins over a file of the same name in
    /// the working directory), else the scene file at that path.
    ///
    /// # Errors
    /// [`SceneError::NotFound`] when it is neither; otherwise as [`Scene::load`].
    pub fn resolve(name_or_path: &str) -> Result<Scene, SceneError> {
        if BUILTIN_NAMES.contains(&name_or_path) {
            return Self::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        if path.exists() {
            Self::load(path)
        } else {
            Err(SceneError::NotFound { name: name_or_path.to_owned(), known: BUILTIN_NAMES.join(", ") })
        }
    }

    /// Checks every valid range stated on the scene's types, and that parts sit where they can: supports wholly
    /// under the plate, actuators on the plate and off the supports, some grid point measurable, enough audio
    /// channels for the actuators and the loopback reference.
    ///
    /// # Errors
    /// [`SceneError::Invalid`] naming the first offending key.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.check().map_err(|p| SceneError::Invalid {
            location: format!("scene `{}`", self.name),
            key_path: p.key_path,
            message: p.message,
        })
    }

    /// The scene as TOML, fully resolved (defaults filled in); [`Scene::from_toml_str`] reads it back to an equal
    /// scene. The canonical form: the same scene always gives the same text.
    ///
    /// The scene's types all have a TOML form, so writing cannot fail; were it ever to, the text would be a single
    /// TOML comment saying why (which reads back as a missing-key error, never as a wrong scene).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(&SceneFile::from(self.clone()))
            .unwrap_or_else(|e| format!("# scene `{}` cannot be written as TOML: {e}\n", self.name))
    }

    /// A stable 64-bit hash (FNV-1a) of the scene's canonical form ([`Scene::canonical_text`]): the same resolved
    /// scene gives the same hash on every machine and run, whatever its file's layout, key order or float spelling,
    /// and whatever version of the `toml` crate, so it can key caches and datasets.
    pub fn content_hash(&self) -> u64 {
        crate::hash::fnv1a_64(self.canonical_text().bytes())
    }

    /// A stable 64-bit hash (FNV-1a) of what the simulated plate's response depends on alone: the seed, the plate,
    /// its supports and resonators, the actuators' positions and the grid, in the canonical form; not the name, the
    /// voice coils (they act on the drive, not on the plate), the instruments, the faults or the setup. Caches of the plate's Green's functions key on it, so scenes that
    /// differ only in their instruments or setup share them.
    pub fn physics_hash(&self) -> u64 {
        crate::hash::fnv1a_64(canonical::physics_text(self).bytes())
    }

    /// The canonical form the scene's identity hashes: one `path = value` line per leaf of the resolved scene, keys
    /// sorted, floats as their IEEE-754 bits (see [`CANONICAL_FORM_VERSION`] for the exact rules).
    pub fn canonical_text(&self) -> String {
        canonical::canonical_text(self)
    }

    /// The scene's identity as datasets record it: its name and `fnv1a64:` followed by the 16 hex digits of
    /// [`Scene::content_hash`]. The one place that spells a scene id: resumes and caches compare these.
    pub fn id(&self) -> SceneId {
        SceneId { name: self.name.clone(), hash: format!("{SCENE_HASH_PREFIX}{:016x}", self.content_hash()) }
    }

    /// Per grid point (by flat index): true when it can be measured, on the plate (edge included) and not on a
    /// support pad.
    pub fn grid_mask(&self) -> Vec<bool> {
        (0..self.grid.len())
            .map(|i| {
                let (x, y) = self.grid.position_m(i);
                self.plate.outline.contains(x, y) && !self.supports.iter().any(|s| s.covers(x, y))
            })
            .collect()
    }

    /// Flat indices of the measurable grid points ([`Scene::grid_mask`] true), ascending.
    pub fn measured_points(&self) -> Vec<usize> {
        self.grid_mask().iter().enumerate().filter_map(|(i, &m)| m.then_some(i)).collect()
    }

    /// The actuators' driving points as flat "point" indices after the grid's (`grid.len() + k` for actuator `k`,
    /// on its magnet, where a calibration aims the beam).
    pub fn driving_points(&self) -> Vec<usize> {
        let n = self.grid.len();
        (0..self.actuators.len()).map(|k| n + k).collect()
    }

    /// Each actuator's magnet position, m, in actuator order.
    pub fn actuator_sites_m(&self) -> Vec<(f64, f64)> {
        self.actuators.iter().map(|a| (a.x_m, a.y_m)).collect()
    }
}

impl TryFrom<SceneFile> for Scene {
    type Error = SceneError;

    fn try_from(file: SceneFile) -> Result<Self, SceneError> {
        let scene = file.resolve(None).map_err(|p| SceneError::Invalid {
            location: "scene".to_owned(),
            key_path: p.key_path,
            message: p.message,
        })?;
        scene.validate()?;
        Ok(scene)
    }
}

//! The canonical form of a scene, which its identity hashes.
//!
//! The form depends only on the resolved scene's values, never on how a TOML writer lays text out: the scene's file
//! form ([`SceneFile`], defaults resolved) is turned into a TOML value tree and written one leaf per line as
//! `path = value`, table keys sorted, array elements by index. Strings are written escaped between quotes,
//! integers in decimal, booleans as `true`/`false`, and floats as the 16 hex digits of their IEEE-754 bits
//! (`f:3ff0000000000000` for 1.0), so `1e3`, `1000.0` and `1_000.0` in a scene file give the same form. An empty
//! table or array is written as `path = {}` or `path = []`.
//!
//! Changing this form changes every scene's identity (and so invalidates resumes and caches keyed by it): bump
//! [`CANONICAL_FORM_VERSION`], which heads the text, if it must ever change.

use std::fmt::Write as _;

use super::file::SceneFile;
use super::{ResonatorModel, Scene};

/// Version of the canonical form; the first line of the text is `metaplate-scene-canonical-v{VERSION}`.
pub const CANONICAL_FORM_VERSION: u32 = 1;

/// The canonical text of `scene` (see the module documentation).
///
/// The scene's types all have a TOML value form, so this cannot fail; were it ever to, the text would be the
/// version line plus a line naming the error (a distinct identity, never a wrong one shared with another scene).
pub(super) fn canonical_text(scene: &Scene) -> String {
    let mut out = format!("metaplate-scene-canonical-v{CANONICAL_FORM_VERSION}\n");
    match toml::Value::try_from(SceneFile::from(scene.clone())) {
        Ok(value) => write_value(&mut out, "", &value),
        Err(e) => {
            let _ = writeln!(out, "error = {:?}", e.to_string());
        }
    }
    out
}

/// Top-level keys of the file form that the simulated plate's response depends on: the seed (resonator spread;
/// left out when the scene has no spread to draw, so the plain plate's seeds share one physics), the plate, its supports and resonators, the actuators' positions and the grid. Not the name, the voice coils
/// (the top-level `voice_coil` and each actuator's: they turn the drive into force, which the plate model never
/// sees, so an error budget that switches their spread or nonlinearity off shares the plate's Green's functions),
/// the instruments, the faults or the setup.
const PHYSICS_KEYS: &[&str] = &["seed", "plate", "supports", "resonators", "actuators", "grid"];

/// The canonical text of the physics of `scene`: as [`canonical_text`], restricted to [`PHYSICS_KEYS`] and without
/// the actuators' voice coils, under its own version line (`metaplate-scene-physics-v{VERSION}`).
pub(super) fn physics_text(scene: &Scene) -> String {
    let mut out = format!("metaplate-scene-physics-v{CANONICAL_FORM_VERSION}\n");
    match toml::Value::try_from(SceneFile::from(scene.clone())) {
        Ok(toml::Value::Table(mut table)) => {
            table.retain(|key, _| PHYSICS_KEYS.contains(&key));
            // The seed draws only the rods' height spread: without rods or spread, every seed is the same plate.
            if scene.resonators.model == ResonatorModel::None || scene.resonators.height_spread == 0.0 {
                table.remove("seed");
            }
            if let Some(toml::Value::Array(actuators)) = table.get_mut("actuators") {
                for actuator in actuators.iter_mut() {
                    if let toml::Value::Table(entry) = actuator {
                        entry.remove("voice_coil");
                    }
                }
            }
            write_value(&mut out, "", &toml::Value::Table(table));
        }
        Ok(_) => {
            let _ = writeln!(out, "error = \"not a table\"");
        }
        Err(e) => {
            let _ = writeln!(out, "error = {:?}", e.to_string());
        }
    }
    out
}

fn write_value(out: &mut String, path: &str, value: &toml::Value) {
    // `write!` to a String cannot fail.
    match value {
        toml::Value::Table(table) => {
            if table.is_empty() {
                let _ = writeln!(out, "{path} = {{}}");
            }
            let mut keys: Vec<&String> = table.keys().collect();
            keys.sort();
            for key in keys {
                let child = if path.is_empty() { format!("{key:?}") } else { format!("{path}.{key:?}") };
                write_value(out, &child, &table[key.as_str()]);
            }
        }
        toml::Value::Array(items) => {
            if items.is_empty() {
                let _ = writeln!(out, "{path} = []");
            }
            for (i, item) in items.iter().enumerate() {
                write_value(out, &format!("{path}[{i}]"), item);
            }
        }
        toml::Value::String(s) => {
            let _ = writeln!(out, "{path} = {s:?}");
        }
        toml::Value::Integer(i) => {
            let _ = writeln!(out, "{path} = {i}");
        }
        toml::Value::Float(f) => {
            let _ = writeln!(out, "{path} = f:{:016x}", f.to_bits());
        }
        toml::Value::Boolean(b) => {
            let _ = writeln!(out, "{path} = {b}");
        }
        toml::Value::Datetime(d) => {
            let _ = writeln!(out, "{path} = t:{d}");
        }
    }
}

//! The [`Rig`] a command runs on: the mock lab of a scene (`--scene`), or the real instruments a hardware file names
//! (`--hardware FILE`), opened by the driver registry ([`metaplate_drivers::open_plate_rig`], which documents the
//! file's format and checks its wiring against its plate; `crates/cli/hardware.example.toml` is an example). Which
//! backends this binary has is its cargo features (default `hardware`: all of them).

use std::path::Path;

use metaplate_core::rig::Rig;
use metaplate_core::scene::Scene;
use metaplate_drivers::{OpenPurpose, OpenedRig};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_store::SceneId;

use crate::run::Source;

/// The plate a run measures: its geometry (grid, mask, actuator positions) and its identity in the dataset.
#[derive(Debug, Clone)]
pub struct Plate {
    /// The scene describing it (simulated or real plate).
    pub scene: Scene,
    /// Its identity in the manifest.
    pub id: SceneId,
}

impl Plate {
    /// The plate of the scene `name_or_path` (a built-in name or a scene file), validated.
    ///
    /// # Errors
    /// The scene's error (not found, invalid, with the key path).
    pub fn resolve(name_or_path: &str) -> anyhow::Result<Self> {
        let scene = Scene::resolve(name_or_path)?;
        scene.validate()?;
        Ok(Self::of(scene))
    }

    fn of(scene: Scene) -> Self {
        let id = scene.id();
        Self { scene, id }
    }
}

/// The mock lab of `plate`'s scene with `options`, with its rig. Keep the lab alive while the rig is used.
///
/// # Errors
/// The lab's reason.
pub fn mock_rig_with(plate: &Plate, options: &LabOptions) -> anyhow::Result<(MockLab, Rig)> {
    let lab = MockLab::new(&plate.scene, options).map_err(|e| anyhow::anyhow!("cannot build the mock lab: {e}"))?;
    let rig = lab.rig().map_err(|e| anyhow::anyhow!("cannot build the mock lab: {e}"))?;
    Ok((lab, rig))
}

/// The plate, rig and keypad (if it names one) of the hardware file at `path`, every instrument opened.
///
/// # Errors
/// The file, its plate, a backend this build lacks, or the instruments that cannot be opened.
pub fn hardware_rig_and_keypad(path: &Path, purpose: OpenPurpose) -> anyhow::Result<(Plate, OpenedRig)> {
    let (scene, opened) = metaplate_drivers::open_plate_rig(path, purpose)?;
    Ok((Plate::of(scene), opened))
}

/// A rig opened as `--scene` or `--hardware` asks, with what keeps it alive.
pub struct Opened {
    /// The plate.
    pub plate: Plate,
    /// The rig.
    pub rig: Rig,
    /// The hardware file's keypad, if it names one.
    pub keypad: Option<metaplate_keypad::Keypad<Box<dyn metaplate_keypad::HidInput>>>,
    /// The mock lab behind a `--scene` rig (dropped last).
    pub lab: Option<MockLab>,
}

/// Opens the rig of `source`: the hardware file's instruments (as far as `purpose` asks), or the mock lab of the scene with the options
/// `lab_options` gives for its plate (which points it prepares, its seed and cache).
///
/// # Errors
/// The plate's, the file's, the lab's or an instrument's error.
pub fn open(
    source: &Source,
    purpose: OpenPurpose,
    lab_options: impl FnOnce(&Plate) -> anyhow::Result<LabOptions>,
) -> anyhow::Result<Opened> {
    match (&source.scene, &source.hardware) {
        (_, Some(file)) => {
            let (plate, opened) = hardware_rig_and_keypad(file, purpose)?;
            Ok(Opened { plate, rig: opened.rig, keypad: opened.keypad, lab: None })
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            let (lab, rig) = mock_rig_with(&plate, &lab_options(&plate)?)?;
            Ok(Opened { plate, rig, keypad: None, lab: Some(lab) })
        }
        (None, None) => anyhow::bail!("give --scene or --hardware"),
    }
}

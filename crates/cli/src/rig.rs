//! Building the [`Rig`] a recipe runs on: the mock lab of a scene (`--scene`), or the real instruments named by a
//! hardware file (`--hardware FILE`), opened through the driver registry (`metaplate-drivers`, which documents the
//! file's format; `cli/hardware.example.toml` is an example). Which backends this binary has is its cargo features
//! (default `hardware`: all of them); a file naming a missing one is refused before anything is opened.

use std::fmt;
use std::path::{Path, PathBuf};

use metaplate_core::rig::Rig;
use metaplate_core::scene::Scene;
use metaplate_drivers::{HardwareError, HardwareFile, OpenedRig};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::ScanPlan;
use metaplate_store::SceneId;

/// Why a rig could not be built.
#[derive(Debug)]
pub enum RigError {
    /// The hardware file is invalid, names a backend this build lacks, or an instrument could not be opened.
    Hardware(HardwareError),
    /// The hardware file's wiring does not fit its plate.
    Plate {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
    /// The mock lab of a scene could not be built.
    Lab(String),
}

impl fmt::Display for RigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RigError::Hardware(e) => e.fmt(f),
            RigError::Plate { path, reason } => write!(f, "hardware file {}: {reason}", path.display()),
            RigError::Lab(detail) => write!(f, "cannot build the mock lab: {detail}"),
        }
    }
}

// No `source`: the message of `Hardware` is its inner error's, which anyhow would print twice.
impl std::error::Error for RigError {}

/// The plate a run measures: its geometry (grid, mask, actuator positions) and its identity in the dataset.
#[derive(Debug, Clone)]
pub struct Plate {
    /// The scene describing it (simulated or real plate).
    pub scene: Scene,
    /// Its identity in the manifest.
    pub id: SceneId,
}

impl Plate {
    /// The plate of the scene `name_or_path` (a built-in name or a scene file).
    ///
    /// # Errors
    /// The scene's error (not found, invalid, with the key path).
    pub fn resolve(name_or_path: &str) -> anyhow::Result<Self> {
        let scene = Scene::resolve(name_or_path)?;
        scene.validate()?;
        let id = scene.id();
        Ok(Self { scene, id })
    }

    /// Each actuator's magnet position, m, in actuator order.
    pub fn actuator_sites_m(&self) -> Vec<(f64, f64)> {
        self.scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect()
    }

    /// Flat "point" indices of the actuators' driving points in the mock lab (`grid.len() + k`).
    pub fn driving_points(&self) -> Vec<usize> {
        let n = self.scene.grid.len();
        (0..self.scene.actuators.len()).map(|k| n + k).collect()
    }

    /// The points a mock lab prepares for `plan` when the plan is small (at most [`PREPARE_WHOLE_PLAN_POINTS`]):
    /// the plan's points and the actuators' driving points, so a `check`, and a scan of the same plan share one
    /// Green's-function cache entry (the plate model's cost does not depend on the points). `None` for a larger
    /// plan, whose caller prepares only what it visits.
    pub fn small_plan_points(&self, plan: &ScanPlan) -> Option<Vec<usize>> {
        (plan.points.len() <= PREPARE_WHOLE_PLAN_POINTS).then(|| {
            let mut points = plan.points.clone();
            points.extend(self.driving_points());
            points
        })
    }
}

/// On the mock lab, a plan of at most this many points is prepared whole ([`Plate::small_plan_points`]; 64 points
/// of 8 responses of 0.5 s take 100 MB).
pub const PREPARE_WHOLE_PLAN_POINTS: usize = 64;

/// The mock lab of `plate`'s scene, preparing only `points` (Green's functions are computed, or read from
/// `cache_dir`, for those alone), with its rig. Keep the lab alive while the rig is used.
///
/// # Errors
/// [`RigError::Lab`] with the lab's reason.
pub fn mock_rig(
    plate: &Plate,
    points: Vec<usize>,
    seed: Option<u64>,
    cache_dir: Option<PathBuf>,
) -> Result<(MockLab, Rig), RigError> {
    mock_rig_with(plate, &LabOptions { seed, cache_dir, points: Some(points), ..LabOptions::default() })
}

/// The mock lab of `plate`'s scene with `options` (which points it prepares, how its LDV is served, ...), with its
/// rig. Keep the lab alive while the rig is used.
///
/// # Errors
/// [`RigError::Lab`] with the lab's reason.
pub fn mock_rig_with(plate: &Plate, options: &LabOptions) -> Result<(MockLab, Rig), RigError> {
    let lab = MockLab::new(&plate.scene, options).map_err(|e| RigError::Lab(e.to_string()))?;
    let rig = lab.rig().map_err(|e| RigError::Lab(e.to_string()))?;
    Ok((lab, rig))
}

/// The plate and rig described by the hardware file at `path`: every instrument opened through its backend (the
/// audio interface configured once, so that a missing card is found now rather than at the first point), on the
/// real clock.
///
/// # Errors
/// [`RigError::Hardware`] for the file, a backend this build lacks, or the first instrument that cannot be opened;
/// [`RigError::Plate`] when the wiring does not fit the plate; the plate scene's error.
pub fn hardware_rig(path: &Path) -> anyhow::Result<(Plate, Rig)> {
    // A keypad, if the file names one, is opened too (so that its absence is found now) and unused: no recipe
    // reads it yet.
    let (plate, opened) = hardware_rig_and_keypad(path)?;
    Ok((plate, opened.rig))
}

/// As [`hardware_rig`], with the keypad the file names, if any ([`OpenedRig::keypad`]).
///
/// # Errors
/// As [`hardware_rig`].
pub fn hardware_rig_and_keypad(path: &Path) -> anyhow::Result<(Plate, OpenedRig)> {
    let file = HardwareFile::load(path).map_err(RigError::Hardware)?;
    let plate = Plate::resolve(&file.plate)?;
    let actuators = file.wiring.actuator_channels.len();
    if actuators != plate.scene.actuators.len() {
        let reason = format!(
            "wiring.actuator_channels lists {actuators} actuators, the plate `{}` has {}",
            file.plate,
            plate.scene.actuators.len()
        );
        return Err(RigError::Plate { path: path.to_path_buf(), reason }.into());
    }
    let opened = metaplate_drivers::open_rig(&file).map_err(RigError::Hardware)?;
    Ok((plate, opened))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    const EXAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/hardware.example.toml");

    #[test]
    fn the_example_file_parses_to_a_valid_wiring() {
        let file = HardwareFile::load(Path::new(EXAMPLE)).unwrap();
        assert_eq!(file.plate, "metamaterial");
        let wiring = file.wiring();
        assert_eq!(wiring.actuator_channels, (0..8).collect::<Vec<u32>>());
        assert_eq!((wiring.loopback_channel, wiring.audio_channels), (8, 10));
        let backends: Vec<_> = file.backends().into_iter().map(|(_, name)| name).collect();
        assert_eq!(backends, ["serial", "usb-bulk", "alsa"]);
    }

    /// Writes the example with `edit` applied, in a temporary directory.
    fn edited(edit: impl Fn(String) -> String) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hardware.toml");
        std::fs::write(&path, edit(std::fs::read_to_string(EXAMPLE).unwrap())).unwrap();
        (dir, path)
    }

    #[test]
    #[cfg(feature = "serial")]
    fn a_missing_serial_port_is_named_in_the_error() {
        let missing = "/dev/metaplate-no-such-port";
        let (_dir, path) = edited(|text| {
            let start = text.find("port = ").unwrap();
            let end = start + text[start..].find('\n').unwrap();
            format!("{}port = \"{missing}\"{}", &text[..start], &text[end..])
        });
        let error = hardware_rig(&path).err().unwrap();
        let rig_error = error.downcast_ref::<RigError>().unwrap();
        let is_ldv = matches!(rig_error, RigError::Hardware(HardwareError::Device { device: "LDV", .. }));
        assert!(is_ldv, "{rig_error:?}");
        let message = error.to_string();
        assert!(message.contains("LDV") && message.contains(missing), "{message}");
    }

    #[test]
    fn a_wiring_that_does_not_fit_the_plate_is_refused_before_opening_anything() {
        let (_dir, path) = edited(|text| text.replace("[0, 1, 2, 3, 4, 5, 6, 7]", "[0, 1, 2, 3, 4, 5, 6]"));
        let error = hardware_rig(&path).err().unwrap();
        let message = error.to_string();
        assert!(message.contains("lists 7 actuators") && message.contains("has 8"), "{message}");
    }
}

//! Scenes and helpers shared by the integration tests.
#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_core::scene::Scene;

/// The built-in homogeneous plate with no supports (a free plate): every mode's loss factor is then the plate's.
pub fn free_homogeneous() -> Scene {
    let mut scene = Scene::builtin("homogeneous").unwrap();
    scene.supports.clear();
    scene
}

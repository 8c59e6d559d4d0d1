//! Shared fixtures: a small, fast lab on the built-in homogeneous plate.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_core::scene::{FaultSpec, Scene};
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_plate::ModelOptions;

/// Band of the test labs' Green's functions, Hz: narrow and above the plate's slowest ring-downs, so that the
/// plate model (debug build) needs only a few hundred frequency solves.
pub const BAND_HZ: (f64, f64) = (100.0, 600.0);

/// The homogeneous plate without random dropouts and with `faults`; `linear` removes the coils' cubic term.
pub fn scene(faults: Vec<FaultSpec>, linear: bool) -> Scene {
    let mut scene = Scene::builtin("homogeneous").unwrap();
    scene.faults = faults;
    scene.ldv.dropout_probability = 0.0;
    if linear {
        for a in &mut scene.actuators {
            a.voice_coil.nonlinearity = 0.0;
        }
    }
    scene
}

/// The test point: a measured point near the plate's centre.
pub fn point(scene: &Scene) -> usize {
    let measured = scene.measured_points();
    measured[measured.len() / 2]
}

/// A lab for `scene` preparing only the test point, coarse plate lattice, Green's functions cached under the
/// target directory (shared by every test run).
pub fn lab(scene: &Scene, seed: Option<u64>) -> MockLab {
    lab_with_points(scene, seed, vec![point(scene)])
}

/// As [`lab`], preparing `points` (grid indices, or `grid.len() + k` for actuator k's driving point).
pub fn lab_with_points(scene: &Scene, seed: Option<u64>, points: Vec<usize>) -> MockLab {
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&cache).unwrap();
    let options = LabOptions {
        seed,
        cache_dir: Some(cache),
        points: Some(points),
        model: ModelOptions { refinement: 1, threads: 2 },
        band_hz: BAND_HZ,
        ir_duration_s: 0.25,
        ..LabOptions::default()
    };
    MockLab::new(scene, &options).unwrap()
}

/// A linear sweep at 48 kHz, 80 to 700 Hz (past the band on both sides), half full scale, 10 ms fades.
pub fn sweep(duration_s: f64) -> Vec<f64> {
    SweepSpec {
        kind: SweepKind::Linear,
        f1_hz: 80.0,
        f2_hz: 700.0,
        duration_s,
        sample_rate_hz: 48_000.0,
        amplitude: 0.5,
        fade_in_s: 0.01,
        fade_out_s: 0.01,
    }
    .generate()
    .unwrap()
}

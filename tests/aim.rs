//! `metaplate aim teach` on the mock lab's mirrors, through the binary: a simulated user's key bytes (the lab's
//! `teacher`, computed in-process on the same seeded mirrors) piped to the command, the fit it writes read back, and
//! a 7 x 5 scan aimed through it landing within 0.3 mm of every target, and `scan --galvo-fit` aiming the mock lab
//! through it.

use std::sync::Arc;

use metaplate_aim::galvo::{GalvoAimer, GalvoSettings, file};
use metaplate_core::aim::Aim;
use metaplate_core::clock::VirtualClock;
use metaplate_core::scene::Scene;
use metaplate_lab::mirrors::{MirrorGeometry, MockMirrors};
use metaplate_lab::teacher::{NINE_MARKS_MM, teach_nine_marks};

#[test]
fn aim_teach_on_the_mock_galvo_with_scripted_keys_lands_a_7_by_5_scan_within_0_3_mm() {
    let dir = crate::common::scratch("aim-cli", "teach");
    let marks_file = dir.join("marks.txt");
    std::fs::write(&marks_file, NINE_MARKS_MM).unwrap();
    // The user's keys, found on the mirrors the binary builds for the scene (same seed, same start).
    let scene = Scene::builtin("metamaterial").unwrap();
    let geometry = MirrorGeometry::seeded(scene.seed);
    let (teach, keys) = teach_nine_marks(geometry).unwrap();

    let fit_path = dir.join("galvo-fit.toml");
    let args = ["aim", "teach", "--scene", "metamaterial", "--marks-file", marks_file.to_str().unwrap()];
    let out = crate::common::metaplate_with_input(&[&args[..], &["--out", fit_path.to_str().unwrap()]].concat(), &keys);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains(&format!("wrote {}", fit_path.display())), "{stdout}");

    // The binary recorded what the user taught in-process (the same keys on the same mirrors).
    let fit = file::read(&fit_path).unwrap();
    let taught = teach.fit(fit.model()).unwrap();
    assert_eq!(fit.residual(), taught.residual());
    assert!(fit.residual().max_mm < 0.3, "{:?}", fit.residual());

    // The lab's view of where the beam lands: a handle on the same mirrors the aimer drives.
    let lab_mirrors = MockMirrors::new(geometry);
    let mut aimer = GalvoAimer::new(
        fit,
        Box::new(lab_mirrors.clone()),
        Arc::new(VirtualClock::new()),
        GalvoSettings { settle_s: 0.002 },
    )
    .unwrap();
    let mut worst_m: f64 = 0.0;
    for p in scene.grid.subset(7, 5).unwrap() {
        let (x_m, y_m) = scene.grid.position_m(p);
        aimer.aim_at(x_m, y_m).unwrap();
        let (bx, by) = lab_mirrors.beam_m().unwrap();
        worst_m = worst_m.max((bx - x_m).hypot(by - y_m));
    }
    assert!(worst_m < 0.3e-3, "worst landing {:.3} mm off", worst_m * 1e3);

    // A mock-lab scan aimed through the taught fit (the recipes' tests measure its error against the truth): the
    // dataset's rig record names the fit; without --scene the option is refused.
    let scan_dir = dir.join("scan");
    let (f, s) = (fit_path.to_str().unwrap(), scan_dir.to_str().unwrap());
    let scan = ["scan", "--scene", "metamaterial", "--protocol", "quick", "--grid", "2x1", "--uncalibrated"];
    let out = crate::common::metaplate(&[&scan[..], &["--galvo-fit", f, "--out", s]].concat());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let manifest = std::fs::read_to_string(scan_dir.join("manifest.json")).unwrap();
    assert!(manifest.contains("galvo mirrors (projective fit of 9 points"), "{manifest}");
    let hardware = ["scan", "--hardware", "rig.toml", "--galvo-fit", f, "--out", s];
    let refused = crate::common::metaplate_bare(&hardware);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("required arguments were not provided") && stderr.contains("--scene"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

//! `metaplate play` on the metamaterial scene's mock lab: a calibration and a 3 x 2 scan through it (the scan of
//! tests/recipes.rs, the scene's own seed; Green's functions cached under the target directory, shared with the other
//! tests), then patterns played with the onset measured on the loopback, a clipping level and an off-plate pixel
//! refused; the same scan on scattered points (points on no lattice, as an import of a scan mesh places them) plays
//! as on its grid, the scan exported as a universal file and imported again plays as the scan, and a measurement
//! that is no scan through a calibration is refused by its unit.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::metaplate;
use metaplate_core::scene::Scene;
use metaplate_store::{Dataset, DatasetWriter, IfExists, IrRecord, ScatteredPoints};
use serde_json::Value;

/// `metaplate play` on the metamaterial mock lab with `extra` arguments.
fn play(extra: &[&str]) -> Output {
    let (_, scan) = common::calibrated_scan();
    play_on(&scan, extra)
}

/// `metaplate play` of the dataset `scan` through the shared calibration on the metamaterial mock lab.
fn play_on(scan: &Path, extra: &[&str]) -> Output {
    let (cal, _) = common::calibrated_scan();
    let mut args = vec![
        "play",
        "--data",
        scan.to_str().unwrap(),
        "--calibration",
        cal.to_str().unwrap(),
        "--scene",
        "metamaterial",
    ];
    args.extend(extra);
    metaplate(&args)
}

#[test]
fn plays_on_the_mock_lab_with_the_onset_measured_on_the_loopback() {
    // Three of the scan's six points (x -0.08, 0, 0.08; y -0.03, 0.03), snapped: an impulse, a noise burst, a null.
    let out = play(&["--pixel", "0,-0.03", "--pixel", "0.06,0.03:noise@0.1,0.2", "--pixel=-0.06,0.03:null", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let number = |key: &str| doc[key].as_f64().unwrap_or_else(|| panic!("{key} in {doc}"));

    // The mock audio interface sounds frame 0 `audio.latency_s` after its submission. Tolerance 10 us (a quarter
    // of a DAQ sample at 24 kHz): the clocks' offsets (audio -30 ppm, DAQ +20 ppm) move a 55 ms onset by 2.7 us,
    // the DAQ's start precedes the audio's by the driver's command exchange on the virtual clock (microseconds),
    // and the delay estimate on a clean loopback is good to a hundredth of a sample.
    let latency_s = Scene::builtin("metamaterial").unwrap().audio.latency_s;
    let (scheduled, measured) = (number("scheduled_onset_s"), number("measured_onset_s"));
    assert!((number("latency_s") - (measured - scheduled)).abs() < 1e-12, "{doc}");
    assert!((measured - scheduled - latency_s).abs() < 10e-6, "measured {measured} s, scheduled {scheduled} s");
    assert_eq!(doc["underruns"], 0);
    assert_eq!(doc["gap"], false);

    // The default level (1 dB below full scale) leaves about 1 dB; the focused pixels are in the paper's 1 to 10
    // mm/s range or near it, the null pixel far below.
    let margin = number("clip_margin_db");
    assert!(margin > 0.0 && margin < 3.0, "{doc}");
    let peaks: Vec<f64> =
        doc["pixels"].as_array().unwrap().iter().map(|p| p["predicted_peak_mm_s"].as_f64().unwrap()).collect();
    assert_eq!(peaks.len(), 3);
    assert!(peaks[0] > 1.0 && peaks[1] > 1.0, "{peaks:?}");
    assert!(peaks[2] < 0.01 * peaks[0].min(peaks[1]), "null pixel: {peaks:?}");

    // Velocities scale with the level.
    let out = play(&[
        "--pixel",
        "0,-0.03",
        "--pixel",
        "0.06,0.03:noise@0.1,0.2",
        "--pixel=-0.06,0.03:null",
        "--json",
        "--level",
        "0.089",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let quiet: Value = serde_json::from_slice(&out.stdout).unwrap();
    let quiet_peak = quiet["pixels"][0]["predicted_peak_mm_s"].as_f64().unwrap();
    assert!((quiet_peak / peaks[0] - 0.1).abs() < 1e-9, "{quiet_peak} against {}", peaks[0]);
}

#[test]
fn a_clipping_level_is_refused_with_nothing_played() {
    let out = play(&["--pixel", "0,-0.03", "--level", "1.5", "--json"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("would clip") && stderr.contains("level 1.5"), "{stderr}");
    // Nothing played: no report (the refusal comes before the rig is touched; recipes' play tests check that the
    // refusal needs only the wiring).
    assert!(out.stdout.is_empty(), "{}", String::from_utf8_lossy(&out.stdout));
}

#[test]
fn an_unfocusable_pixel_is_refused_by_name() {
    // Off the outline, and on the plate but outside the scanned points'
    // hull (x -0.08, 0, 0.08; y -0.03, 0.03).
    for (pixel, reason) in [
        ("0.5,0", "pixel (0.5, 0) is off the plate"),
        ("0,0.07", "pixel (0, 0.07) is 40.0 mm from the nearest measured point"),
    ] {
        let out = play(&["--pixel", "0,-0.03", "--pixel", pixel]);
        assert!(!out.status.success(), "{pixel}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(reason), "{pixel}: {stderr}");
        assert!(out.stdout.is_empty(), "{pixel}: {}", String::from_utf8_lossy(&out.stdout));
    }
}

#[test]
fn a_hardware_file_goes_through_the_registry() {
    // The example file names devices this machine does not have: the registry's error, before anything plays.
    let (cal, scan) = common::calibrated_scan();
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/hardware.example.toml");
    let args =
        ["play", "--data", scan.to_str().unwrap(), "--calibration", cal.to_str().unwrap(), "--hardware", example];
    let out = metaplate(&[&args[..], &["--pixel", "0,-0.03"]].concat());
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("LDV") || stderr.contains("backend"), "{stderr}");
    assert!(out.stdout.is_empty(), "{}", String::from_utf8_lossy(&out.stdout));
}

/// Each point of the 3 x 2 scan (in the order of their grid indices) moved by up to 2.2 mm, no two by the same
/// step: on no lattice.
const MOVED_MM: [(f64, f64); 6] = [(1.5, -0.8), (-2.0, 1.1), (0.7, 2.2), (-1.1, -1.9), (2.2, 0.4), (-0.4, -1.3)];

/// A point of the scan: its grid index, and its moved position (x, y), m.
type MovedPoint = (u32, (f64, f64));

/// The 3 x 2 scan written again as scattered points 0 to 5 (its points in the order of their grid indices, each
/// moved by [`MOVED_MM`]), every response, unit and calibration as they were: what an import of the scan with the
/// positions a camera measured holds. Returns the dataset and each point's grid index and moved position.
fn scattered_scan(scan: &Path) -> (PathBuf, Vec<MovedPoint>) {
    let original = Dataset::open(scan).unwrap();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("play-scattered").join(std::process::id().to_string());
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let grid = original.manifest().meta.grid;
    let points: Vec<MovedPoint> = original
        .points()
        .iter()
        .zip(MOVED_MM)
        .map(|(&p, (dx, dy))| {
            let (x, y) = grid.position_m(p as usize);
            (p, (x + dx * 1e-3, y + dy * 1e-3))
        })
        .collect();
    assert_eq!(points.len(), 6);
    let positions_m: Vec<(f64, f64)> = points.iter().map(|&(_, at)| at).collect();
    let frame = "the scan's frame, points moved as a camera placed them (a test)".to_owned();
    let meta = original.manifest().meta.clone().with_scattered(ScatteredPoints { positions_m, frame });
    let out = dir.join("scattered");
    let mut writer = DatasetWriter::create(&out, meta, IfExists::Refuse).unwrap();
    let rows: Vec<IrRecord> = original
        .rows()
        .iter()
        .map(|m| {
            let index = points.iter().position(|&(p, _)| p == m.point_index).unwrap();
            let mut meta = *m;
            (meta.point_index, meta.ix, meta.iy) = (index as u32, index as u32, 0);
            (meta.x_m, meta.y_m) = points[index].1;
            IrRecord { meta, ir: original.ir(m.point_index, m.actuator).unwrap().to_vec() }
        })
        .collect();
    writer.commit_batch(&rows).unwrap();
    writer.finish().unwrap();
    (out, points)
}

#[test]
fn a_scan_on_scattered_points_plays_as_on_its_grid() {
    let (_, scan) = common::calibrated_scan();
    let (scattered, points) = scattered_scan(&scan);
    let json = |out: Output| -> Value {
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    // Two of the points: (0, -0.03) and (0.08, 0.03), asked at their grid positions on the grid, at their moved
    // ones on the scattered points.
    let on_grid = json(play_on(&scan, &["--pixel", "0,-0.03", "--pixel", "0.08,0.03:null", "--json"]));
    let chosen: Vec<usize> = (0..2)
        .map(|i| {
            let p = on_grid["pixels"][i]["point_index"].as_u64().unwrap();
            points.iter().position(|&(q, _)| u64::from(q) == p).unwrap()
        })
        .collect();
    let (a, b) = (points[chosen[0]].1, points[chosen[1]].1);
    let pixels = [format!("{},{}", a.0, a.1), format!("{},{}:null", b.0, b.1)];
    let on_points = json(play_on(&scattered, &["--pixel", &pixels[0], "--pixel", &pixels[1], "--json"]));

    // The same points, now at their moved positions; the same responses and filters give the same drives, so the
    // same predicted peaks (1e-12 relative allows a different summation order, nothing more).
    for (i, &index) in chosen.iter().enumerate() {
        let (grid, scattered) = (&on_grid["pixels"][i], &on_points["pixels"][i]);
        assert_eq!(scattered["point_index"], index, "{on_points}");
        let (x, y) = points[index].1;
        let (got_x, got_y) = (scattered["x_m"].as_f64().unwrap(), scattered["y_m"].as_f64().unwrap());
        assert!((got_x - x).abs() < 1e-12 && (got_y - y).abs() < 1e-12, "{on_points}");
        let (want, got) =
            (grid["predicted_peak_mm_s"].as_f64().unwrap(), scattered["predicted_peak_mm_s"].as_f64().unwrap());
        assert!(
            (want - got).abs() <= 1e-12 * want.abs().max(1e-9),
            "pixel {i}: {want} mm/s on the grid, {got} on the points"
        );
    }
    assert!(on_points["pixels"][0]["predicted_peak_mm_s"].as_f64().unwrap() > 1.0, "{on_points}");
    assert_eq!(on_points["clip_margin_db"], on_grid["clip_margin_db"]);

    // 3 mm beside a moved point the pixel snaps to it. Amid four points (48 mm from the nearest, whose cell
    // reaches 0.71 of its 59 mm to its neighbour, 42 mm) it is refused by its distance.
    let near = format!("{},{}", a.0 + 0.003, a.1);
    let snapped = json(play_on(&scattered, &["--pixel", &near, "--json"]));
    assert_eq!(snapped["pixels"][0]["point_index"], chosen[0], "{snapped}");
    let out = play_on(&scattered, &["--pixel", "0.04,0"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("pixel (0.04, 0) is 48.") && stderr.contains("outside the scattered points"), "{stderr}");
    assert!(out.stdout.is_empty());
}

#[test]
fn a_measurement_that_is_no_scan_through_a_calibration_is_refused_by_its_unit() {
    // Another tool's accelerance FRF (a public file of the import corpus), imported: velocity per newton, on a plate
    // metaplate does not know. Refused by the unit (the reason that holds on any rig) before anything is opened,
    // pointing to `focus`.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("play-import").join(std::process::id().to_string());
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let nodes = dir.join("nodes.csv");
    std::fs::write(&nodes, "node,x_m,y_m\n0,0.0,-0.03\n").unwrap();
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../interchange/tests/corpus/non_ascii_header.uff");
    let data = dir.join("imported");
    let args = ["import", "--uff", file, "--nodes", nodes.to_str().unwrap(), "--out", data.to_str().unwrap()];
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = play_on(&data, &["--pixel", "0,-0.03"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("impulse responses are in `m/s/N`") && stderr.contains("metaplate focus"), "{stderr}");
    assert!(!stderr.contains("plate `uff-import`"), "{stderr}");
    assert!(out.stdout.is_empty());
}

#[test]
fn a_scan_exported_and_imported_again_plays_as_the_scan() {
    // The universal file keeps the scan's unit and calibration in its header (dataset 151): the import restores
    // them, and `play` renders the same drives from the same responses (58b in single precision: the stored f32
    // values exactly).
    let (_, scan) = common::calibrated_scan();
    let dir = common::scratch("play-round-trip", "uff");
    let file = dir.join("scan.uff");
    let data = dir.join("imported");
    let (file_arg, data_arg) = (file.to_str().unwrap(), data.to_str().unwrap());
    let export = ["export", "--data", scan.to_str().unwrap(), "--format", "uff58b", "--out", file_arg];
    let out = common::metaplate_bare(&export);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = common::metaplate_bare(&["import", "--uff", file_arg, "--out", data_arg]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("measured through the calibration"));

    let pixels = ["--pixel", "0,-0.03", "--pixel", "0.08,0.03:null", "--json"];
    let json = |out: Output| -> Value {
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let (scanned, imported) = (json(play_on(&scan, &pixels)), json(play_on(&data, &pixels)));
    for key in ["clip_margin_db", "pixels", "focus_s", "duration_s"] {
        assert_eq!(imported[key], scanned[key], "{key}: {imported} vs {scanned}");
    }
}

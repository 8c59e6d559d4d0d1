//! `metaplate play` on the metamaterial scene's mock lab: a calibration and a 3 x 2 scan through it (the scan of
//! tests/recipes.rs, the scene's own seed; Green's functions cached under the target directory, shared with the other
//! tests), then patterns played with the onset measured on the loopback, a clipping level and an off-plate pixel
//! refused.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::process::Output;

use common::metaplate;
use metaplate_core::scene::Scene;
use serde_json::Value;

/// `metaplate play` on the metamaterial mock lab with `extra` arguments.
fn play(extra: &[&str]) -> Output {
    let (cal, scan) = common::calibrated_scan();
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

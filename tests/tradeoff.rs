//! `metaplate tradeoff --json` on a tiny grid with two protocols: one JSON object with the documented keys.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use std::process::Command;

#[test]
fn tradeoff_json_has_every_key_per_protocol() {
    let figures = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["tradeoff", "--scene", "metamaterial", "--grid", "2x1", "--protocols", "quick,hadamard:0.6x1"])
        .arg("--json")
        .arg("--figures")
        .arg(figures.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let protocols = v["protocols"].as_array().unwrap();
    assert_eq!(protocols.len(), 2);
    for (p, name) in protocols.iter().zip(["quick", "hadamard:0.6x1"]) {
        assert_eq!(p["name"], name);
        for key in ["time_per_point_s", "nominal_time_per_point_s", "scan_hours", "median_error_db", "p95_error_db"] {
            assert!(p[key].as_f64().is_some_and(f64::is_finite), "{name}: {key} = {}", p[key]);
        }
        // Present, and null on a grid this coarse (no closed half-maximum contour).
        assert!(p.get("median_pixel_area_cm2").is_some(), "{name}");
    }
    // The simultaneous protocol plays less per point: nominal 8 x (0.6 + 0.5) = 8.8 s against 8 x (2 + 0.5) = 20 s.
    let t = |i: usize| protocols[i]["time_per_point_s"].as_f64().unwrap();
    assert!(t(1) < t(0), "hadamard {} s vs quick {} s", t(1), t(0));
    assert!(figures.path().join("tradeoff.png").exists() && figures.path().join("tradeoff.svg").exists());
}

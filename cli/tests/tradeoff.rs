//! `metaplate tradeoff --json` on a tiny grid with two protocols: one JSON object with the documented keys; and
//! the same over two seeds with a series, the keys of the means, intervals, series and ratio.

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

#[test]
fn tradeoff_over_seeds_reports_intervals_and_a_series() {
    // The cheapest run with the new keys: one point (1x1), two seeds, `quick` and a two-member Hadamard series.
    // Without `paper` there is no ratio (its arithmetic is tested on synthetic numbers in `tradeoff::fit`).
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["tradeoff", "--scene", "metamaterial", "--grid", "1x1", "--protocols", "quick"])
        .args(["--series", "hadamard:0.6x1,0.6x2", "--seeds", "7,8", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["seeds"], serde_json::json!([7, 8]));
    let protocols = v["protocols"].as_array().unwrap();
    assert_eq!(protocols.len(), 3);
    for p in protocols {
        assert_eq!(p["per_seed"].as_array().unwrap().len(), 2, "{}", p["name"]);
        let ci = p["median_error_db_ci95"].as_array().unwrap();
        let mean = p["median_error_db"].as_f64().unwrap();
        assert!(ci[0].as_f64().unwrap() <= mean && mean <= ci[1].as_f64().unwrap(), "{}", p["name"]);
    }
    let series = &v["series"][0];
    assert_eq!(series["protocols"], serde_json::json!(["hadamard:0.6x1", "hadamard:0.6x2"]));
    // 4.8 s to 9.6 s of excitation per point: one doubling, its slope from both seeds.
    assert_eq!(series["steps"][0]["doublings"].as_f64().unwrap(), 1.0);
    let slope = &series["steps"][0]["slope_db_per_doubling"];
    assert!(slope["mean"].as_f64().is_some_and(f64::is_finite) && slope["n"] == 2, "{slope}");
    assert!(v["ratio"].is_null());
}

//! `metaplate budget --json` on a small grid: the documented shape, and a term that stands out of the floor.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

mod common;

use serde_json::Value;

#[test]
fn budget_json_has_the_floor_the_terms_and_all_on() {
    // The metamaterial plate with a vibrometer 1000 times noisier (a plate without tape, and then some): the same
    // physics, so the Green's functions are those of the other tests' 3 x 2, seed 5 scans, already in the cache.
    let dir = tempfile::tempdir().unwrap();
    let shown = std::process::Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["scene", "show", "metamaterial"])
        .output()
        .unwrap();
    assert!(shown.status.success());
    let text =
        String::from_utf8(shown.stdout).unwrap().replacen("noise_rms_m_s = 0.000001", "noise_rms_m_s = 0.001", 1);
    assert!(text.contains("noise_rms_m_s = 0.001"));
    let scene = dir.path().join("noisy.toml");
    std::fs::write(&scene, text).unwrap();
    let started = std::time::Instant::now();
    let out = common::metaplate(&[
        "budget",
        "--scene",
        scene.to_str().unwrap(),
        "--grid",
        "3x2",
        "--seed",
        "5",
        "--protocol",
        "hadamard:0.6x1",
        "--only",
        "floor,ldv-noise,latency,all-on",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Progress on stderr, one line per part; stdout is the JSON alone.
    assert_eq!(String::from_utf8_lossy(&out.stderr).matches("budget [").count(), 4);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let quantiles = |x: &Value, what: &str| {
        for key in ["median_db", "p95_db"] {
            assert!(x[key].as_f64().is_some_and(f64::is_finite), "{what}: {key} = {}", x[key]);
        }
        assert_eq!(x["bands"].as_array().map(Vec::len), Some(3), "{what}: octave bands");
        x["median_db"].as_f64().unwrap()
    };
    let floor = quantiles(&v["floor"], "floor");
    let all_on = quantiles(&v["all_on"], "all_on");
    let terms = v["terms"].as_array().unwrap();
    let names: Vec<&str> = terms.iter().map(|t| t["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["ldv-noise", "latency"]);
    let (noise, latency) = (quantiles(&terms[0], "ldv-noise"), quantiles(&terms[1], "latency"));
    // The noise stands far out of the floor and sets the total; latency, which the loopback cancels, adds nothing.
    assert!(noise > floor + 10.0, "noise {noise} dB, floor {floor} dB");
    assert!((latency - floor).abs() < 0.5, "latency {latency} dB, floor {floor} dB");
    assert!(all_on > noise - 1.0, "all on {all_on} dB, noise {noise} dB");
    assert!(v["additivity"]["closure_db"].as_f64().is_some_and(f64::is_finite), "{}", v["additivity"]);
    println!("budget took {:.1} s", started.elapsed().as_secs_f64());
}

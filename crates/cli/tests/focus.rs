//! `metaplate focus` end to end on a small ground-truth dataset (13 x 7 points of the metamaterial plate).

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn metaplate(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args).env("RUST_BACKTRACE", "0").output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("metaplate-focus-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The 13 x 7 metamaterial dataset (Green's functions cached under the target directory, so reruns are quick).
fn dataset(dir: &Path) -> PathBuf {
    let data = dir.join("gt");
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    let out = metaplate(&[
        "simulate",
        "greens",
        "--scene",
        "metamaterial",
        "--grid",
        "13x7",
        "--out",
        data.to_str().unwrap(),
        "--cache-dir",
        cache.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    data
}

#[test]
fn focus_writes_a_normalised_eight_channel_drive_and_refuses_bad_pixels() {
    let dir = scratch("drive");
    let data = dataset(&dir);
    let wav = dir.join("drive.wav");
    let field = dir.join("field.json");
    let out = metaplate(&[
        "focus",
        "--data",
        data.to_str().unwrap(),
        "--pixel",
        "0,0",
        "--pixel",
        "0.04,0.02:sine@200,0.3,0.2",
        "--pixel=-0.04,-0.02:null",
        "--out",
        wav.to_str().unwrap(),
        "--field",
        field.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains("peak drive") && stdout.contains("normalisation factor"), "{stdout}");

    let mut reader = hound::WavReader::open(&wav).unwrap();
    assert_eq!(reader.spec().channels, 8);
    assert_eq!(reader.spec().sample_format, hound::SampleFormat::Float);
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    let peak = samples.iter().fold(0.0_f32, |m, v| m.max(v.abs()));
    // Peak-normalised to 1: f32 rounding of the scaled peak is at most one ulp.
    assert!(peak <= 1.0 && peak > 1.0 - 1e-6, "peak {peak}");

    // The predicted field: three pixels, each one drive long; the impulse pixel peaks at the default focus time
    // (half the drive), where it is the largest of the three.
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&field).unwrap()).unwrap();
    let pixels = doc["pixels"].as_array().unwrap();
    assert_eq!(pixels.len(), 3);
    let v: Vec<Vec<f64>> =
        pixels.iter().map(|p| p["v"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()).collect();
    assert!(v.iter().all(|x| x.len() * 8 == samples.len()));
    let argmax = v[0].iter().enumerate().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).unwrap().0;
    // Within 2 samples of half the period (24 kHz: 83 us; the band-limited impulse's peak is one sample wide).
    assert!(argmax.abs_diff(v[0].len() / 2) <= 2, "impulse peak at sample {argmax} of {}", v[0].len());
}

#[test]
fn a_pixel_off_the_plate_or_in_a_gap_is_a_clear_error() {
    let dir = scratch("bad");
    let data = dataset(&dir);
    let wav = dir.join("drive.wav");
    for (pixel, message) in [("0.5,0", "off the plate"), ("0.011,0", "nearest measured point"), ("0,x", "not a number")]
    {
        let out =
            metaplate(&["focus", "--data", data.to_str().unwrap(), "--pixel", pixel, "--out", wav.to_str().unwrap()]);
        assert!(!out.status.success(), "{pixel} accepted");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains(message) && !err.contains("panicked"), "{pixel}: {err}");
    }
    assert!(!wav.exists());
}

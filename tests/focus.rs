//! `metaplate focus` end to end on a small ground-truth dataset (13 x 7 points of the metamaterial plate), with and
//! without a calibration made by the calibration recipe on the mock lab.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common::{self, metaplate_bare as metaplate};
use std::path::{Path, PathBuf};
use std::process::Output;

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
        // The mock lab's band: cut from the lab's cache entry for this plate (tests/analyze.rs).
        "--band-lo-hz",
        "40",
        "--band-hi-hz",
        "800",
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
    let dir = common::scratch("focus-cli", "drive");
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

/// A calibration of the metamaterial plate's 8 actuators by the calibration recipe on the mock lab (only the
/// actuators' driving points prepared; Green's functions cached under the target directory).
fn calibration(dir: &Path) -> PathBuf {
    use metaplate_core::scene::Scene;
    use metaplate_lab::{LabOptions, MockLab};
    use metaplate_recipes::{CalibrationConfig, Output, RunControl, Silent, calibrate};

    let scene = Scene::builtin("metamaterial").unwrap();
    let n = scene.actuators.len();
    let options = LabOptions {
        points: Some((0..n).map(|k| scene.grid.len() + k).collect()),
        cache_dir: Some(Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache")),
        ..LabOptions::default()
    };
    let lab = MockLab::new(&scene, &options).unwrap();
    let mut rig = lab.rig().unwrap();
    let out = Output {
        dir: dir.join("calibration"),
        scene: scene.id(),
        software_version: "test".into(),
        resume: false,
        force: false,
        preflight: None,
    };
    let sites: Vec<(f64, f64)> = scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect();
    calibrate(&mut rig, &sites, &CalibrationConfig::default(), &out, &RunControl::new(), &mut Silent).unwrap();
    out.dir
}

/// `metaplate focus` of an impulse at the plate centre, with `calibration` if given, into `wav`.
fn focus_at_centre(data: &Path, calibration: Option<&Path>, wav: &Path) -> Output {
    let mut args = vec!["focus", "--data", data.to_str().unwrap(), "--pixel", "0,0", "--out", wav.to_str().unwrap()];
    if let Some(dir) = calibration {
        args.extend(["--calibration", dir.to_str().unwrap()]);
    }
    metaplate(&args)
}

fn wav_channels(path: &Path) -> Vec<Vec<f32>> {
    let mut reader = hound::WavReader::open(path).unwrap();
    let channels = usize::from(reader.spec().channels);
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    (0..channels).map(|c| samples.iter().skip(c).step_by(channels).copied().collect()).collect()
}

#[test]
fn focus_applies_a_recipe_calibration_and_refuses_a_dataset_that_is_not_one() {
    let dir = common::scratch("focus-cli", "calibrated");
    let data = dataset(&dir);
    let cal = calibration(&dir);
    let (plain, compensated) = (dir.join("plain.wav"), dir.join("compensated.wav"));
    for (wav, calibration) in [(&plain, None), (&compensated, Some(cal.as_path()))] {
        let out = focus_at_centre(&data, calibration, wav);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let calibration = metaplate_recipes::Calibration::load(&cal, 8).unwrap();
    let (plain, compensated) = (wav_channels(&plain), wav_channels(&compensated));
    assert_eq!(compensated.len(), 8);
    for (a, (p, c)) in plain.iter().zip(&compensated).enumerate() {
        // Convolution with the actuator's filter: the channel grows by the filter length minus one.
        assert_eq!(c.len(), p.len() + calibration.filters[a].taps.len() - 1, "actuator {a}");
    }
    let peak = compensated.iter().flatten().fold(0.0_f32, |m, v| m.max(v.abs()));
    // Peak-normalised after compensation: within one f32 ulp of 1.
    assert!(peak <= 1.0 && peak > 1.0 - 1e-6, "peak {peak}");
    // The compensated drive is not the plain one rescaled: the filters shape it (relative difference well above
    // f32 rounding, 1e-7, after matching the scale by least squares on the common part).
    let (p0, c0) = (&plain[0], &compensated[0]);
    let scale = p0.iter().zip(c0).map(|(p, c)| f64::from(*p) * f64::from(*c)).sum::<f64>()
        / p0.iter().map(|p| f64::from(*p).powi(2)).sum::<f64>();
    let residual: f64 = p0.iter().zip(c0).map(|(p, c)| (f64::from(*c) - scale * f64::from(*p)).powi(2)).sum();
    let energy: f64 = c0.iter().map(|c| f64::from(*c).powi(2)).sum();
    assert!(residual / energy > 1e-3, "compensation changed nothing: {}", residual / energy);

    // The ground-truth dataset is not a calibration: a clear error, no panic, no output.
    let bad = dir.join("bad.wav");
    let out = focus_at_centre(&data, Some(&data), &bad);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("not a calibration") && !err.contains("panicked"), "{err}");
    assert!(!bad.exists());
}

#[test]
fn a_pixel_off_the_plate_or_in_a_gap_is_a_clear_error() {
    let dir = common::scratch("focus-cli", "bad");
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

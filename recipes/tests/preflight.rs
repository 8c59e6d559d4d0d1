//! The pre-flight check on the mock lab: a healthy rig passes every check, and each setup mistake a scene can
//! inject fails the check that should catch it, with a message naming the problem, while the others still pass.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use common::lab_and_plan;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_recipes::preflight::{PlannedRun, PreflightConfig, PreflightReport, preflight};

/// The pre-flight of `scene` on its mock lab (the 7 x 5 plan's lab, whose Green's functions the other recipe tests
/// share), with three of the plan's points for the LDV and a planned paper scan of the full grid.
fn check(scene: &Scene) -> PreflightReport {
    let (lab, plan) = lab_and_plan(scene, 7, 5);
    let mut rig = lab.rig().unwrap();
    let sites: Vec<(f64, f64)> = scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect();
    let n = plan.points.len();
    let points = [plan.points[n / 4], plan.points[n / 2], plan.points[3 * n / 4]];
    let mut config = PreflightConfig::new(sites, points.iter().map(|&p| scene.grid.position_m(p)).collect());
    config.planned = Some(PlannedRun {
        points: scene.measured_points().len(),
        protocol: ExcitationProtocol::paper(),
        out_dir: "/data/scan".into(),
        free_bytes: Some(scene.setup.disk_free_bytes.unwrap_or(1 << 40)),
    });
    let mut seen = Vec::new();
    let report = preflight(&mut rig, &config, &mut |c| seen.push(c.name)).unwrap();
    assert_eq!(seen, report.checks.iter().map(|c| c.name).collect::<Vec<_>>(), "every outcome reported as it came");
    report
}

fn outcome<'a>(report: &'a PreflightReport, name: &str) -> &'a metaplate_recipes::preflight::CheckOutcome {
    report.checks.iter().find(|c| c.name == name).unwrap_or_else(|| panic!("no `{name}` check in {report:#?}"))
}

/// Asserts that exactly the checks `failing` failed, and that the first one's message holds `phrase`.
fn assert_fails(report: &PreflightReport, failing: &[&str], phrase: &str) {
    let failed: Vec<&str> = report.checks.iter().filter(|c| !c.passed).map(|c| c.name).collect();
    assert_eq!(failed, failing, "{:#?}", report.to_json());
    assert_eq!(report.verdict(), "fail");
    let message = &outcome(report, failing[0]).message;
    assert!(message.contains(phrase), "`{phrase}` not in: {message}");
}

fn with_setup(toml: &str) -> Scene {
    let text = format!("{}\n[setup]\n{toml}\n", common::metamaterial().to_toml_string());
    Scene::from_toml_str(&text, "faulty.toml").unwrap()
}

#[test]
fn a_healthy_mock_rig_passes_every_check_with_the_labs_own_figures() {
    for name in ["metamaterial", "homogeneous"] {
        healthy(&Scene::builtin(name).unwrap());
    }
}

fn healthy(scene: &Scene) {
    let report = check(scene);
    let json = report.to_json();
    assert!(report.passed(), "{json:#}");
    let names: Vec<&str> = report.checks.iter().map(|c| c.name).collect();
    assert_eq!(
        names,
        [
            "wiring",
            "vibrometer",
            "daq",
            "audio",
            "loopback",
            "clocks",
            "actuator_wiring",
            "ldv_signal",
            "disk",
            "duration"
        ]
    );
    // The loopback's latency is the interface's output latency (the DAQ and the audio start at the same virtual
    // time); its level is the wiring's 1 V per full scale at -20 dBFS.
    let loopback = &outcome(&report, "loopback").details;
    let latency_s = loopback["latency_s"].as_f64().unwrap();
    assert!((latency_s - scene.audio.latency_s).abs() < 2e-5, "latency {latency_s} s");
    assert!(loopback["level_db"].as_f64().unwrap().abs() < 0.5, "{loopback}");
    // The drift is the two clocks' offsets: DAQ +20 ppm against audio -30 ppm.
    let drift = outcome(&report, "clocks").details["drift_ppm"].as_f64().unwrap();
    let expected =
        ((1.0 + scene.daq.clock_offset_ppm * 1e-6) / (1.0 + scene.audio.clock_offset_ppm * 1e-6) - 1.0) * 1e6;
    assert!((drift - expected).abs() < 1.0, "drift {drift} ppm, expected {expected}");
    // Reciprocity as wired holds to the noise (the mock plate is exactly reciprocal, its LDV quiet); the same pairs
    // read as if swapped disagree by far more than the limit.
    let wiring = &outcome(&report, "actuator_wiring").details;
    let worst = |key: &str, pick: fn(f64, f64) -> f64| {
        wiring[key].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).reduce(pick).unwrap()
    };
    assert!(worst("reciprocity_error_db", f64::max) < -40.0, "{wiring}");
    assert!(worst("swapped_error_db", f64::min) > -25.0, "{wiring}");
    println!("{json:#}");
}

#[test]
fn a_swapped_actuator_pair_is_named_with_both_channels() {
    let report = check(&with_setup("swapped_actuators = [2, 5]"));
    assert_fails(&report, &["actuator_wiring"], "actuators 2 and 5 are swapped: channel 2");
    assert!(outcome(&report, "actuator_wiring").message.contains("channel 5 drives actuator 2"));
}

#[test]
fn a_dead_loopback_is_named_and_what_needs_it_is_not_run() {
    let report = check(&with_setup("loopback_disconnected = true"));
    let failing = ["loopback", "clocks", "actuator_wiring"];
    assert_fails(&report, &failing, "no signal on the loopback (audio channel 8 to DAQ input 1)");
    // The clocks are read from the loopback, and the wiring's responses are referred to it.
    assert!(outcome(&report, "clocks").message.starts_with("not run"));
    assert!(outcome(&report, "actuator_wiring").message.starts_with("not run"));
}

#[test]
fn a_low_ldv_signal_is_named_with_the_remedy() {
    let mut scene = common::metamaterial();
    scene.ldv.speckle_mean_level = 0.05;
    assert_fails(&check(&scene), &["ldv_signal"], "retroreflective tape");
}

#[test]
fn an_audio_interface_at_the_wrong_rate_is_named_and_nothing_is_played() {
    let report = check(&with_setup("audio_device_rate_hz = 44100.0"));
    assert_fails(&report, &["audio", "loopback", "clocks", "actuator_wiring", "ldv_signal"], "44100");
    assert!(outcome(&report, "audio").message.contains("Set the interface's clock to 48000 Hz"));
}

#[test]
fn a_full_disk_is_named_with_what_to_free() {
    // The paper scan of the full grid needs about 0.5 GB.
    let report = check(&with_setup("disk_free_bytes = 100000000"));
    assert_fails(&report, &["disk"], "only 100.0 MB free at /data/scan");
}

/// A rig whose instruments did not all open: each that failed fails the check of its name with its own message,
/// the instrument checks no failure names are not run, and the verdict says which failed.
#[test]
fn instruments_that_did_not_open_fail_their_checks_by_name() {
    let failed = [
        ("ldv", "cannot open the LDV `/dev/ttyUSB0` (polytec): no answer".to_owned()),
        ("aim", "cannot open the aimer `fit.toml` (galvo): the taught fit's residual".to_owned()),
    ];
    let report = PreflightReport::unopened(&failed);
    assert!(!report.passed());
    let names: Vec<&str> = report.checks.iter().map(|c| c.name).collect();
    assert_eq!(names, ["vibrometer", "aim", "daq", "audio", "loopback", "clocks", "actuator_wiring", "ldv_signal"]);
    assert_eq!(outcome(&report, "vibrometer").message, failed[0].1);
    assert_eq!(outcome(&report, "aim").message, failed[1].1);
    assert!(outcome(&report, "daq").message.starts_with("not run"), "{:?}", outcome(&report, "daq"));
    assert!(report.checks.iter().all(|c| !c.passed));
    assert!(report.verdict_line().starts_with("fail: vibrometer, aim, daq"), "{}", report.verdict_line());
}

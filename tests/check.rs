//! `metaplate check` as a user runs it: the pre-flight of the mock lab passes and its report is recorded by the
//! scan that follows (and kept by a resume); rig mistakes injected by a scene file fail the check by name with exit
//! code 3; the mock LDV over a pseudo-terminal exercises the real serial transport end to end; and, on request
//! only, the pre-flight of a real rig.
//!
//! The check of `--grid 7x5` prepares the 7 x 5 plan and the magnets, as the recipe tests' lab does, with their seed
//! (5), so all share one Green's-function cache entry in `CARGO_TARGET_TMPDIR`.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::process::Command;

use common::metaplate;
use serde_json::Value;

/// The scene's own seed, as the other tests' scans of the metamaterial plate and the ground truth: one Green's-function
/// cache entry for all of them.
const CHECK: &[&str] = &["check", "--scene", "metamaterial", "--grid", "7x5"];
/// The checks of a mock-lab pre-flight with a planned run, in order.
const CHECKS: [&str; 10] =
    ["wiring", "vibrometer", "daq", "audio", "loopback", "clocks", "actuator_wiring", "ldv_signal", "disk", "duration"];

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn names(report: &Value) -> Vec<&str> {
    report["checks"].as_array().unwrap().iter().map(|c| c["name"].as_str().unwrap()).collect()
}

/// The names of the checks that failed, in order.
fn failed(report: &Value) -> Vec<&str> {
    report["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["passed"] == false)
        .map(|c| c["name"].as_str().unwrap())
        .collect()
}

fn check(report: &'_ Value, name: &str) -> Value {
    report["checks"].as_array().unwrap().iter().find(|c| c["name"] == name).cloned().unwrap()
}

#[test]
fn a_healthy_mock_rig_passes_and_the_scan_records_the_verdict_which_a_resume_keeps() {
    let tmp = tempfile::tempdir().unwrap();
    let report_path = tmp.path().join("preflight.json");
    let scan = tmp.path().join("scan");
    let mut args = CHECK.to_vec();
    args.extend(["--json", "--report", report_path.to_str().unwrap(), "--out", scan.to_str().unwrap()]);
    let out = metaplate(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let printed: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(printed["verdict"], "pass", "{printed:#}");
    assert_eq!(names(&printed), CHECKS);
    assert!(printed["checks"].as_array().unwrap().iter().all(|c| c["passed"] == true && c["message"].is_string()));
    // The report on disk is what was printed; it names the rig it checked; nothing else was written.
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&report_path).unwrap()).unwrap();
    assert_eq!(written, printed);
    assert_eq!(written["rig"]["vibrometer"]["vendor"], "Polytec", "the mock lab's vibrometer is a Polytec controller");
    assert!(!scan.exists(), "the check writes nothing in the run's directory");

    let scan_args = |extra: &[&str]| {
        let mut a = vec!["scan", "--out", scan.to_str().unwrap(), "--scene", "metamaterial", "--protocol", "quick"];
        a.extend(["--grid", "3x2", "--uncalibrated"]);
        a.extend(extra);
        a.into_iter().map(str::to_owned).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| metaplate(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let out = run(scan_args(&["--preflight", report_path.to_str().unwrap()]));
    assert!(out.status.success(), "{}", text(&out.stderr));
    let recorded = || -> Value {
        let manifest: Value =
            serde_json::from_str(&std::fs::read_to_string(scan.join("manifest.json")).unwrap()).unwrap();
        manifest["config"]["preflight"].clone()
    };
    let first = recorded();
    assert_eq!(first["verdict"], "pass", "{first}");
    assert_eq!(first["same_rig"], true, "the check and the scan ran on the same (mock) rig and wiring: {first}");
    assert_eq!(first["failed"], serde_json::json!([]));
    assert_eq!(first["checked_at"], written["checked_at"]);
    // A resume without the report is not a changed configuration: the run keeps the pre-flight of its start.
    let out = run(scan_args(&["--resume"]));
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(recorded(), first);
    // Something that is not a report is refused before anything runs.
    let bogus = tmp.path().join("bogus.json");
    std::fs::write(&bogus, "{\"checks\": []}").unwrap();
    let out = run(scan_args(&["--resume", "--preflight", bogus.to_str().unwrap()]));
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("is not a pre-flight report (no `verdict`)"), "{}", text(&out.stderr));
}

#[test]
fn rig_mistakes_in_a_scene_file_fail_the_check_by_name_with_exit_code_3() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("miswired.toml");
    let resolved =
        Command::new(env!("CARGO_BIN_EXE_metaplate")).args(["scene", "show", "metamaterial"]).output().unwrap();
    assert!(resolved.status.success(), "{}", text(&resolved.stderr));
    // Two actuator cables swapped at the amplifier, and a disk with a kilobyte free.
    let faulty = format!("{}\n[setup]\nswapped_actuators = [1, 6]\ndisk_free_bytes = 1000\n", text(&resolved.stdout));
    std::fs::write(&scene, faulty).unwrap();
    let out = metaplate(&["check", "--scene", scene.to_str().unwrap(), "--grid", "7x5", "--json"]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(report["verdict"], "fail");
    assert_eq!(failed(&report), ["actuator_wiring", "disk"], "{report:#}");
    let wiring = check(&report, "actuator_wiring")["message"].as_str().unwrap().to_owned();
    assert!(wiring.contains("actuators 1 and 6 are swapped: channel 1"), "{wiring}");
    let disk = check(&report, "disk")["message"].as_str().unwrap().to_owned();
    assert!(disk.contains("only 1.0 kB free"), "{disk}");
    // Without --json: each check as a line, and the one-line verdict on stdout.
    let out = metaplate(&["check", "--scene", scene.to_str().unwrap(), "--grid", "7x5"]);
    assert_eq!(out.status.code(), Some(3));
    assert_eq!(text(&out.stdout).trim(), "fail: actuator_wiring, disk (8 of 10 passed)");
    assert!(
        text(&out.stderr).contains("  FAIL actuator_wiring: actuators 1 and 6 are swapped"),
        "{}",
        text(&out.stderr)
    );
}

/// The U6's stream overflows during the loopback sweep (the scene's `daq_overrun` fault: the mock U6 reports
/// errorcodes 59 and 60 to the real U6 driver): the loopback fails naming the overflow, and what needs the loopback
/// is not run.
#[test]
fn a_daq_stream_overflow_fails_the_loopback_by_name() {
    let dir = common::scratch("check", "overflow");
    let scene = dir.join("overflowing.toml");
    let resolved =
        Command::new(env!("CARGO_BIN_EXE_metaplate")).args(["scene", "show", "metamaterial"]).output().unwrap();
    assert!(resolved.status.success(), "{}", text(&resolved.stderr));
    let faulty = format!(
        "{}\n[[faults]]\nkind = \"daq_overrun\"\nat_s = 0.0\nduration_s = 2.0\n",
        text(&resolved.stdout).replace("faults = []\n", "")
    );
    std::fs::write(&scene, faulty).unwrap();
    let out = metaplate(&["check", "--scene", scene.to_str().unwrap(), "--grid", "7x5", "--json"]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(failed(&report), ["loopback", "clocks", "actuator_wiring"], "{report:#}");
    let loopback = check(&report, "loopback")["message"].as_str().unwrap().to_owned();
    assert!(loopback.contains("the DAQ's stream overflowed") && loopback.contains("U6"), "{loopback}");
}

/// The LDV answers over a pseudo-terminal through the real `serialport` transport (the `serial` backend), against
/// the mock controller: the serial path of `check --hardware`, end to end, without the instrument.
#[cfg(feature = "serial")]
#[test]
fn the_check_runs_over_the_real_serial_transport_on_a_pseudo_terminal() {
    let mut args = CHECK.to_vec();
    args.extend(["--ldv-pty", "--json"]);
    let out = metaplate(&args);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(report["verdict"], "pass", "{report:#}");
    assert!(check(&report, "vibrometer")["message"].as_str().unwrap().contains("Polytec"));
    assert!(check(&report, "ldv_signal")["passed"] == true, "levels and velocities read over the serial line");
}

/// A hardware file whose instruments are not there (the example's serial port, U6 and sound card on a machine
/// without them): `check` tries each, fails the check of every one it cannot open by name with exit code 3, and
/// writes its report; a typo in the file is an error of the file, not a failed check.
#[cfg(all(feature = "serial", feature = "labjack-u6", feature = "alsa", target_os = "linux"))]
#[test]
fn instruments_that_cannot_be_opened_fail_their_checks_by_name() {
    let dir = common::scratch("check", "unopened");
    let file = dir.join("rig.toml");
    std::fs::write(&file, include_str!("../crates/cli/hardware.example.toml")).unwrap();
    let report_path = dir.join("report.json");
    let out = metaplate(&[
        "check",
        "--hardware",
        file.to_str().unwrap(),
        "--json",
        "--report",
        report_path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(3), "{}", text(&out.stderr));
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(report["verdict"], "fail");
    for (name, phrase) in [("vibrometer", "usb-FTDI"), ("daq", "360012345"), ("audio", "hw:CARD=24Ao")] {
        let outcome = check(&report, name);
        assert_eq!(outcome["passed"], false, "{outcome}");
        assert!(outcome["message"].as_str().unwrap().contains(phrase), "{outcome}");
    }
    assert!(check(&report, "loopback")["message"].as_str().unwrap().starts_with("not run"), "{report:#}");
    assert!(report["rig"]["error"].is_string() && report["plate"]["name"] == "metamaterial", "{report:#}");
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&report_path).unwrap()).unwrap();
    assert_eq!(written["checks"], report["checks"]);
    let lines = metaplate(&["check", "--hardware", file.to_str().unwrap()]);
    let stderr = text(&lines.stderr);
    assert!(stderr.contains("FAIL vibrometer: cannot open the LDV") && stderr.contains("FAIL audio"), "{stderr}");
    assert!(text(&lines.stdout).starts_with("fail: vibrometer, daq, audio"), "{}", text(&lines.stdout));
    std::fs::write(&file, include_str!("../crates/cli/hardware.example.toml").replace("[ldv]", "[ldvv]")).unwrap();
    let typo = metaplate(&["check", "--hardware", file.to_str().unwrap(), "--json"]);
    assert_eq!(typo.status.code(), Some(1), "{}", text(&typo.stderr));
    assert!(text(&typo.stderr).contains("ldvv"), "{}", text(&typo.stderr));
}

/// The pre-flight of a real rig, only on request:
/// `METAPLATE_HARDWARE=rig.toml cargo test -p metaplate-cli --test check -- --ignored --nocapture`.
/// It moves the beam to the magnets and a few grid points and plays quiet chirps: turn the amplifier down.
#[test]
#[ignore = "needs a real rig: set METAPLATE_HARDWARE to its hardware file and run with --ignored"]
fn the_pre_flight_of_a_real_rig_passes() {
    // Run on purpose without a rig: fail loudly rather than pass without testing anything.
    let file = std::env::var("METAPLATE_HARDWARE").expect("set METAPLATE_HARDWARE=path/to/hardware.toml");
    let out = metaplate(&["check", "--hardware", &file, "--json"]);
    eprintln!("{}", text(&out.stderr));
    let report: Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    eprintln!("{report:#}");
    assert_eq!(report["verdict"], "pass", "{report:#}");
    assert_eq!(out.status.code(), Some(0));
}

//! `metaplate calibrate` and `metaplate scan` end to end, as a user runs them, on the built-in metamaterial scene's
//! mock lab (fast-forward): calibrate then scan, `--json` events and the log, Ctrl-C and resume, a changed
//! configuration on resume.
//!
//! The plate's Green's functions are cached in `CARGO_TARGET_TMPDIR` (keyed by scene and request, so a stale entry
//! cannot be read): the first run of this file computes them (about a minute of CPU per point set in the debug
//! profile), later runs take seconds.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;

use crate::common::interrupt;
use metaplate_store::{Dataset, Status};
use serde_json::Value;

/// The scan every test runs: 3 x 2 points of the metamaterial grid (all 6 on the plate), the quick protocol.
const SCAN: &[&str] = &["--scene", "metamaterial", "--protocol", "quick", "--grid", "3x2"];
const POINTS: usize = 6;
const ACTUATORS: usize = 8;

fn cache_dir() -> &'static Path {
    static CACHE: OnceLock<PathBuf> = OnceLock::new();
    CACHE.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
        std::fs::create_dir_all(&dir).unwrap();
        // Warm the scan's entry once, so that tests running in parallel do not all compute it.
        let warm = tempfile::tempdir().unwrap();
        let out = run(&scan_args(&warm.path().join("warm"), &["--uncalibrated"]), &dir);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        dir
    })
}

fn scan_args(out: &Path, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = ["scan", "--out", out.to_str().unwrap()].iter().map(|s| s.to_string()).collect();
    args.extend(SCAN.iter().chain(extra).map(|s| s.to_string()));
    args
}

fn command(args: &[String], cache: &Path) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_metaplate"));
    command.args(args).arg("--cache-dir").arg(cache).env("RUST_BACKTRACE", "0");
    command
}

fn run(args: &[String], cache: &Path) -> Output {
    command(args, cache).output().unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Checks a finished scan dataset: one row per point and actuator, every row valid or re-measured (the quick
/// protocol's SNR on this plate is 40 dB and more, far above the 20 dB gate, so a failed row is a bug).
fn assert_complete_scan(dir: &Path) {
    let dataset = Dataset::open(dir).unwrap();
    assert_eq!(dataset.len(), POINTS * ACTUATORS, "one row per point and actuator");
    assert_eq!(dataset.points().len(), POINTS);
    for row in dataset.rows() {
        assert!(matches!(row.status, Some(Status::Valid | Status::ReMeasured)), "{row:?}");
    }
}

#[test]
fn calibrate_then_scan_end_to_end_with_json_events_and_a_log() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    let cal = tmp.path().join("cal");
    let args: Vec<String> = ["calibrate", "--scene", "metamaterial", "--out", cal.to_str().unwrap()]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let out = run(&args, cache);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let calibration = Dataset::open(&cal).unwrap();
    assert_eq!(calibration.actuators().len(), ACTUATORS, "one commit per actuator");
    assert_eq!(calibration.len(), 3 * ACTUATORS, "filter, response and verification per actuator");
    assert!(cal.join("calibrate.log").is_file());

    let scan = tmp.path().join("scan");
    let out = run(&scan_args(&scan, &["--calibration", cal.to_str().unwrap(), "--json"]), cache);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_complete_scan(&scan);

    let events: Vec<Value> = text(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let kinds: Vec<&str> = events.iter().map(|e| e["event"].as_str().unwrap()).collect();
    assert_eq!(kinds.first(), Some(&"started"), "{kinds:?}");
    assert_eq!(kinds.last(), Some(&"finished"), "{kinds:?}");
    let committed: Vec<&Value> = events.iter().filter(|e| e["event"] == "committed").collect();
    assert_eq!(committed.len(), POINTS, "one committed event per point");
    let last = committed[POINTS - 1];
    assert_eq!((last["done"].as_u64(), last["total"].as_u64()), (Some(POINTS as u64), Some(POINTS as u64)));
    assert!(last["snr_db"].as_f64().unwrap() > 20.0, "{last}");
    assert_eq!(last["eta_h"].as_f64(), Some(0.0));
    assert!(last["rate_per_hour"].as_f64().unwrap() > 0.0);
    // Every commit says where (grid column and row, position), how, and when; the start names the dataset.
    let manifest: Value = serde_json::from_str(&std::fs::read_to_string(scan.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(events[0]["dataset"].as_str(), Some(scan.to_str().unwrap()));
    assert_eq!(events[0]["config_hash"], manifest["config_hash"]);
    let dataset = Dataset::open(&scan).unwrap();
    for c in &committed {
        let meta = dataset.meta(c["unit"].as_u64().unwrap() as u32, 0).unwrap();
        assert_eq!((c["ix"].as_u64(), c["iy"].as_u64()), (Some(u64::from(meta.ix)), Some(u64::from(meta.iy))), "{c}");
        assert_eq!((c["x_m"].as_f64(), c["y_m"].as_f64()), (Some(meta.x_m), Some(meta.y_m)), "{c}");
        assert!(c["status"].is_string() && c["wall_s"].as_f64().unwrap() >= 0.0 && c["at"].is_string(), "{c}");
    }
    assert_eq!(last["remaining_s"]["median"].as_f64(), Some(0.0), "nothing left: {last}");
    // The phases of a unit: moving, playing each actuator (the quick protocol drives one at a time), committing.
    let phases: Vec<&Value> = events.iter().filter(|e| e["event"] == "phase").collect();
    for phase in ["moving", "playing", "committing"] {
        assert!(phases.iter().any(|p| p["phase"] == phase), "no `{phase}` phase");
    }
    let driven: std::collections::BTreeSet<u64> = phases
        .iter()
        .filter(|p| p["phase"] == "playing")
        .flat_map(|p| p["actuators"].as_array().unwrap().iter().map(|a| a.as_u64().unwrap()))
        .collect();
    assert_eq!(driven, (0..ACTUATORS as u64).collect(), "every actuator is played, and named");

    let log = std::fs::read_to_string(scan.join("scan.log")).unwrap();
    assert!(log.matches("committed").count() >= POINTS, "{log}");
    assert!(!log.contains('\u{1b}'), "no colour codes in the log");
}

#[test]
fn ctrl_c_stops_cleanly_and_resume_completes_refusing_a_changed_configuration() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let args = scan_args(&dir, &["--uncalibrated", "--json"]);

    // SIGINT once, right after the first commit: the point in flight is finished and committed, then it stops.
    let mut child = command(&args, cache).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let first_commit = lines.by_ref().map(Result::unwrap).find(|l| l.contains("\"committed\""));
    assert!(first_commit.is_some(), "no commit seen");
    interrupt(&child);
    let rest: Vec<String> = lines.map(Result::unwrap).collect();
    let out = child.wait_with_output().unwrap();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("stopping after the current point (Ctrl-C again to abandon it)"), "{stderr}");
    let resume = stderr.lines().find(|l| l.trim_start().contains(" scan ") && l.contains("--resume"));
    assert!(resume.is_some_and(|l| l.contains("--protocol quick") && l.contains("--grid 3x2")), "{stderr}");
    assert_eq!(rest.last().map(|l| l.contains("\"stopped\"")), Some(true), "{rest:?}");
    let partial = Dataset::open(&dir).unwrap();
    let committed = partial.points().len();
    assert!((1..POINTS).contains(&committed), "stopped after {committed} points");
    assert_eq!(partial.len(), committed * ACTUATORS, "whole points only");

    // Without --resume, the directory is refused; with a changed protocol, the resume is refused saying what
    // changed; with --force it proceeds.
    // A failure is one message even with RUST_BACKTRACE=1, and --json says `failed` on stdout before the exit.
    let out = command(&args, cache).env("RUST_BACKTRACE", "1").output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--resume") && !stderr.to_lowercase().contains("backtrace"), "{stderr}");
    let last: Value = serde_json::from_str(text(&out.stdout).lines().last().unwrap()).unwrap();
    assert_eq!(last["event"], "failed", "{last}");
    assert!(last["error"].as_str().unwrap().contains("--resume"), "{last}");
    let mut changed = scan_args(&dir, &["--uncalibrated", "--resume"]);
    let protocol = changed.iter().position(|a| a == "quick").unwrap();
    changed[protocol] = "paper".into();
    let out = run(&changed, cache);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains("protocol") && stderr.contains("--force"), "{stderr}");
    assert_eq!(Dataset::open(&dir).unwrap().len(), committed * ACTUATORS, "a refused resume changes nothing");
    // The run's log says it failed, and why (the monitor reads how a run ended there).
    let log = std::fs::read_to_string(dir.join("scan.log")).unwrap();
    let last = log.lines().last().unwrap();
    assert!(last.contains("metaplate::run: run failed") && last.contains("--force"), "{last}");

    let mut forced = changed.clone();
    forced.push("--force".into());
    let out = run(&forced, cache);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_complete_scan(&dir);
}

#[test]
fn resume_after_ctrl_c_completes_the_same_configuration() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let args = scan_args(&dir, &["--uncalibrated", "--json"]);
    let mut child = command(&args, cache).stdout(Stdio::piped()).stderr(Stdio::null()).spawn().unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    assert!(lines.by_ref().map(Result::unwrap).any(|l| l.contains("\"committed\"")));
    interrupt(&child);
    lines.for_each(drop);
    assert_eq!(child.wait().unwrap().code(), Some(130));

    let mut resume = args.clone();
    resume.push("--resume".into());
    let out = run(&resume, cache);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_complete_scan(&dir);
    let events: Vec<Value> = text(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let started = &events[0];
    assert!(started["done"].as_u64().unwrap() >= 1, "resume starts after the committed points: {started}");
    assert_eq!(started["resumed"], true, "{started}");
    assert_eq!(events.last().unwrap()["event"], "finished");
}

#[test]
fn resume_into_a_directory_without_a_run_says_plainly_that_a_new_run_starts() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    // A mistyped directory on the morning after: nothing to resume there.
    let dir = tmp.path().join("scna");
    let out = run(&scan_args(&dir, &["--uncalibrated", "--json", "--resume"]), cache);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("holds no run to resume; a new run starts at 0"), "{stderr}");
    let started: Value = serde_json::from_str(text(&out.stdout).lines().next().unwrap()).unwrap();
    assert_eq!((started["event"].as_str(), started["resumed"].as_bool()), (Some("started"), Some(false)), "{started}");
    assert_eq!(started["done"], 0);
    assert_complete_scan(&dir);
    // Without --resume a new run says nothing of it, and its `started` says `"resumed": false` too.
    let fresh = run(&scan_args(&tmp.path().join("fresh"), &["--uncalibrated", "--json"]), cache);
    assert!(!text(&fresh.stderr).contains("no run to resume"), "{}", text(&fresh.stderr));
    let started: Value = serde_json::from_str(text(&fresh.stdout).lines().next().unwrap()).unwrap();
    assert_eq!(started["resumed"], false);
}

#[test]
fn a_hardware_file_without_its_devices_is_a_clear_error() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/hardware.example.toml");
    let tmp = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["scan", "--hardware", example, "--uncalibrated", "--out"])
        .arg(tmp.path().join("scan"))
        .output()
        .unwrap();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot open the LDV") && stderr.contains("usb-FTDI"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn a_scan_that_finishes_with_flagged_rows_exits_3_and_the_codes_are_in_the_help() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    // The scan every test runs, with an adaptive target no measurement reaches in its one round: every row is
    // committed `failed` (the target is final, nothing is deferred), the dataset whole.
    let protocol = "adaptive:1x2@200/1";
    let mut args: Vec<String> = ["scan", "--out", dir.to_str().unwrap(), "--uncalibrated"].map(String::from).to_vec();
    for pair in SCAN.chunks(2) {
        let value = if pair[0] == "--protocol" { protocol } else { pair[1] };
        args.extend([pair[0].to_string(), value.to_string()]);
    }
    let out = run(&args, cache);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("flagged"), "{stderr}");
    let dataset = Dataset::open(&dir).unwrap();
    assert_eq!(dataset.len(), POINTS * ACTUATORS, "finished: one row per point and actuator");
    assert!(dataset.rows().iter().all(|row| row.status == Some(Status::Failed)));

    for command in ["scan", "calibrate"] {
        let help = run(&[command.to_string(), "--help".to_string()], cache);
        let help = text(&help.stdout);
        assert!(help.contains("Exit codes: 0 finished") && help.contains("130 stopped"), "{help}");
    }
    // The protocol names come from the excitation-protocol registry.
    let help = text(&run(&["scan".to_string(), "--help".to_string()], cache).stdout);
    for (name, _) in metaplate_dsp::excitation::NAMES {
        assert!(help.contains(name), "{name} missing from: {help}");
    }
}

#[test]
fn notify_command_hears_of_stalls_the_finish_and_a_failure_once_each() {
    let cache = cache_dir();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("scan");
    let notes = tmp.path().join("notes.jsonl");
    let notify = format!("cat >> '{}'", notes.display());
    // A stall limit far below the mock lab's time per point, so that gaps between commits count as stalls.
    let args = scan_args(&dir, &["--uncalibrated", "--notify-command", &notify, "--stall-after-s", "0.05"]);
    let out = run(&args, cache);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let read = || -> Vec<Value> {
        std::fs::read_to_string(&notes).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect()
    };
    let got = read();
    let last = got.last().unwrap();
    assert_eq!(last["event"], "finished", "{got:?}");
    assert_eq!((last["done"].as_u64(), last["total"].as_u64()), (Some(POINTS as u64), Some(POINTS as u64)));
    assert_eq!(last["dataset"].as_str(), Some(dir.to_str().unwrap()));
    let stalls = got.iter().filter(|n| n["event"] == "stalled").count();
    // At most once per gap: before the first commit, between commits, and after the last (before the finish).
    assert!((1..=POINTS + 1).contains(&stalls), "{stalls} stall notifications: {got:?}");
    assert_eq!(got.iter().filter(|n| n["event"] == "finished").count(), 1);

    // A run that fails (the directory holds a finished run) notifies `failed` with the message.
    let out = run(&args, cache);
    assert_eq!(out.status.code(), Some(1));
    let failed = read().into_iter().last().unwrap();
    assert_eq!(failed["event"], "failed");
    assert!(failed["error"].as_str().unwrap().contains("--resume"), "{failed}");
}

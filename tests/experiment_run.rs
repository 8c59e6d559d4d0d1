//! `metaplate experiment run` on the metamaterial scene's mock lab, over the calibration and 3 x 2 scan of
//! tests/play.rs (the scene's own seed; Green's functions cached under the target directory, shared with the other
//! tests).
//!
//! The scan's six points are 8 cm apart, too coarse for the built-ins' fingertips 3.2 cm apart (refused: two pixels
//! would share a point), so most sessions run a small experiment whose pixels are three of the scan's points; the
//! paper's four built-ins run on the fixture's 7 x 5 scan.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use common::cache_dir;
use metaplate_experiment::journal::JOURNAL_FILE;
use metaplate_experiment::{Entry, SessionRecord};
use serde_json::Value;

/// Three of the scan's points; a train of three bursts at one of them, the others nulled; `repeats` of each.
fn experiment_file(repeats: u32, repeat_pause_s: f64) -> String {
    let mut text = format!(
        "name = \"three-points\"\ndescription = \"which of three measured points plays a burst train\"\n\
         chance = 0.3333333333333333\npresentation = \"once\"\nrepeat_pause_s = {repeat_pause_s}\n\n\
         [phases]\nfamiliarisation = true\nrepeats = {repeats}\n\n[order]\nmode = \"full\"\nseed = 7\n"
    );
    for (k, (name, x_m)) in [("left", -0.08), ("centre", 0.0), ("right", 0.08)].iter().enumerate() {
        text.push_str(&format!("\n[[pixels]]\nname = \"{name}\"\nx_m = {x_m}\ny_m = -0.03\n"));
        text.push_str(&format!("\n[[responses]]\nlabel = \"{name}\"\nkey = \"{}\"\n", k + 1));
        text.push_str(&format!(
            "\n[[stimuli]]\nid = \"at-{name}\"\ncorrect = \"{name}\"\n\
             pixels.{name} = {{ kind = \"noise-bursts\", burst_s = 0.025, pause_s = 0.075, count = 3 }}\n"
        ));
    }
    text
}

/// The calibration and the scan through it (the fixture every test process shares, [`common::calibrated_scan`]),
/// the experiment file (4 repeats: 15 trials) and this process's scratch directory, holding that file.
fn fixtures() -> &'static (PathBuf, PathBuf, PathBuf, PathBuf) {
    static FIXTURES: OnceLock<(PathBuf, PathBuf, PathBuf, PathBuf)> = OnceLock::new();
    FIXTURES.get_or_init(|| {
        let scratch = common::scratch("experiment-run-cli", "fixtures");
        let (cal, scan) = common::calibrated_scan();
        let experiment = scratch.join("three-points.toml");
        std::fs::write(&experiment, experiment_file(4, 0.5)).unwrap();
        (cal, scan, experiment, scratch)
    })
}

/// A fresh path for a session directory (or file) named `name` beside the fixtures.
fn fresh(name: &str) -> PathBuf {
    let path = fixtures().3.join(name);
    let _ = std::fs::remove_dir_all(&path);
    path
}

/// The arguments of `metaplate experiment run EXPERIMENT --participant P --out OUT` on the fixtures.
fn run_args(experiment: &Path, participant: &str, out: &Path) -> Vec<String> {
    let (cal, scan, ..) = fixtures();
    [
        "experiment",
        "run",
        experiment.to_str().unwrap(),
        "--participant",
        participant,
        "--data",
        scan.to_str().unwrap(),
        "--calibration",
        cal.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--scene",
        "metamaterial",
        "--cache-dir",
        cache_dir().to_str().unwrap(),
    ]
    .iter()
    .map(|s| (*s).to_owned())
    .collect()
}

fn command(args: &[String]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_metaplate"));
    c.args(args).env("RUST_BACKTRACE", "0");
    c
}

/// Runs `args` with `stdin` as its standard input.
fn run_with_stdin(args: &[String], stdin: &str) -> Output {
    let mut child = command(args).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).unwrap();
    child.wait_with_output().unwrap()
}

/// What a trial's result is, times on the clock apart (a resumed session's virtual clock starts again at 0):
/// (trial, stimulus, drive hash, response, trial time, repeats requested).
fn results(dir: &Path) -> Vec<(u32, String, String, String, u64, u32)> {
    let record = SessionRecord::read(dir).unwrap();
    record
        .progress
        .results
        .iter()
        .map(|r| {
            let r = r.as_ref().unwrap();
            (
                r.trial,
                r.stimulus_id.clone(),
                r.drive_hash.clone(),
                r.response.clone(),
                r.trial_time_s.to_bits(),
                r.repeats_requested,
            )
        })
        .collect()
}

#[test]
fn a_simulated_session_runs_end_to_end_and_the_report_reads_it() {
    let (.., file, _) = fixtures();
    let out_dir = fresh("sim-whole");
    let mut args = run_args(file, "sim:seed=3", &out_dir);
    args.push("--json".into());
    let out = command(&args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("trial 1 of 15") && stderr.contains("trial 15 of 15"), "{stderr}");
    let events: Vec<Value> =
        String::from_utf8_lossy(&out.stdout).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(events.len(), 16);
    assert_eq!(events[15]["event"], "finished");
    for e in &events[..15] {
        assert_eq!(e["event"], "trial");
        // The onset measured on the loopback follows the scheduled one by the mock interface's latency.
        let latency_s = e["measured_onset_s"].as_f64().unwrap() - e["scheduled_onset_s"].as_f64().unwrap();
        assert!(latency_s > 0.0 && latency_s < 0.05, "{e}");
        assert!(e.get("stimulus_id").is_none() && e.get("correct").is_none(), "blind: {e}");
    }
    // One drive per stimulus, recorded with every trial that plays it.
    let record = SessionRecord::read(&out_dir).unwrap();
    let mut hashes: Vec<(String, String)> =
        record.progress.results.iter().flatten().map(|r| (r.stimulus_id.clone(), r.drive_hash.clone())).collect();
    hashes.sort();
    hashes.dedup();
    assert_eq!(hashes.len(), 3, "{hashes:?}");

    let out = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["experiment", "report", out_dir.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["experiment"], "three-points");
    let p = &report["participants"][0];
    assert_eq!(p["id"], "sim:seed=3");
    assert_eq!(p["scored_trials"], 12);
    // Focused on points 8 cm apart, far above threshold: the simulated participant is near perfect.
    assert!(p["correct"].as_u64().unwrap() >= 10, "{report}");
}

/// A number in `0..n` from the clock's nanoseconds (the kill instants; printed, so a failure can be replayed).
fn random_below(n: u64) -> u64 {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().subsec_nanos();
    u64::from(nanos.wrapping_mul(2_654_435_761)) % n.max(1)
}

/// Runs `experiment` (a file or a built-in's name) twice with `sim:seed=3` on `scan`: once whole, once killed
/// with SIGKILL at a random instant (after a random number of journal entries, at least one and at most half the
/// trials, plus a random 0 to 20 ms) and resumed. The signal goes to the binary's own process (spawned directly,
/// no shell around it: its `/proc/PID/exe` is checked). Both must have the same plan and the same results (clock
/// times apart). Returns the whole session's directory and what it printed on standard error.
fn whole_and_killed_sessions_agree(experiment: &Path, scan: &Path, name: &str, trials: usize) -> (PathBuf, String) {
    let with_scan = |out: &Path| {
        let mut args = run_args(experiment, "sim:seed=3", out);
        let at = args.iter().position(|a| a == "--data").unwrap() + 1;
        args[at] = scan.to_str().unwrap().to_owned();
        args
    };
    let whole = fresh(&format!("{name}-uninterrupted"));
    let out = command(&with_scan(&whole)).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");

    let split = fresh(&format!("{name}-killed"));
    let args = with_scan(&split);
    let mut child = command(&args).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    if let Ok(exe) = std::fs::read_link(format!("/proc/{}/exe", child.id())) {
        assert_eq!(exe, Path::new(env!("CARGO_BIN_EXE_metaplate")), "the child is the binary itself");
    }
    let journal = split.join(JOURNAL_FILE);
    let started = Instant::now();
    let lines = || std::fs::read_to_string(&journal).map_or(0, |t| t.lines().count());
    let (after, delay_ms) = (1 + random_below(trials as u64 / 2) as usize, random_below(21));
    eprintln!("{name}: killed after {after} journal lines and {delay_ms} ms");
    while lines() < after {
        assert!(started.elapsed() < Duration::from_secs(120), "no {after} journal lines in 2 minutes");
        assert!(child.try_wait().unwrap().is_none(), "the session ended before it was killed");
        std::thread::sleep(Duration::from_millis(1));
    }
    std::thread::sleep(Duration::from_millis(delay_ms));
    assert!(child.try_wait().unwrap().is_none(), "the session ended before it was killed");
    child.kill().unwrap(); // SIGKILL, to the binary's process
    child.wait().unwrap();
    let killed = SessionRecord::read(&split).unwrap();
    let answered = killed.progress.results.iter().flatten().count();
    assert!((1..trials).contains(&answered), "killed after {answered} of {trials} trials");

    let out = command(&args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read(whole.join("plan.json")).unwrap(), std::fs::read(split.join("plan.json")).unwrap());
    let results = results(&whole);
    assert_eq!(results.len(), trials);
    assert_eq!(results, self::results(&split));
    (whole, stderr)
}

#[test]
fn a_session_killed_with_sigkill_resumes_with_the_same_plan_and_results() {
    // 10 repeats (33 trials, some 15 ms each here), so that a loaded machine still kills it mid-session.
    let file = fresh("long.toml");
    std::fs::write(&file, experiment_file(10, 0.5)).unwrap();
    whole_and_killed_sessions_agree(&file, &fixtures().1, "three-points", 33);
}

/// A built-in experiment on the 7 x 5 scan ([`common::fingertip_scan`], where the five fingertips snap to five
/// points): the simulated participant's sessions, whole and killed then resumed, agree
/// ([`whole_and_killed_sessions_agree`]), and `experiment report --json` reads them: `scored` trials, and an
/// accuracy far above `chance`.
fn built_in_runs_resumes_and_is_reported(name: &str, trials: usize, scored: u64, chance: f64) -> Value {
    let (dir, stderr) = whole_and_killed_sessions_agree(Path::new(name), &common::fingertip_scan(), name, trials);
    // The paper's masker, on the interface's last two outputs beside the actuators' (the mock interface has 24).
    assert!(stderr.contains("masking: pink noise on outputs 22 and 23 at -20 dB FS RMS"), "{stderr}");
    let out = command(&["experiment".into(), "report".into(), dir.to_str().unwrap().into(), "--json".into()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["experiment"], name);
    assert_eq!(report["chance"].as_f64(), Some(chance));
    let pooled = &report["pooled"];
    assert_eq!(pooled["scored_trials"].as_u64(), Some(scored), "{report}");
    // The fingertips' points are 3.2 cm apart, the focus is tens of dB above the nulls there (the README's
    // stimulus table), so the simulated participant errs only by its 2 % lapse: 90 % leaves room for a few lapses
    // (P(more than 5 lapses in 50) < 0.1 %), and the Wilson interval must clear chance.
    let accuracy = pooled["accuracy"].as_f64().unwrap();
    assert!(accuracy >= 0.9, "{report}");
    assert!(pooled["wilson_95"][0].as_f64().unwrap() > chance, "{report}");
    assert!(pooled["p_value"].as_f64().unwrap() < 1e-9, "{report}");
    report
}

#[test]
fn pixel_identification_runs_end_to_end_resumes_and_is_reported() {
    let report = built_in_runs_resumes_and_is_reported("pixel-identification", 55, 50, 0.2);
    // The confusion matrix is answered against presented over the five fingers.
    let counts = report["pooled"]["confusion"]["presented_by_answered"].as_array().unwrap();
    assert_eq!(counts.len(), 5, "{report}");
}

#[test]
fn odd_one_out_exploration_runs_end_to_end_resumes_and_is_reported() {
    let report = built_in_runs_resumes_and_is_reported("odd-one-out-exploration", 60, 50, 0.2);
    // Experiment 2 records trial times: the stimulus repeats until the response.
    for c in report["pooled"]["conditions"].as_array().unwrap() {
        assert!(c["trial_time_s"]["median"].as_f64().unwrap() > 0.0, "{c}");
    }
}

#[test]
fn motion_direction_runs_end_to_end_resumes_and_is_reported() {
    let report = built_in_runs_resumes_and_is_reported("motion-direction", 88, 80, 0.5);
    assert_eq!(report["pooled"]["conditions"].as_array().unwrap().len(), 8, "{report}");
}

#[test]
fn multi_touch_odd_one_out_runs_end_to_end_resumes_and_is_reported() {
    built_in_runs_resumes_and_is_reported("multi-touch-odd-one-out", 55, 50, 0.2);
}

#[test]
fn a_changed_experiment_file_is_refused_on_resume_unless_forced() {
    let original = fresh("changed.toml");
    std::fs::write(&original, experiment_file(4, 0.5)).unwrap();
    let dir = fresh("changed-session");
    // One trial answered at the console, then the input ends: the session stops, resumable.
    let out = run_with_stdin(&run_args(&original, "P07", &dir), "2\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    std::fs::write(&original, experiment_file(4, 0.75)).unwrap();
    let out = run_with_stdin(&run_args(&original, "P07", &dir), "1\n");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("experiment file hash"), "{stderr}");
    let mut forced = run_args(&original, "P07", &dir);
    forced.push("--force".into());
    let out = run_with_stdin(&forced, "1\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let record = SessionRecord::read(&dir).unwrap();
    assert!(matches!(record.entries[1], Entry::Forced { .. }), "{:?}", record.entries);
    assert_eq!(record.progress.results.iter().flatten().count(), 2);
    // Another participant's session is refused too.
    let out = run_with_stdin(&run_args(&original, "P08", &dir), "1\n");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("participant `P07`"));
}

#[test]
fn the_console_journals_undo_and_void_as_new_entries_and_stays_blind() {
    let (.., file, _) = fixtures();
    let dir = fresh("console");
    // Answer 1; undo it and answer 2; void the next; an unknown key; repeat the stimulus, answer 3; pause, go on,
    // answer 1; then the input ends.
    let out = run_with_stdin(&run_args(file, "P01", &dir), "1\nu\n2\nv\nq\nr\n3\np\n\n1\n");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("trial 1 of 15: 1 left  2 centre  3 right"), "{stderr}");
    assert!(stderr.contains("`q` is not a key here"), "{stderr}");
    assert!(stderr.contains("stopped with 3 of 15"), "{stderr}");
    assert!(!stderr.contains("at-"), "the console shows no stimulus: {stderr}");

    let record = SessionRecord::read(&dir).unwrap();
    let kinds: Vec<&str> = record
        .entries
        .iter()
        .map(|e| match e {
            Entry::Trial(_) => "trial",
            Entry::Undo { .. } => "undo",
            Entry::Void { .. } => "void",
            Entry::Correction { .. } => "correction",
            Entry::Forced { .. } => "forced",
        })
        .collect();
    assert_eq!(kinds, ["trial", "undo", "trial", "void", "trial", "trial"]);
    let Entry::Trial(first) = &record.entries[0] else { unreachable!() };
    let Entry::Trial(again) = &record.entries[2] else { unreachable!() };
    assert_eq!((first.trial, first.response.as_str()), (0, "left"));
    assert_eq!((again.trial, again.response.as_str()), (0, "centre"));
    let Entry::Void { trial: voided, .. } = record.entries[3] else { unreachable!() };
    let Entry::Trial(repeated) = &record.entries[4] else { unreachable!() };
    assert_eq!((repeated.response.as_str(), repeated.repeats_requested), ("right", 1));
    // The voided trial is asked again at the end.
    assert_eq!(record.progress.queue.last(), Some(&voided));
    assert!(record.progress.results[voided as usize].is_none());
}

#[test]
fn a_built_in_whose_pixels_share_a_measured_point_is_refused_with_nothing_written() {
    let dir = fresh("builtin");
    let out = command(&run_args(Path::new("pixel-identification"), "sim", &dir)).output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("snap to the same measured point"), "{stderr}");
    assert!(!dir.exists());
}

#[test]
fn the_stimuli_report_gives_each_pixels_predicted_peak_and_the_suppression() {
    let (cal, scan, experiment, _) = fixtures();
    let args = [
        "experiment",
        "stimuli",
        experiment.to_str().unwrap(),
        "--data",
        scan.to_str().unwrap(),
        "--calibration",
        cal.to_str().unwrap(),
        "--json",
    ];
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let stimuli = doc["experiments"][0]["stimuli"].as_array().unwrap();
    assert_eq!(stimuli.len(), 3, "{doc}");
    for s in stimuli {
        let roles: Vec<&str> = s["pixels"].as_array().unwrap().iter().map(|p| p["role"].as_str().unwrap()).collect();
        assert_eq!(roles.iter().filter(|r| **r == "target").count(), 1, "{s}");
        assert_eq!(roles.iter().filter(|r| **r == "null").count(), 2, "{s}");
        // Three of the scan's six points with eight actuators: the nulls are met almost exactly (the inverse
        // filter's regularisation leaves a residue), the target's burst reaches millimetres per second.
        let target = s["target_min_mm_s"].as_f64().unwrap();
        assert!((0.1..100.0).contains(&target), "{s}");
        assert!(s["suppression_db"].as_f64().unwrap() > 20.0, "{s}");
        // Within a fingertip's 5 mm (the scan's points are 8 cm apart): the point itself.
        for p in s["pixels"].as_array().unwrap() {
            assert_eq!(p["within_fingertip_mm_s"], p["predicted_peak_mm_s"], "{p}");
        }
    }
    // The figure of the stimuli at their pixels (Figs. S8 to S11), one per experiment.
    let figures = fresh("stimuli-figures");
    let mut with_figures = args.to_vec();
    with_figures.extend(["--figures", figures.to_str().unwrap()]);
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(&with_figures).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for ext in ["png", "svg"] {
        assert!(figures.join(format!("three-points-stimuli.{ext}")).is_file());
    }
    // A reach of 9 cm takes in the neighbouring points, where nothing is nulled: the nulls' figures grow.
    let mut wide = args.to_vec();
    wide.extend(["--fingertip-radius-m", "0.09"]);
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(&wide).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    for s in doc["experiments"][0]["stimuli"].as_array().unwrap() {
        for p in s["pixels"].as_array().unwrap().iter().filter(|p| p["role"] == "null") {
            let (at, near) = (p["predicted_peak_mm_s"].as_f64().unwrap(), p["within_fingertip_mm_s"].as_f64().unwrap());
            assert!(near > 10.0 * at, "{p}");
        }
    }
    // The built-ins on the coarse scan: refused as `run` refuses them, naming why.
    let mut builtin = args;
    builtin[2] = "pixel-identification";
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(builtin).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("snap to the same measured point"));
}

#[test]
fn the_stimuli_judged_on_the_ground_truth_match_the_scans_prediction_at_the_targets() {
    let (cal, _, _, _) = fixtures();
    let scan = common::fingertip_scan();
    let args = |truth: &str| {
        [
            "experiment",
            "stimuli",
            "pixel-identification",
            "--data",
            scan.to_str().unwrap(),
            "--calibration",
            cal.to_str().unwrap(),
            "--truth",
            truth,
            "--json",
            "--cache-dir",
            cache_dir().to_str().unwrap(),
        ]
        .map(str::to_owned)
    };
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args("metamaterial")).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let stimuli = doc["experiments"][0]["stimuli"].as_array().unwrap();
    assert_eq!(stimuli.len(), 5);
    for s in stimuli {
        let (predicted, truth) = (s["target_min_mm_s"].as_f64().unwrap(), s["true_target_min_mm_s"].as_f64().unwrap());
        // A quick scan's Green's functions lie about -35 dB (2 %) from the plate's truth (full grid, seed 11, at the
        // fingertips: median -34.4 dB): the focus, a sum of eight in-phase contributions, is met to that.
        assert!((truth / predicted - 1.0).abs() < 0.05, "{s}");
        // A null is a cancellation of eight contributions, each known to about 2 %: it holds to some 30 to 45 dB
        // on the plate, never much deeper than predicted.
        let true_db = s["true_suppression_at_points_db"].as_f64().unwrap();
        assert!(true_db > 25.0 && true_db <= s["suppression_at_points_db"].as_f64().unwrap() + 3.0, "{s}");
        for p in s["pixels"].as_array().unwrap() {
            assert!(p["true_peak_mm_s"].as_f64().unwrap().is_finite(), "{p}");
        }
    }
    // Another plate's truth is refused, naming the scan's.
    let out = Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args("homogeneous")).output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("the scan was made on the scene `metamaterial`"), "{stderr}");
}

/// The console's session of `args` fed `answers` (one line each) and then the end of its input.
fn console_session(args: &[String], answers: &str) -> Output {
    run_with_stdin(args, answers)
}

/// `experiment report --json` of `dir`, with the `dir` key taken out (it names the directory).
fn report_without_dir(dir: &Path) -> Value {
    let out = command(&["experiment".into(), "report".into(), dir.to_str().unwrap().into(), "--json".into()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut report: Value = serde_json::from_slice(&out.stdout).unwrap();
    report["participants"][0].as_object_mut().unwrap().remove("dir");
    report
}

#[test]
fn a_second_run_on_a_session_in_use_is_refused_at_once_and_the_first_completes() {
    let (.., file, _) = fixtures();
    // 15 trials answered at the console: the left key for every trial.
    let answers = "1\n".repeat(15);
    let whole = fresh("one-writer-uninterrupted");
    let out = console_session(&run_args(file, "P11", &whole), &answers);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    // The first process answers one trial and waits at the console for the second.
    let dir = fresh("one-writer");
    let args = run_args(file, "P11", &dir);
    let mut first = command(&args).stdin(Stdio::piped()).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let mut stdin = first.stdin.take().unwrap();
    stdin.write_all(b"1\n").unwrap();
    let journal = dir.join(JOURNAL_FILE);
    let started = Instant::now();
    while std::fs::read_to_string(&journal).map_or(0, |t| t.lines().count()) < 1 {
        assert!(started.elapsed() < Duration::from_secs(120), "the first process journalled nothing in 2 minutes");
        std::thread::sleep(Duration::from_millis(10));
    }
    let before: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    for participant in ["P11", "sim:seed=3"] {
        let asked = Instant::now();
        let second = run_with_stdin(&run_args(file, participant, &dir), "1\n");
        let stderr = String::from_utf8_lossy(&second.stderr);
        assert!(!second.status.success(), "{stderr}");
        assert!(stderr.contains("is in use by another process"), "{stderr}");
        assert!(stderr.contains(dir.to_str().unwrap()) && stderr.contains(&format!("pid {}", first.id())), "{stderr}");
        assert!(!stderr.contains("trial "), "refused before any trial: {stderr}");
        assert!(asked.elapsed() < Duration::from_secs(30), "refused at once, not after {:?}", asked.elapsed());
    }
    let after: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    assert_eq!(before, after, "the refused processes changed nothing");
    stdin.write_all("1\n".repeat(14).as_bytes()).unwrap();
    drop(stdin);
    let out = first.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let record = SessionRecord::read(&dir).unwrap();
    assert!(record.duplicates.is_empty());
    assert_eq!(record.entries.len(), 15);
    assert_eq!(report_without_dir(&dir), report_without_dir(&whole));
}

/// Appends to `dir`'s journal a copy of its `line`-th entry (0-based), with the response `response` if given.
fn duplicate_entry(dir: &Path, line: usize, response: Option<&str>) {
    let path = dir.join(JOURNAL_FILE);
    let text = std::fs::read_to_string(&path).unwrap();
    let mut entry: Value = serde_json::from_str(text.lines().nth(line).unwrap()).unwrap();
    if let Some(r) = response {
        entry["response"] = r.into();
    }
    let mut f = std::fs::OpenOptions::new().append(true).open(&path).unwrap();
    writeln!(f, "{entry}").unwrap();
}

#[test]
fn a_session_with_duplicated_entries_is_reported_and_resumed_or_refused_until_settled() {
    let (.., file, _) = fixtures();
    let dir = fresh("duplicated");
    let args = run_args(file, "P12", &dir);
    // Three trials answered, then the input ends; two processes then journalled trials 1 and 2 twice (agreeing).
    let out = console_session(&args, "1\n2\n3\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    duplicate_entry(&dir, 0, None);
    duplicate_entry(&dir, 1, None);
    let record = SessionRecord::read(&dir).unwrap();
    let first_trial = match &record.entries[0] {
        Entry::Trial(r) => r.trial,
        other => panic!("{other:?}"),
    };
    let report = report_without_dir(&dir);
    let dups = report["participants"][0]["duplicated_trials"].as_array().unwrap().clone();
    assert_eq!(dups.len(), 2, "{report}");
    assert_eq!(dups[0]["trial"], first_trial);
    assert_eq!(dups[0]["responses"], serde_json::json!(["left", "left"]));
    assert_eq!(dups[0]["counted"], "left");
    let text = command(&["experiment".into(), "report".into(), dir.to_str().unwrap().into()]).output().unwrap();
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("trials journalled more than once") && text.contains("(agree)"), "{text}");
    // Agreeing duplicates: the session continues.
    let out = console_session(&args, "1\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(SessionRecord::read(&dir).unwrap().progress.results.iter().flatten().count(), 4);

    // A conflicting duplicate (trial 1 answered `right` by the other process): refused, naming it and the fix.
    duplicate_entry(&dir, 0, Some("right"));
    let journal_before = std::fs::read(dir.join(JOURNAL_FILE)).unwrap();
    let out = console_session(&args, "1\n");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("trial {first_trial} (left, left, right)")), "{stderr}");
    assert!(stderr.contains("metaplate experiment correct"), "{stderr}");
    assert_eq!(std::fs::read(dir.join(JOURNAL_FILE)).unwrap(), journal_before, "nothing written");
    let report = report_without_dir(&dir);
    assert_eq!(report["participants"][0]["duplicated_trials"][0]["counted"], "left", "the first answer counts");
    // Settled by a correction, the session continues, and the corrected answer counts.
    let correct =
        ["experiment", "correct", dir.to_str().unwrap(), "--trial", &first_trial.to_string(), "--response", "right"]
            .map(String::from);
    let out = command(&correct).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = console_session(&args, "1\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let record = SessionRecord::read(&dir).unwrap();
    assert_eq!(record.progress.results[first_trial as usize].as_ref().unwrap().response, "right");
    assert_eq!(record.progress.results.iter().flatten().count(), 5);
}

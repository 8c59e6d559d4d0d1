//! Crash safety of `metaplate scan` and `metaplate calibrate`: kill -9 at random instants (seeded), inside units
//! (while a point or an actuator is measured or processed) and inside commits (made wide by the store's
//! commit-pause test hook), resume each time until it finishes; the final dataset must equal an uninterrupted run
//! with the same seed, row for row: same keys, bit-identical impulse responses, same statuses, no duplicates, no gaps.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use std::collections::BTreeSet;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use metaplate_core::rng::SplitMix64;
use metaplate_store::Dataset;

/// The scan under test: 4 x 3 points of the metamaterial grid (all on the plate), the quick protocol, the scene's own
/// seed.
const SCAN: &[&str] = &["scan", "--scene", "metamaterial", "--protocol", "quick", "--grid", "4x3", "--uncalibrated"];
/// Milliseconds each commit pauses between its batch file's rename and its journal line (the store's test hook):
/// long against a point's acquisition in fast-forward (about 0.15 s in the debug profile), so that a good share of
/// random kills land inside a commit.
const COMMIT_PAUSE_MS: u64 = 200;
const KILLS: usize = 24;

fn cache_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The calibration under test: the metamaterial scene's 8 actuators, the scene's own seed (one Green's-function request
/// with the scan's and `recipes.rs`'s, so the cache serves all of them).
const CALIBRATE: &[&str] = &["calibrate", "--scene", "metamaterial"];
const CALIBRATE_KILLS: usize = 6;

fn command(args: &[&str], out: &Path, resume: bool, commit_pause_ms: u64) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_metaplate"));
    command.args(args).arg("--out").arg(out).arg("--cache-dir").arg(cache_dir()).arg("--json");
    if resume {
        command.arg("--resume");
    }
    command.env("METAPLATE_TEST_COMMIT_PAUSE_MS", commit_pause_ms.to_string()).env("RUST_BACKTRACE", "0");
    command
}

/// Batch files in `batches/` that no journal line lists (a kill between the rename and the journal append).
fn unjournaled_batches(dir: &Path) -> usize {
    let journal = std::fs::read_to_string(dir.join("journal.jsonl")).unwrap_or_default();
    let journaled: BTreeSet<String> = journal
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter_map(|v| v["file"].as_str().map(str::to_owned))
        .collect();
    let Ok(entries) = std::fs::read_dir(dir.join("batches")) else { return 0 };
    entries
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".parquet") && !journaled.contains(name))
        .count()
}

/// Runs to completion, returning the wall time from the `started` event to the end and the points.
fn uninterrupted(args: &[&str], out: &Path, commit_pause_ms: u64) -> Duration {
    let mut child =
        command(args, out, false, commit_pause_ms).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let mut started = None;
    for line in BufReader::new(child.stdout.take().unwrap()).lines() {
        if line.unwrap().contains("\"started\"") {
            started = Some(Instant::now());
        }
    }
    let output = child.wait_with_output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    started.unwrap().elapsed()
}

#[test]
fn kill_9_at_random_instants_then_resume_equals_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let reference_dir = tmp.path().join("reference");
    let scan_time = uninterrupted(SCAN, &reference_dir, COMMIT_PAUSE_MS);
    let reference = Dataset::open(&reference_dir).unwrap();
    let points = reference.points().len();
    eprintln!("uninterrupted: {points} points in {scan_time:?} after start-up");

    let dir = tmp.path().join("crashed");
    let mut rng = SplitMix64::new(0x6b69_6c6c, 0);
    let (mut kills, mut inside_commit, mut inside_point, mut runs) = (0, 0, 0, 0);
    let per_point = scan_time / points as u32;
    loop {
        runs += 1;
        assert!(runs < 200, "no end after {runs} runs");
        let resume = runs > 1;
        let mut child =
            command(SCAN, &dir, resume, COMMIT_PAUSE_MS).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let spawned = Instant::now();
        // Lines from the child as they come, time-stamped on arrival.
        let (tx, rx) = mpsc::channel();
        let stdout = child.stdout.take().unwrap();
        let reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                if tx.send(line.unwrap()).is_err() {
                    break;
                }
            }
        });
        let mut after_start = false;
        let kill_at = if kills >= KILLS {
            None
        } else if rng.uniform() < 0.2 {
            // Anywhere in start-up: opening the dataset (resume, quarantine), the lab, the instruments.
            Some(spawned + Duration::from_secs_f64(0.6 * rng.uniform()))
        } else if rng.uniform() < 0.12 {
            // Inside a commit: the engine's `committing` phase event comes just before the batch file is written;
            // the test pause then holds the commit between the file's rename and its journal line, where this
            // lands (a timed kill alone reached that window too rarely under load).
            let seen = rx.iter().find(|l| l.contains("\"committing\"") || l.contains("\"finished\""));
            let delay = Duration::from_millis(COMMIT_PAUSE_MS).mul_f64(0.5 + 0.45 * rng.uniform());
            after_start = true;
            seen.filter(|l| !l.contains("\"finished\"")).map(|_| Instant::now() + delay)
        } else {
            // After the scan started, or after its first commit (so that the run makes progress), within one
            // point's time: an acquisition, processing, or the next commit.
            let marker = if rng.uniform() < 0.25 { "\"committed\"" } else { "\"started\"" };
            let seen = rx.iter().find(|l| l.contains(marker) || l.contains("\"finished\""));
            let delay = per_point.mul_f64(rng.uniform());
            after_start = true;
            seen.filter(|l| !l.contains("\"finished\"")).map(|_| Instant::now() + delay)
        };
        let mut killed = false;
        if let Some(at) = kill_at {
            std::thread::sleep(at.saturating_duration_since(Instant::now()));
            if child.try_wait().unwrap().is_none() {
                // SIGKILL (std's kill on Unix): no handler runs, as with kill -9.
                child.kill().unwrap();
                killed = true;
            }
        }
        let output = child.wait_with_output().unwrap();
        reader.join().unwrap();
        if killed && output.status.code().is_none() {
            kills += 1;
            if unjournaled_batches(&dir) > 0 {
                inside_commit += 1;
            } else if after_start {
                // After `started` a point is always being measured or processed (the next one is recorded while
                // the previous one is processed): the kill cut a unit.
                inside_point += 1;
            }
            continue;
        }
        assert!(output.status.success(), "run {runs}: {}", String::from_utf8_lossy(&output.stderr));
        break;
    }
    eprintln!("{kills} kills ({inside_commit} inside a commit, {inside_point} inside a point) in {runs} runs");
    assert!(kills >= 20, "only {kills} kills landed");
    assert!(inside_point >= KILLS / 2, "only {inside_point} of {kills} kills landed inside a point");
    assert!(inside_commit >= 1, "no kill landed between a batch file's rename and its journal line");

    assert_same_rows(&reference, &Dataset::open(&dir).unwrap());
}

/// The crashed-and-resumed dataset equals the reference row for row, bit for bit.
fn assert_same_rows(reference: &Dataset, crashed: &Dataset) {
    assert_eq!(crashed.len(), reference.len(), "no duplicates, no gaps");
    let keys = |d: &Dataset| d.rows().iter().map(|r| (r.point_index, r.actuator)).collect::<BTreeSet<_>>();
    assert_eq!(keys(crashed), keys(reference));
    assert_eq!(keys(crashed).len(), crashed.len(), "each (point, actuator) once");
    // Every row bit for bit; the differences are collected first, so that a failure says how far apart the two
    // runs are (relative error energy of the impulse response, dB) and where.
    let mut mismatches = Vec::new();
    for row in reference.rows() {
        let (p, a) = (row.point_index, row.actuator);
        let other = crashed.meta(p, a).unwrap();
        let (x, y) = (crashed.ir(p, a).unwrap(), reference.ir(p, a).unwrap());
        let same_ir = x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits());
        let same_snr = other.snr_db.map(f64::to_bits) == row.snr_db.map(f64::to_bits);
        if !same_ir || !same_snr || other.status != row.status {
            let error: f64 = x.iter().zip(y).map(|(u, v)| f64::from(u - v).powi(2)).sum();
            let energy: f64 = y.iter().map(|v| f64::from(*v).powi(2)).sum();
            mismatches.push(format!(
                "point {p} actuator {a}: IR error {:.1} dB, SNR {:?} vs {:?}, status {:?} vs {:?}",
                10.0 * (error / energy).log10(),
                other.snr_db,
                row.snr_db,
                other.status,
                row.status
            ));
        }
    }
    assert!(
        mismatches.is_empty(),
        "{} of {} rows differ:\n{}",
        mismatches.len(),
        reference.len(),
        mismatches.join("\n")
    );
}

#[test]
fn calibrate_killed_inside_actuators_then_resumed_equals_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().unwrap();
    let reference_dir = tmp.path().join("reference");
    let calibration_time = uninterrupted(CALIBRATE, &reference_dir, 0);
    let reference = Dataset::open(&reference_dir).unwrap();
    let units = reference.rows().iter().map(|r| r.actuator).collect::<BTreeSet<_>>().len();
    let per_unit = calibration_time / units as u32;
    eprintln!("uninterrupted: {units} actuators in {calibration_time:?} after start-up");

    let dir = tmp.path().join("crashed");
    let mut rng = SplitMix64::new(0x6361_6c69, 0);
    let (mut kills, mut inside_unit, mut runs) = (0, 0, 0);
    loop {
        runs += 1;
        assert!(runs < 50, "no end after {runs} runs");
        let mut child =
            command(CALIBRATE, &dir, runs > 1, 0).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
        let stdout = child.stdout.take().unwrap();
        let mut lines = BufReader::new(stdout).lines().map(Result::unwrap);
        let mut killed = false;
        // Kills go on until enough landed inside actuators: how many do depends on the machine's load (the sleep is
        // timed on the uninterrupted run), so the count of runs varies, not what is checked.
        if kills < CALIBRATE_KILLS || inside_unit < CALIBRATE_KILLS / 2 {
            // Half-way-ish through an actuator: the first of this run (after `started`) or the second (after the
            // first `committed`, so that the run makes progress), well clear of both ends.
            let marker = if rng.uniform() < 0.3 { "\"started\"" } else { "\"committed\"" };
            let seen = lines.by_ref().find(|l| l.contains(marker) || l.contains("\"finished\""));
            // Then into a step of the actuator the run is on: as it plays, waits for its processing, or commits
            // (the engine's phase events), and a little later, so the kill lands inside that step whatever the
            // machine's load (a sleep timed on the uninterrupted run alone let loaded runs commit several actuators
            // between kills, and the calibration ran out of actuators before enough kills had landed).
            let phase = ["\"playing\"", "\"processing\"", "\"committing\""][(rng.uniform() * 3.0) as usize % 3];
            let seen = seen
                .filter(|l| !l.contains("\"finished\""))
                .and_then(|_| lines.by_ref().find(|l| l.contains(phase) || l.contains("\"finished\"")));
            if seen.is_some_and(|l| !l.contains("\"finished\"")) {
                std::thread::sleep(per_unit.mul_f64(0.15 * rng.uniform()));
                if child.try_wait().unwrap().is_none() {
                    child.kill().unwrap();
                    killed = true;
                }
            }
        }
        // What the run printed after the marker: a kill that lands before the next `committed` was inside an
        // actuator's measurement, processing or commit.
        let later: Vec<String> = lines.collect();
        let output = child.wait_with_output().unwrap();
        if killed && output.status.code().is_none() {
            kills += 1;
            if !later.iter().any(|l| l.contains("\"committed\"")) {
                inside_unit += 1;
            }
            continue;
        }
        assert!(output.status.success(), "run {runs}: {}", String::from_utf8_lossy(&output.stderr));
        break;
    }
    eprintln!("{kills} kills ({inside_unit} inside an actuator) in {runs} runs");
    assert!(kills >= CALIBRATE_KILLS, "only {kills} kills landed");
    assert!(inside_unit >= CALIBRATE_KILLS / 2, "only {inside_unit} of {kills} kills landed inside an actuator");
    assert_same_rows(&reference, &Dataset::open(&dir).unwrap());
}

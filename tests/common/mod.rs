//! What several of the binary's test files share: the Green's-function cache under the target directory (shared by
//! every test run and file, and with the recipes' tests) and running `metaplate` with it.
#![allow(dead_code, clippy::unwrap_used)] // Each test file uses a subset; tests may unwrap.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The Green's-function cache in `CARGO_TARGET_TMPDIR` (created when missing).
pub fn cache_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `metaplate ARGS --cache-dir <the cache>`, its output collected, without backtraces.
pub fn metaplate(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(args)
        .arg("--cache-dir")
        .arg(cache_dir())
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap()
}

/// `metaplate ARGS` as given (for commands that take no cache directory), its output collected, without
/// backtraces.
pub fn metaplate_bare(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args).env("RUST_BACKTRACE", "0").output().unwrap()
}

/// A fresh, empty directory `name` of test file `area`, of this test process's own (under cargo-nextest every test
/// is a process: two tests must not share, and replace, one directory), under the target's temporary directory so
/// that `cargo clean` removes it.
pub fn scratch(area: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(area).join(std::process::id().to_string()).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A calibration (`calibrate`) and two quick scans through it (`scan --protocol quick`), with the scene's own seed,
/// on the metamaterial scene's mock lab, written into `dir` (as `cal`, `scan` and `scan-7x5`):
/// - `scan`, `--grid 3x2`: the small scan the play and experiment tests render on (points at x -0.08, 0, 0.08 m
///   and y -0.03, 0.03 m);
/// - `scan-7x5`: fine enough for the built-in experiments' fingertips (x -0.1 to 0.1 m in steps of 1/30 m, so
///   the five pixels 3.2 cm apart on y = 0 snap to five points within 3 mm). It shares its Green's functions with
///   `check --grid 7x5` (tests/check.rs), so in a test run it costs no plate computation of its own.
///
/// Returns (calibration, 3 x 2 scan).
pub fn calibration_and_scan_3x2(dir: &Path) -> (PathBuf, PathBuf) {
    let cal = dir.join("cal");
    let out = metaplate(&["calibrate", "--scene", "metamaterial", "--out", cal.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for (grid, name) in [("3x2", "scan"), ("7x5", "scan-7x5")] {
        let out = metaplate(&[
            "scan",
            "--scene",
            "metamaterial",
            "--protocol",
            "quick",
            "--grid",
            grid,
            "--calibration",
            cal.to_str().unwrap(),
            "--out",
            dir.join(name).to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    (cal, dir.join("scan"))
}

/// The calibration and the 3 x 2 scan of [`calibration_and_scan_3x2`]: (calibration, scan); the 7 x 5 scan is
/// [`fingertip_scan`]. Made once per build of the binary and shared by every test
/// process that needs it (play, experiments): the first takes a lock file and builds them in a scratch directory
/// renamed into place when complete; the others wait for it. Keyed by the binary's modification time, so a rebuilt
/// binary makes its own.
pub fn calibrated_scan() -> (PathBuf, PathBuf) {
    let binary = std::fs::metadata(env!("CARGO_BIN_EXE_metaplate")).unwrap();
    let stamp = binary.modified().unwrap().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fixtures");
    std::fs::create_dir_all(&root).unwrap();
    let done = root.join(format!("cal-scans-seed5-{stamp:x}"));
    let paths = |dir: &Path| (dir.join("cal"), dir.join("scan"));
    let lock = done.with_extension("lock");
    for _ in 0..1200 {
        if done.is_dir() {
            return paths(&done);
        }
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&lock) {
            Ok(_) => {
                let scratch = root.join(format!("building-{}", std::process::id()));
                let _ = std::fs::remove_dir_all(&scratch);
                std::fs::create_dir_all(&scratch).unwrap();
                calibration_and_scan_3x2(&scratch);
                // The scan records the calibration's content hash, not its path: the pair moves together.
                std::fs::rename(&scratch, &done).unwrap();
                std::fs::remove_file(&lock).unwrap();
                return paths(&done);
            }
            // Another process builds it (a lock older than 10 minutes is a dead builder's: taken over).
            Err(_) => {
                let age = std::fs::metadata(&lock).and_then(|m| m.modified()).ok().and_then(|t| t.elapsed().ok());
                if age.is_some_and(|a| a.as_secs() > 600) {
                    let _ = std::fs::remove_file(&lock);
                }
                std::thread::sleep(std::time::Duration::from_millis(500));
            }
        }
    }
    panic!("the calibrated scan fixture was not built within 10 minutes (lock {})", lock.display());
}

/// The 7 x 5 scan of [`calibration_and_scan_3x2`] (through the calibration [`calibrated_scan`] returns), from the
/// same shared fixture.
pub fn fingertip_scan() -> PathBuf {
    let (cal, _) = calibrated_scan();
    cal.with_file_name("scan-7x5")
}

/// Sends SIGINT (what Ctrl-C sends) to `child`, with kill(1): the workspace forbids unsafe code, tests included.
pub fn interrupt(child: &std::process::Child) {
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
}

/// `metaplate ARGS` (as given) with `stdin` written to its standard input (a user's keys), its output collected.
pub fn metaplate_with_input(args: &[&str], stdin: &[u8]) -> Output {
    use std::io::Write as _;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(args)
        .env("RUST_BACKTRACE", "0")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(stdin).unwrap();
    child.wait_with_output().unwrap()
}

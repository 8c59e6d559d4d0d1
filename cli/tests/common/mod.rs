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

/// A calibration (`calibrate --seed 5`) and a 3 x 2 quick scan through it (`scan --grid 3x2 --protocol quick
/// --seed 5`) on the metamaterial scene's mock lab, written into `dir` (as `cal` and `scan`): the small scan the
/// play and experiment tests render on (points at x -0.08, 0, 0.08 m and y -0.03, 0.03 m). Returns (calibration,
/// scan).
pub fn calibration_and_scan_3x2(dir: &Path) -> (PathBuf, PathBuf) {
    let (cal, scan) = (dir.join("cal"), dir.join("scan"));
    let out = metaplate(&["calibrate", "--scene", "metamaterial", "--seed", "5", "--out", cal.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = metaplate(&[
        "scan",
        "--scene",
        "metamaterial",
        "--protocol",
        "quick",
        "--grid",
        "3x2",
        "--seed",
        "5",
        "--calibration",
        cal.to_str().unwrap(),
        "--out",
        scan.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    (cal, scan)
}

/// A calibration of the metamaterial mock lab (`calibrate --seed 5`) and a scan through it (`scan --grid 3x2
/// --protocol quick --seed 5`): (calibration, scan). Made once per build of the binary and shared by every test
/// process that needs it (play, experiments): the first takes a lock file and builds them in a scratch directory
/// renamed into place when complete; the others wait for it. Keyed by the binary's modification time, so a rebuilt
/// binary makes its own.
pub fn calibrated_scan() -> (PathBuf, PathBuf) {
    let binary = std::fs::metadata(env!("CARGO_BIN_EXE_metaplate")).unwrap();
    let stamp = binary.modified().unwrap().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos();
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fixtures");
    std::fs::create_dir_all(&root).unwrap();
    let done = root.join(format!("cal-scan-3x2-seed5-{stamp:x}"));
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

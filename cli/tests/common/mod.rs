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

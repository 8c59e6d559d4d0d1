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

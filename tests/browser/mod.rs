//! Headless Chromium for the tests of pages (`report.rs`, `monitor.rs`): Debian's `chromium`, installed by
//! `scripts/install-deps.sh`, or another binary through `METAPLATE_CHROMIUM`. Without it a test fails, saying so:
//! a page nobody rendered is not tested.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The Chromium binary; fails the test when there is none.
pub fn chromium() -> PathBuf {
    let path = std::env::var_os("METAPLATE_CHROMIUM").map_or_else(|| PathBuf::from("chromium"), PathBuf::from);
    let found = Command::new(&path).arg("--version").output().is_ok_and(|o| o.status.success());
    assert!(
        found,
        "headless Chromium is needed to render the page: `bash scripts/install-deps.sh` installs Debian's chromium \
         (or point METAPLATE_CHROMIUM at one)"
    );
    path
}

/// Chromium's headless options, with a fresh profile in `profile`: as root (CI) it needs --no-sandbox; the rest
/// keeps it off this machine's closed network.
pub fn headless(profile: &Path) -> Command {
    let mut command = Command::new(chromium());
    command
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--hide-scrollbars"])
        .args(["--disable-background-networking", "--disable-component-update", "--disable-sync"])
        .arg(format!("--user-data-dir={}", profile.display()));
    command
}

/// A screenshot of `url` (a `file://` or `http://` address), `width` x `height` px, written to `png` and decoded
/// as RGB(A) pixels.
pub fn screenshot(url: &str, png: &Path, width: u32, height: u32) -> (png::OutputInfo, Vec<u8>) {
    let profile = tempfile::tempdir().unwrap();
    let out = headless(profile.path())
        .arg(format!("--window-size={width},{height}"))
        .arg(format!("--screenshot={}", png.display()))
        .arg(url)
        .output()
        .unwrap();
    assert!(out.status.success() && png.exists(), "chromium failed: {}", String::from_utf8_lossy(&out.stderr));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    pixels.truncate(info.buffer_size());
    (info, pixels)
}

/// Every RGB colour in a decoded screenshot.
pub fn colours(info: &png::OutputInfo, pixels: &[u8]) -> HashSet<[u8; 3]> {
    pixels.chunks_exact(info.color_type.samples()).map(|p| [p[0], p[1], p[2]]).collect()
}

//! `metaplate report` as a reader gets it: the HTML file is self-contained (nothing fetched, no script), holds the
//! measurement's summary, provenance and the error against the truth, and renders in headless Chromium with its
//! figures and maps visible.
//!
//! Needs headless Chromium (`browser/mod.rs`: Debian's `chromium`, installed by `scripts/install-deps.sh`, or another
//! binary through `METAPLATE_CHROMIUM`). Without it the test fails, saying so: a report nobody rendered is not tested.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::browser;
use crate::common::metaplate_bare as metaplate;

use std::path::{Path, PathBuf};

use browser::{colours, screenshot};

/// The scan of `recipes.rs` (3 x 2 points of the metamaterial plate, the quick protocol, the scene's own seed), so that
/// both files share one Green's-function cache entry.
const SCAN: &[&str] = &["--scene", "metamaterial", "--protocol", "quick", "--grid", "3x2"];

fn cache_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn a_scan_report_is_self_contained_and_renders_with_its_figures() {
    let tmp = tempfile::tempdir().unwrap();
    let (scan, html) = (tmp.path().join("scan"), tmp.path().join("report.html"));
    let cache = cache_dir();
    let (scan_s, html_s, cache_s) = (scan.to_str().unwrap(), html.to_str().unwrap(), cache.to_str().unwrap());
    let mut args = vec!["scan", "--out", scan_s, "--uncalibrated", "--cache-dir", cache_s];
    args.extend(SCAN);
    let out = metaplate(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));

    let out = metaplate(&["report", scan_s, "--out", html_s, "--cache-dir", cache_s]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("report.html"), "the path is printed");
    let page = std::fs::read_to_string(&html).unwrap();

    // Self-contained: no script, no stylesheet link, nothing fetched; every image inline.
    assert!(page.starts_with("<!doctype html>"));
    for banned in ["<script", "<link", "@import", "url(", "src=\"http", "href=\"http"] {
        assert!(!page.contains(banned), "the page holds `{banned}`");
    }
    let images = page.matches("<img ").count();
    assert!(images >= 3, "{images} figures embedded");
    assert_eq!(page.matches("src=\"data:image/png;base64,").count(), images, "every image is a data URI");

    // The measurement: its points by status (all 6 of 6), the truth, the provenance as the manifest says it.
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scan.join("manifest.json")).unwrap()).unwrap();
    assert!(page.contains(manifest["config_hash"].as_str().unwrap()), "configuration hash");
    assert!(page.contains("6 of 6 planned") && page.contains("measured 6<"), "points and the status map");
    assert!(page.contains("none (uncompensated drives)"), "the calibration, none");
    let truth = page.split("Green&#39;s functions against the truth</th><td>").nth(1).unwrap();
    assert!(truth.starts_with("median -"), "errors against the truth in dB: {}", &truth[..80.min(truth.len())]);
    assert!(page.contains("Paper against suite") && page.contains("Plate: metamaterial"));

    // One dataset per plate: the same scene twice is refused, and the report already written is left alone.
    let out = metaplate(&["report", scan_s, scan_s, "--out", html_s, "--no-truth"]);
    assert!(!out.status.success() && text(&out.stderr).contains("two datasets of the scene"), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(&html).unwrap(), page);

    // Rendered as a person sees it. A copy whose images are broken is the control: the real page must show the
    // figures' and maps' colours, which text, rules and broken-image icons do not have.
    let broken = tmp.path().join("broken.html");
    let mut control = String::new();
    for (i, part) in page.split("data:image/png;base64,").enumerate() {
        if i > 0 {
            control.push_str("data:image/png;base64,AAAA");
            control.push_str(&part[part.find('"').unwrap()..]);
        } else {
            control.push_str(part);
        }
    }
    std::fs::write(&broken, control).unwrap();
    let (width, height) = (1200, 6000);
    let (info, pixels) =
        screenshot(&format!("file://{}", html.display()), &tmp.path().join("report.png"), width, height);
    assert_eq!((info.width, info.height), (width, height));
    let (info_c, pixels_c) =
        screenshot(&format!("file://{}", broken.display()), &tmp.path().join("broken.png"), width, height);
    let (seen, seen_control) = (colours(&info, &pixels), colours(&info_c, &pixels_c));
    assert!(
        seen.len() > 3 * seen_control.len() && seen.len() > 1000,
        "{} colours rendered, {} with the images broken",
        seen.len(),
        seen_control.len()
    );
    // The status map's "measured" green is drawn by the inline SVG, in both.
    assert!(seen.contains(&[0x00, 0x9e, 0x73]) && seen_control.contains(&[0x00, 0x9e, 0x73]), "status map");
}

#[test]
fn report_refuses_what_is_not_a_dataset_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let html = tmp.path().join("report.html");
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = metaplate(&["report", empty.to_str().unwrap(), "--out", html.to_str().unwrap(), "--no-truth"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("opening dataset"), "{}", text(&out.stderr));
    assert!(!html.exists(), "no partial report");

    let out = metaplate(&["report", "--out", html.to_str().unwrap()]);
    assert!(!out.status.success(), "a dataset is required");
    assert!(!html.exists(), "no partial report");
}

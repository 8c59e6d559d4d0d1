//! `metaplate demo` end to end on a small scan grid (the hidden `--grid`): calibration and scan on the mock lab for
//! both plates, the analyses, the figures, the 5-pixel pattern, the summary and the report.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use std::path::Path;
use std::process::Command;

#[test]
fn the_demo_calibrates_scans_analyses_and_renders_both_plates() {
    let out = crate::common::scratch("demo-cli", "out");
    // Green's functions cached under the target directory, so reruns skip the plate model; the scene's own seed
    // (20240601), as the other tests' scans of the metamaterial plate and the ground truth, so the seed's rod heights
    // are one cache entry for all of them.
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    let run = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["demo", "--out", out.to_str().unwrap(), "--grid", "7x4", "--seed", "20240601"])
        .args(["--cache-dir", cache.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let stdout = String::from_utf8(run.stdout).unwrap();
    for row in ["wavelength at 75 Hz", "median virtual-pixel area", "POD components", "mean condition number"] {
        assert!(stdout.contains(row), "table row `{row}` missing:\n{stdout}");
    }
    // The report: both plates, the table, each scan's error against the truth through its calibration (rendering
    // is tested in report.rs).
    assert!(stdout.contains(&out.join("report.html").display().to_string()), "the report's path is printed");
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    for part in ["Paper against suite", "Both plates", "Plate: metamaterial", "Plate: homogeneous"] {
        assert!(page.contains(part), "report: `{part}` missing");
    }
    assert_eq!(page.matches("functions against the truth</th><td>median -").count(), 2, "both plates' errors");
    // `metaplate report` on a calibrated scan without its calibration says why it cannot compare with the truth.
    let html = out.join("metamaterial.html");
    let scan = out.join("metamaterial").join("scan");
    let run = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["report", scan.to_str().unwrap(), "--out", html.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("pass its --calibration DIR to compare with the truth"), "the reason is given");

    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for plate in ["metamaterial", "homogeneous"] {
        let p = &summary["plates"][plate];
        for key in ["dispersion", "calibration", "scan", "analysis", "pattern"] {
            assert!(!p[key].is_null(), "{plate}: `{key}` missing");
        }
        assert_eq!(p["calibration"]["actuators"].as_array().unwrap().len(), 8, "{plate}: 8 actuators calibrated");
        let scan = &p["scan"];
        // Every planned point committed: the 7 x 4 subset less masked points, at least 20 of 28.
        let points = scan["points"].as_u64().unwrap();
        assert!(points >= 20 && points == scan["total"].as_u64().unwrap(), "{plate}: {scan}");
        let rows: u64 = scan["statuses"].as_object().unwrap().values().map(|v| v.as_u64().unwrap()).sum();
        assert_eq!(rows, points * 8, "{plate}: one status per (point, actuator)");
        assert!(scan["simulated_hours"].as_f64().unwrap() > 0.0);
        let e = &scan["greens_error_db"];
        assert!(e["median"].as_f64().unwrap() <= e["p95"].as_f64().unwrap(), "{plate}: {e}");
        for key in ["wavelength", "median_pixel_area_cm2", "pod_components_99", "effective_rank", "condition_number"] {
            assert!(p["analysis"].get(key).is_some(), "{plate}: analysis key `{key}` missing");
        }
        let pattern = &p["pattern"];
        assert!(pattern["peak_drive"].as_f64().unwrap() > 0.0);
        let pixels = pattern["pixels"].as_array().unwrap();
        assert_eq!(pixels.len(), 5);
        let targets: std::collections::BTreeSet<&str> = pixels.iter().map(|x| x["target"].as_str().unwrap()).collect();
        assert_eq!(targets.len(), 5, "five distinct targets");

        let wav = out.join(plate).join("pattern.wav");
        let mut reader = hound::WavReader::open(&wav).unwrap();
        assert_eq!(reader.spec().channels, 8);
        assert_eq!(reader.spec().sample_format, hound::SampleFormat::Float);
        let peak = reader.samples::<f32>().map(Result::unwrap).fold(0.0_f32, |m, v| m.max(v.abs()));
        // Peak-normalised to 1: f32 rounding of the scaled peak is at most one ulp.
        assert!(peak <= 1.0 && peak > 1.0 - 1e-6, "{plate}: peak {peak}");

        for figure in ["wavelength", "focus_snapshots", "pod_energy", "driven_response"] {
            for ext in ["png", "svg"] {
                let f = out.join(plate).join("figures").join(format!("{figure}.{ext}"));
                assert!(f.metadata().map(|m| m.len() > 0).unwrap_or(false), "{} missing", f.display());
            }
        }
        // The 7 x 4 scan fills 2 % of its lattice: every k-space estimate is hollow, and the title says why.
        let svg = std::fs::read_to_string(out.join(plate).join("figures").join("wavelength.svg")).unwrap();
        assert!(svg.contains("hollow: lattice 2 % filled, under 50 %"), "{plate}: wavelength title");
    }
    // Both plates on shared axes.
    assert_eq!(summary["comparison_figures"].as_array().map(Vec::len), Some(4), "{}", summary["comparison_figures"]);
    for figure in ["wavelength", "condition_numbers"] {
        let svg = std::fs::read_to_string(out.join("figures").join(format!("{figure}.svg"))).unwrap();
        assert!(svg.contains("metamaterial") && svg.contains("homogeneous") && svg.contains("paper"), "{figure}");
    }
    std::fs::remove_dir_all(&out).unwrap();
}

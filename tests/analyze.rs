//! `metaplate analyze` on a small ground-truth dataset: the JSON object has the keys with sane values, and
//! the figures are written.

#![allow(clippy::unwrap_used)] // helpers outside #[test] functions unwrap too: a failure is a failed test

use crate::common::{self, metaplate_bare as metaplate};
use std::path::Path;

use serde_json::Value;

#[test]
fn analyze_prints_the_paper_quantities_and_writes_figures() {
    let dir = common::scratch("analyze-cli", "meta13x7");
    let data = dir.join("data");
    // A 13 x 7 subset (83 measured points) of the metamaterial plate: enough for every analysis but the 3.5 cm
    // domain, which holds fewer points than actuators on so sparse a grid.
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&cache).unwrap();
    let sim = metaplate(&[
        "simulate",
        "greens",
        "--scene",
        "metamaterial",
        "--grid",
        "13x7",
        // The mock lab's band (40 to 800 Hz): the dataset is cut from the lab's cache entry for this plate, which
        // the scan tests compute anyway, instead of an entry of its own.
        "--band-lo-hz",
        "40",
        "--band-hi-hz",
        "800",
        "--out",
        data.to_str().unwrap(),
        "--cache-dir",
        cache.to_str().unwrap(),
    ]);
    assert!(sim.status.success(), "{}", String::from_utf8_lossy(&sim.stderr));
    let figs = dir.join("figures");
    let out = metaplate(&["analyze", "--data", data.to_str().unwrap(), "--json", "--figures", figs.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();

    // Wavelength: 75 to 600 Hz every 25 Hz, each median inside its quartiles, between two grid steps (1 cm) and
    // the plate's length (25 cm), and the 400 Hz one shorter than the 75 Hz one (the plate disperses; from 552 Hz,
    // above the cell's slow branch, the metamaterial carries no slow wave to compare).
    let wl = v["wavelength"].as_array().unwrap();
    assert_eq!(wl.len(), 22);
    for w in wl {
        let (m, lo, hi) =
            (w["median_m"].as_f64().unwrap(), w["iqr_m"][0].as_f64().unwrap(), w["iqr_m"][1].as_f64().unwrap());
        assert!(lo <= m && m <= hi && (0.01..0.25).contains(&m), "{w}");
    }
    assert_eq!(wl[13]["freq_hz"].as_f64(), Some(400.0));
    assert!(wl[13]["median_m"].as_f64().unwrap() < wl[0]["median_m"].as_f64().unwrap());
    // The lattice the points lie on and what it resolves: every estimate says whether it lies inside.
    let spacing_m = v["lattice"]["spacing_m"].as_f64().unwrap();
    let range = &v["wavelength_resolvable"];
    assert!((range["shortest_m"].as_f64().unwrap() - 2.0 * spacing_m).abs() < 1e-12, "{range}");
    assert!((range["nyquist_k_rad_m"].as_f64().unwrap() * spacing_m - std::f64::consts::PI).abs() < 1e-9);
    assert!(wl.iter().all(|w| w["in_range"].is_boolean()));
    // 13 x 7 spread over 49 x 25 is no regular subset (steps of 3 and 4 points): its lattice is the full grid's,
    // mostly holes, so no estimate may claim to be in range.
    if v["lattice"]["fill"].as_f64().unwrap() < 0.5 {
        assert!(wl.iter().all(|w| w["in_range"] == false), "{wl:?}");
    }
    // The analytic A0 of the scene's plate beside each estimate (a built-in scene).
    assert!(wl.iter().all(|w| w["a0_wavelength_m"].as_f64().is_some_and(|a| a > 0.05)));
    assert!(v["points_per_domain"]["9.5"].as_u64().unwrap() >= 8);

    // POD: at least one component, and no more than the points or twice the band's bins.
    let pod = v["pod_components_99"].as_u64().unwrap();
    assert!((1..=83).contains(&pod), "{pod}");
    // Authority: 9.5 and 6.5 cm computed, rank within 1..=8 and kappa >= 1; 3.5 cm null with its reason.
    for key in ["9.5", "6.5"] {
        let r = v["effective_rank"][key].as_f64().unwrap();
        let k = v["condition_number"][key].as_f64().unwrap();
        assert!((1.0..=8.0).contains(&r) && k >= 1.0, "{key}: rank {r}, kappa {k}");
    }
    assert!(v["effective_rank"]["3.5"].is_null() && v["errors"]["authority 3.5 cm"].is_string());
    // Refresh: between one spacing step (0.1 ms) and the search's 30 ms.
    let refresh = v["refresh_ms"].as_f64().unwrap();
    assert!((0.1..=30.0).contains(&refresh), "{refresh}");
    // Pixel area: the key is present (null here: no point of so sparse a grid has measured neighbours all round).
    assert!(v.get("median_pixel_area_cm2").is_some());
    // Driven response: one entry per bin of 75 to 400 Hz, all positive.
    let resp = v["driven_response"].as_array().unwrap();
    assert!(resp.len() > 100 && resp.iter().all(|r| r["mean_abs"].as_f64().unwrap() > 0.0));

    for name in ["wavelength", "focus_snapshots", "pod_energy", "singular_value_energy", "condition_numbers"] {
        // Every figure carries its lattice in its title.
        let svg = std::fs::read_to_string(figs.join(format!("{name}.svg"))).unwrap();
        assert!(name == "pod_energy" || name == "singular_value_energy" || svg.contains("lattice at"), "{name}");
        // The 13 x 7 subset fills 6 to 7 % of the 0.5 cm lattice: every k-space estimate is hollow, and the title
        // says why (its percentage rounded down, so that 49.7 % never reads as 50).
        assert!(name != "wavelength" || svg.contains("hollow: lattice 6 % filled, under 50 %"), "{name}");
        for ext in ["png", "svg"] {
            let path = figs.join(format!("{name}.{ext}"));
            assert!(std::fs::metadata(&path).map(|m| m.len() > 1000).unwrap_or(false), "{}", path.display());
        }
    }
    // The focusing in time: an animated PNG (its acTL chunk), listed with the figures.
    let animation = std::fs::read(figs.join("focus_animation.png")).unwrap();
    assert!(animation.windows(4).any(|w| w == b"acTL"), "focus_animation.png is not an APNG");
    assert!(v["figures"].as_array().unwrap().iter().any(|p| p.as_str().unwrap().ends_with("focus_animation.png")));
}

#[test]
fn analyze_refuses_a_directory_that_is_not_a_dataset() {
    let dir = common::scratch("analyze-cli", "empty");
    let out = metaplate(&["analyze", "--data", dir.to_str().unwrap(), "--json"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("opening dataset"));
}

//! The `metaplate` binary end to end: each command as a user runs it, its output checked.

// Helpers outside #[test] functions unwrap too: a failure there is a failed test.
#![allow(clippy::unwrap_used)]

use crate::common::{self, metaplate_bare as metaplate};

#[test]
fn scene_list_and_show() {
    let out = metaplate(&["scene", "list"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("metamaterial") && text.contains("homogeneous"), "{text}");
    let out = metaplate(&["scene", "show", "homogeneous"]);
    assert!(out.status.success());
    assert!(String::from_utf8(out.stdout).unwrap().contains("thickness_m"));
}

/// A scene whose lattice names a design, next to its design file: `scene show` writes the design inline and says
/// what the plate model takes from the cell.
#[test]
fn a_scene_naming_a_design_file_shows_the_cells_homogenised_rods() {
    let dir = common::scratch("commands-cli", "designed-scene");
    // The built-in's rods are the design `paper`'s, written inline: swap its design's tables for a file's name.
    let good = String::from_utf8(metaplate(&["scene", "show", "metamaterial"]).stdout).unwrap();
    assert!(good.lines().any(|l| l.starts_with("# rods from design `paper`, homogenised")), "{good}");
    let start = good.find("[resonators.design]").unwrap_or_else(|| panic!("{good}"));
    let rest = &good[start..];
    let end = start
        + rest
            .match_indices("\n[")
            .map(|(i, _)| i + 1)
            .find(|&i| !rest[i..].starts_with("[resonators.design"))
            .unwrap_or(rest.len());
    let scene = format!("{}{}", &good[..start], &good[end..]).replacen(
        "[resonators]\n",
        "[resonators]\ndesign = \"cell.toml\"\n",
        1,
    );
    assert!(scene.contains("design = \"cell.toml\"") && !scene.contains("[resonators.design"), "{scene}");
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let cell = String::from_utf8(metaplate(&["design", "band", "paper", "--json"]).stdout).unwrap();
    assert!(cell.contains("\"homogenised\""), "{cell}");
    std::fs::write(
        dir.join("cell.toml"),
        "name = \"mine\"\nlattice_constant_m = 0.008\n[plate]\nthickness_m = 0.0015\n\
        youngs_modulus_pa = 3.2e9\npoisson_ratio = 0.37\ndensity_kg_m3 = 1180.0\n[resonator]\nkind = \"rod\"\n\
        height_m = 0.0334563\ndiameter_m = 0.003175\nembedded_m = 0.0015\nyoungs_modulus_pa = 97e9\n\
        poisson_ratio = 0.31\ndensity_kg_m3 = 8489.0\n",
    )
    .unwrap();
    let out = metaplate(&["scene", "show", dir.join("scene.toml").to_str().unwrap()]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains("[resonators.design]") && text.contains("name = \"mine\""), "{text}");
    let fit = text
        .lines()
        .find(|l| l.starts_with("# rods from design `mine`, homogenised"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(fit.contains("joint resonance") && fit.contains("frequency error max"), "{fit}");
}

#[test]
fn a_bad_scene_file_is_a_clear_error_not_a_panic() {
    let dir = common::scratch("commands-cli", "bad-scene");
    let path = dir.join("bad.toml");
    let good = String::from_utf8(metaplate(&["scene", "show", "metamaterial"]).stdout).unwrap();
    std::fs::write(&path, good.replacen("thickness_m", "thickness_mm", 1)).unwrap();
    let out = metaplate(&["scene", "show", path.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("thickness_mm") && err.contains("thickness_m"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn sweep_then_deconvolve_recovers_a_unit_impulse() {
    let dir = common::scratch("commands-cli", "sweep");
    let sweep = dir.join("sweep.wav");
    let ir = dir.join("ir.wav");
    assert!(metaplate(&["sweep", "--out", sweep.to_str().unwrap(), "--duration-s", "1"]).status.success());
    let out = metaplate(&[
        "deconvolve",
        "--recording",
        sweep.to_str().unwrap(),
        "--excitation",
        sweep.to_str().unwrap(),
        "--out",
        ir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut reader = hound::WavReader::open(&ir).unwrap();
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    assert_eq!(samples.len(), 12_000);
    // The system is the identity: a band-limited unit impulse at time 0. Its peak is the band's width over the
    // Nyquist band, (625 - 62 + skirts) / 12000, about 0.05; it sits at sample 0 and dominates everything else.
    let peak = samples.iter().enumerate().fold((0, 0.0f32), |m, (i, &v)| if v.abs() > m.1 { (i, v.abs()) } else { m });
    assert_eq!(peak.0, 0);
    assert!((0.04..0.06).contains(&peak.1), "peak {}", peak.1);
}

#[test]
fn deconvolve_without_excitation_or_reference_is_refused() {
    let dir = common::scratch("commands-cli", "no-ref");
    let sweep = dir.join("sweep.wav");
    assert!(metaplate(&["sweep", "--out", sweep.to_str().unwrap(), "--duration-s", "0.5"]).status.success());
    let out = metaplate(&["deconvolve", "--recording", sweep.to_str().unwrap(), "--out", "x.wav"]);
    assert!(!out.status.success());
    assert!(String::from_utf8(out.stderr).unwrap().contains("--excitation"));
}

/// `metaplate simulate greens ARGS --out OUT` (a coarse lattice and a short, high band: seconds), with the cache
/// environment variable set to `env_cache`.
fn simulate_greens(out: &std::path::Path, env_cache: &std::path::Path, extra: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["simulate", "greens", "--scene", "homogeneous", "--grid", "3x2", "--refinement", "1"])
        .args(["--duration-s", "0.1", "--band-lo-hz", "300", "--band-hi-hz", "700", "--out", out.to_str().unwrap()])
        .args(extra)
        .env("METAPLATE_CACHE_DIR", env_cache)
        .env("RUST_BACKTRACE", "0")
        .output()
        .unwrap()
}

/// Whether `dir` holds anything (a cache entry).
fn holds_entries(dir: &std::path::Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|mut entries| entries.next().is_some())
}

#[test]
fn simulate_greens_writes_a_dataset_the_store_reads_and_caches_where_told() {
    let root = common::scratch("commands-cli", "greens");
    let (dir, env_cache) = (root.join("gt"), root.join("env-cache"));
    // Without --cache-dir, the cache is $METAPLATE_CACHE_DIR's.
    let out = simulate_greens(&dir, &env_cache, &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(holds_entries(&env_cache), "the environment's cache directory holds the entry");
    let dataset = metaplate_store::Dataset::open(&dir).unwrap();
    assert_eq!(dataset.actuators().len(), 8);
    assert_eq!(dataset.points().len(), 6);
    assert_eq!(dataset.ir_len(), 2400);
    assert!(dataset.irs().iter().any(|v| *v != 0.0));
    // A second run refuses to overwrite the dataset without --force.
    let again =
        metaplate(&["simulate", "greens", "--scene", "homogeneous", "--grid", "3x2", "--out", dir.to_str().unwrap()]);
    assert!(!again.status.success());
    assert!(String::from_utf8(again.stderr).unwrap().contains("--force"));
    // --cache-dir wins over the environment; --no-cache caches nowhere.
    let (flag_cache, unused) = (root.join("flag-cache"), root.join("unused"));
    let out = simulate_greens(&dir, &unused, &["--force", "--cache-dir", flag_cache.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(holds_entries(&flag_cache) && !holds_entries(&unused));
    let out = simulate_greens(&dir, &unused, &["--force", "--no-cache"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!holds_entries(&unused));
}

#[test]
fn simulate_dispersion_prints_the_documented_json() {
    let out = metaplate(&[
        "simulate",
        "dispersion",
        "--scene",
        "metamaterial",
        "--refinement",
        "1",
        "--from-hz",
        "300",
        "--to-hz",
        "300",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let p = &v["points"][0];
    assert_eq!(p["freq_hz"], 300.0);
    let (lambda, a0) = (p["wavelength_m"].as_f64().unwrap(), p["a0_wavelength_m"].as_f64().unwrap());
    // The metamaterial's waves at 300 Hz are 3.07 cm by the plate equation and 3.10 cm by k-space on the default
    // lattice (plate tests); on the coarse lattice 3.04 cm, 2 % shorter. A0: 12.7 cm, so anything near A0 or the
    // grid's 1 cm fails.
    assert!((0.028..0.033).contains(&lambda), "{lambda}");
    assert!((a0 - 0.1268).abs() < 0.001, "{a0}");
}

#[test]
fn devices_lists_every_backend_and_drafts_a_hardware_file_that_parses() {
    // Whatever this machine has (CI has no USB bus, no sound card, no NI-DAQmx), the listing succeeds.
    let out = metaplate(&["devices", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let listing: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let backends = |section: &str| -> Vec<String> {
        listing[section].as_array().unwrap().iter().map(|b| b["backend"].as_str().unwrap().to_owned()).collect()
    };
    assert_eq!(backends("ldv"), ["polytec", "analog"]);
    assert_eq!(backends("daq"), ["labjack-u6", "nidaqmx", "alsa"]);
    assert_eq!(backends("audio"), ["alsa"]);
    assert_eq!(backends("keypad"), ["hidraw"]);
    for section in ["ldv", "daq", "audio", "keypad"] {
        for b in listing[section].as_array().unwrap() {
            for f in b["found"].as_array().unwrap() {
                assert!(f["key"].as_str().unwrap().starts_with(section), "{f}");
                assert!(!f["value"].as_str().unwrap().is_empty(), "{f}");
            }
        }
    }

    let dir = common::scratch("commands-cli", "devices");
    let draft = dir.join("rig.toml");
    let out = metaplate(&["devices", "--write-hardware", draft.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&draft).unwrap();
    assert!(text.contains("CHOOSE"), "the user's choices are marked:\n{text}");
    metaplate_drivers::HardwareFile::load(&draft).unwrap_or_else(|e| panic!("the draft does not parse: {e}\n{text}"));
    // Never replaced.
    let out = metaplate(&["devices", "--write-hardware", draft.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("exists"));
    assert_eq!(std::fs::read_to_string(&draft).unwrap(), text);
    std::fs::remove_dir_all(&dir).unwrap();
}

//! `metaplate design band`: the paper's cell end to end (table, JSON schema, Parquet, figures) and a design file's
//! mistake reported with file, line and key.

use std::path::PathBuf;
use std::process::{Command, Output};

fn metaplate(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_metaplate")).args(args).env("RUST_BACKTRACE", "0").output().unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("metaplate-design-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn design_band_paper_json_parquet_and_figures() {
    let dir = scratch("band");
    let parquet = dir.join("points.parquet");
    let figures = dir.join("figures");
    let out = metaplate(&[
        "design",
        "band",
        "paper",
        "--wave-vectors",
        "46",
        "--modes",
        "3",
        "--json",
        "--parquet",
        parquet.to_str().unwrap(),
        "--figures",
        figures.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // The schema.
    let branches = json["branches"].as_array().unwrap();
    assert_eq!(branches.len(), 3);
    assert_eq!(branches[0]["mode"], 1);
    let points = branches[0]["points"].as_array().unwrap();
    assert_eq!(points.len(), 46);
    for key in ["path_index", "kx_rad_m", "ky_rad_m", "freq_hz", "plate_energy_share"] {
        assert!(points[3].get(key).is_some_and(|v| v.is_number()), "{key} in {}", points[3]);
    }
    let f_n = json["resonator_mode_hz"].as_f64().unwrap();
    assert!((f_n / 781.0 - 1.0).abs() < 0.05, "f_n {f_n}");
    let slow = &json["slow_branch"];
    assert_eq!(slow["mode"], 1);
    assert!(slow["max_phase_velocity_m_s"].as_f64().unwrap() < 10.0);
    assert!((slow["top_hz"].as_f64().unwrap() / 558.0 - 1.0).abs() < 0.05);
    // 46 wave vectors (every other of the paper's 90) resolve the branch near Gamma for the 75 Hz wavelength.
    let at = slow["wavelength_m_at"].as_array().unwrap();
    assert_eq!(at[0]["freq_hz"], 75.0);
    assert!((at[0]["wavelength_m"].as_f64().unwrap() / 0.10 - 1.0).abs() < 0.10);
    // Parquet: one row per branch point, readable back.
    let file = std::fs::File::open(&parquet).unwrap();
    let reader = parquet::file::reader::SerializedFileReader::new(file).unwrap();
    use parquet::file::reader::FileReader;
    assert_eq!(reader.metadata().file_metadata().num_rows(), 3 * 46);
    for ext in ["png", "svg"] {
        let figure = figures.join(format!("band_structure.{ext}"));
        assert!(std::fs::metadata(&figure).unwrap().len() > 1000, "{}", figure.display());
    }
    // The table names the resonator mode and the slow branch.
    let out = metaplate(&["design", "band", "paper", "--wave-vectors", "7", "--modes", "2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("clamped-cell resonator mode f_n") && text.contains("slow branch m = 1"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn design_file_mistake_names_file_line_and_key() {
    let dir = scratch("file");
    let path = dir.join("cell.toml");
    std::fs::write(
        &path,
        "lattice_constant_m = 0.008\n[plate]\nthickness_mm = 1.5\nyoungs_modulus_pa = 3.2e9\npoisson_ratio = 0.37\n\
         density_kg_m3 = 1180\n[resonator]\nkind = \"none\"\n",
    )
    .unwrap();
    let out = metaplate(&["design", "band", path.to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&format!("{}:3:", path.display())) && stderr.contains("thickness_m"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

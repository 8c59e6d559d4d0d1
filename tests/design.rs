//! `metaplate design band`: the paper's cell end to end (table, JSON schema, Parquet, figures) and a design file's
//! mistake reported with file, line and key.

use crate::common::{self, metaplate_bare as metaplate};
use std::path::PathBuf;
use std::process::Command;

#[test]
fn design_band_paper_json_parquet_and_figures() {
    let dir = common::scratch("design-cli", "band");
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
    let dir = common::scratch("design-cli", "file");
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

/// A coarse search file (bookkeeping, not physics: a coarse mesh, `wave_vectors` wave vectors) of `heights` x 2
/// designs.
fn coarse_search(dir: &std::path::Path, heights: usize, wave_vectors: usize) -> PathBuf {
    let path = dir.join("search.toml");
    std::fs::write(
        &path,
        format!(
            "base = \"paper\"\n[vary]\nrod_height_m = {{ from = 0.02, to = 0.04, count = {heights} }}\n\
             rod_material = [\"brass\", \"aluminium\"]\n[objectives]\nmax_phase_velocity_m_s = 10.0\n\
             over_hz = [75.0, 400.0]\nminimise = [\"added_mass_kg_m2\", \"rod_height_m\"]\n[band]\nwave_vectors = {wave_vectors}\n\
             modes = 1\nper_side = 1\nradial = 1\nrod_elements = 2\n"
        ),
    )
    .unwrap();
    path
}

/// The indices of the designs a `design search --json` run computed, from its events.
fn computed_indices(stdout: &[u8]) -> Vec<u64> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .map(|v| v["result"]["candidate"]["index"].as_u64().unwrap())
        .collect()
}

#[test]
fn four_shards_as_separate_processes_merge_to_one_runs_results() {
    let dir = common::scratch("design-cli", "shards");
    let search = coarse_search(&dir, 4, 7);
    let whole = dir.join("whole");
    let out = metaplate(&["design", "search", search.to_str().unwrap(), "--out", whole.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("of 8 designs feasible; the trade-off front:"), "{text}");
    let shards: Vec<PathBuf> = (0..4).map(|i| dir.join(format!("shard{i}"))).collect();
    let children: Vec<_> = shards
        .iter()
        .enumerate()
        .map(|(i, d)| {
            Command::new(env!("CARGO_BIN_EXE_metaplate"))
                .args(["design", "search", search.to_str().unwrap(), "--out", d.to_str().unwrap()])
                .args(["--shard", &format!("{i}/4"), "--json"])
                .stdout(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for (i, child) in children.into_iter().enumerate() {
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success());
        assert_eq!(computed_indices(&out.stdout), vec![i as u64, i as u64 + 4]);
    }
    let merged = dir.join("merged.parquet");
    let mut args = vec!["design", "merge", search.to_str().unwrap()];
    args.extend(shards.iter().map(|d| d.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    let out = metaplate(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read(&merged).unwrap(), std::fs::read(whole.join("results.parquet")).unwrap());
    // A missing shard is named, and nothing is written.
    let partial = dir.join("partial.parquet");
    let out = metaplate(&[
        "design",
        "merge",
        search.to_str().unwrap(),
        shards[0].to_str().unwrap(),
        "--out",
        partial.to_str().unwrap(),
    ]);
    assert!(!out.status.success() && !partial.exists());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("6 of 8 designs are missing"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Killed with SIGKILL once some designs are written, then run again: the second run computes exactly the designs
/// the first had not written (none lost, none computed twice), and the results equal an uninterrupted run's.
#[test]
fn a_search_killed_with_sigkill_resumes_without_repeating_or_losing_a_design() {
    let dir = common::scratch("design-cli", "kill");
    // Enough wave vectors that a design takes tens of milliseconds: the kill lands mid-run.
    let search = coarse_search(&dir, 8, 60);
    let reference = dir.join("reference");
    let out = metaplate(&["design", "search", search.to_str().unwrap(), "--out", reference.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let run = dir.join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_metaplate"))
        .args(["design", "search", search.to_str().unwrap(), "--out", run.to_str().unwrap(), "--json"])
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let parts = |d: &std::path::Path| -> Vec<u64> {
        let mut v: Vec<u64> = std::fs::read_dir(d.join("parts"))
            .map(|e| {
                e.filter_map(|e| {
                    e.ok()?.file_name().to_str()?.strip_prefix("design-")?.strip_suffix(".parquet")?.parse().ok()
                })
                .collect()
            })
            .unwrap_or_default();
        v.sort_unstable();
        v
    };
    let start = std::time::Instant::now();
    while parts(&run).len() < 3 && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = parts(&run);
    assert!(before.len() >= 3 && before.len() < 16, "{before:?}: kill earlier");
    let out = metaplate(&["design", "search", search.to_str().unwrap(), "--out", run.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut all = before.clone();
    let again = computed_indices(&out.stdout);
    assert!(again.iter().all(|i| !before.contains(i)), "computed twice: {again:?} after {before:?}");
    all.extend(again);
    all.sort_unstable();
    assert_eq!(all, (0..16).collect::<Vec<u64>>());
    assert_eq!(
        std::fs::read(run.join("results.parquet")).unwrap(),
        std::fs::read(reference.join("results.parquet")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

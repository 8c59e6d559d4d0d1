//! `metaplate export` and `metaplate import` on small ground-truth datasets (13 x 7 and 4 x 3 points of the
//! metamaterial plate, 8 actuators): the round trip dataset -> universal file -> dataset in every format (ASCII and binary,
//! single and double precision, both byte orders, time responses and complex FRFs), and `analyze` on the import
//! equal to `analyze` on the original.

#![allow(clippy::unwrap_used)] // helpers outside #[test] functions unwrap too: a failure is a failed test

use crate::common::{self, metaplate_bare as metaplate};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;

use metaplate_store::Dataset;
use metaplate_uff::{FunctionType, UffDecoder, UffEncoder, UffRecord};
use serde_json::Value;

fn ok(args: &[&str]) -> Output {
    let out = metaplate(args);
    assert!(out.status.success(), "metaplate {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The 13 x 7 metamaterial ground truth, simulated once per test process (its Green's functions cached under the
/// target directory, as the other command tests do, so a second process loads them).
fn original() -> &'static Path {
    static DATA: OnceLock<PathBuf> = OnceLock::new();
    DATA.get_or_init(|| ground_truth("original", "13x7"))
}

/// The same plate on a 4 x 3 grid (96 responses): what the round trip through each format needs (every record
/// type, precision and byte order), at an eighth of the original's size, so six formats take seconds, not a minute.
fn few_points() -> &'static Path {
    static DATA: OnceLock<PathBuf> = OnceLock::new();
    DATA.get_or_init(|| ground_truth("few-points", "4x3"))
}

fn ground_truth(name: &str, grid: &str) -> PathBuf {
    let data = common::scratch("uff-cli", name).join("gt");
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&cache).unwrap();
    let (d, c) = (data.to_str().unwrap(), cache.to_str().unwrap());
    // The mock lab's band: cut from the lab's cache entry for this plate (tests/analyze.rs).
    let band = ["--band-lo-hz", "40", "--band-hi-hz", "800"];
    ok(&[&["simulate", "greens", "--scene", "metamaterial", "--grid", grid, "--out", d, "--cache-dir", c][..], &band]
        .concat());
    data
}

/// Asserts that every response of `imported` is the original's within `rel` of the response's peak (and that
/// both hold the same keys, sample rate and length).
fn assert_same_responses(original: &Dataset, imported: &Dataset, rel: f64, what: &str) {
    assert_eq!(imported.len(), original.len(), "{what}");
    assert_eq!(imported.sample_rate_hz(), original.sample_rate_hz(), "{what}");
    assert_eq!(imported.ir_len(), original.ir_len(), "{what}");
    for meta in original.rows() {
        let (p, a) = meta.key();
        let want = original.ir(p, a).unwrap();
        let got = imported.ir(p, a).unwrap_or_else(|| panic!("{what}: point {p} actuator {a} missing"));
        let peak = want.iter().fold(0.0f64, |m, &v| m.max(f64::from(v).abs()));
        let worst = want.iter().zip(got).map(|(&w, &g)| (f64::from(w) - f64::from(g)).abs()).fold(0.0, f64::max);
        assert!(worst <= rel * peak, "{what}: point {p} actuator {a}: error {worst:e} of peak {peak:e}");
        let got_meta = imported.meta(p, a).unwrap();
        assert_eq!((got_meta.x_m, got_meta.y_m, got_meta.status), (meta.x_m, meta.y_m, meta.status), "{what}");
    }
}

#[test]
fn round_trip_in_every_format_reproduces_every_response() {
    let original_path = few_points();
    let original = Dataset::open(original_path).unwrap();
    let dir = common::scratch("uff-cli", "round-trip");
    // (format, precision, byte order, bound on the error relative to a response's peak): ASCII single writes 6
    // significant digits (5e-6 of each value); ASCII double 12 and binary single f32 give the stored f32 back.
    let cases = [
        ("uff58", "single", "little", 5e-6),
        ("uff58", "double", "little", 0.0),
        ("uff58b", "single", "little", 0.0),
        ("uff58b", "single", "big", 0.0),
        ("uff58b", "double", "little", 0.0),
        ("uff58b", "double", "big", 0.0),
    ];
    for (format, precision, byte_order, rel) in cases {
        let what = format!("{format} {precision} {byte_order}");
        let file = dir.join(format!("{format}-{precision}-{byte_order}.uff"));
        let back = dir.join(format!("{format}-{precision}-{byte_order}"));
        let (f, b) = (file.to_str().unwrap(), back.to_str().unwrap());
        let data = original_path.to_str().unwrap();
        let args = ["export", "--data", data, "--format", format, "--precision", precision, "--byte-order", byte_order];
        ok(&[&args[..], &["--out", f, "--frequency"]].concat());
        ok(&["import", "--uff", f, "--out", b]);
        let imported = Dataset::open(&back).unwrap();
        assert_same_responses(&original, &imported, rel, &what);
        assert_eq!(imported.manifest().meta.grid, original.manifest().meta.grid, "{what}");
        assert_eq!(imported.manifest().meta.scene, original.manifest().meta.scene, "{what}");

        // The complex FRFs alone (the time responses removed): turned back into impulse responses, equal within
        // the precision of the spectrum's values relative to its largest.
        let frf_only = dir.join(format!("{format}-{precision}-{byte_order}-frf.uff"));
        keep_only_frfs(&file, &frf_only, format, precision, byte_order);
        let back_frf = dir.join(format!("{format}-{precision}-{byte_order}-frf"));
        let out = ok(&["import", "--uff", frf_only.to_str().unwrap(), "--out", back_frf.to_str().unwrap()]);
        assert!(String::from_utf8_lossy(&out.stderr).contains(&format!("({} from frequency", original.len())));
        let imported = Dataset::open(&back_frf).unwrap();
        let rel_frf = if rel > 0.0 { 2e-5 } else { 2e-6 };
        assert_same_responses(&original, &imported, rel_frf, &format!("{what}, from FRFs"));
        for path in [&file, &frf_only] {
            std::fs::remove_file(path).unwrap();
        }
    }

    // The grid from the nodes alone: the 13 x 7 subset of the 5 mm grid placed on a 5 mm grid again, every
    // response at its position.
    let original_path = self::original();
    let original = Dataset::open(original_path).unwrap();
    let file = dir.join("nodes.uff");
    ok(&["export", "--data", original_path.to_str().unwrap(), "--format", "uff58b", "--out", file.to_str().unwrap()]);
    let back = dir.join("nodes");
    ok(&["import", "--uff", file.to_str().unwrap(), "--out", back.to_str().unwrap(), "--grid-from-nodes"]);
    let imported = Dataset::open(&back).unwrap();
    assert!((imported.manifest().meta.grid.spacing_m - 0.005).abs() < 1e-12);
    assert_eq!(imported.len(), original.len());
    for meta in imported.rows() {
        let twin =
            original.rows().iter().find(|m| m.x_m == meta.x_m && m.y_m == meta.y_m && m.actuator == meta.actuator);
        let twin = twin.unwrap_or_else(|| panic!("no original response at {meta:?}"));
        assert_eq!(imported.ir(meta.point_index, meta.actuator), original.ir(twin.point_index, twin.actuator));
    }
}

/// Rewrites `from` with its units, nodes and frequency responses only, in the same format.
fn keep_only_frfs(from: &Path, to: &Path, format: &str, precision: &str, byte_order: &str) {
    use metaplate_uff::{ByteOrder, Format, Precision};
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(from).unwrap());
    decoder.finish();
    let format = match (format, byte_order) {
        ("uff58", _) => Format::Ascii,
        (_, "big") => Format::Binary { byte_order: ByteOrder::BigEndian },
        _ => Format::Binary { byte_order: ByteOrder::LittleEndian },
    };
    let precision = if precision == "double" { Precision::Double } else { Precision::Single };
    let encoder = UffEncoder::new(format, precision);
    let mut out = Vec::new();
    for record in decoder.records() {
        let record = record.unwrap();
        let keep = match &record {
            UffRecord::Function(f) => f.header.function_type == FunctionType::FrequencyResponse,
            _ => true,
        };
        if keep {
            encoder.encode(&record, &mut out).unwrap();
        }
    }
    std::fs::write(to, out).unwrap();
}

#[test]
fn analyze_on_an_import_equals_analyze_on_the_original() {
    let original_path = original();
    let dir = common::scratch("uff-cli", "analyze");
    let file = dir.join("gt.uff");
    let back = dir.join("imported");
    ok(&["export", "--data", original_path.to_str().unwrap(), "--format", "uff58b", "--out", file.to_str().unwrap()]);
    ok(&["import", "--uff", file.to_str().unwrap(), "--out", back.to_str().unwrap()]);
    let analyze = |data: &Path| -> Value {
        let mut v: Value =
            serde_json::from_slice(&ok(&["analyze", "--data", data.to_str().unwrap(), "--json"]).stdout).unwrap();
        v.as_object_mut().unwrap().remove("dataset");
        v
    };
    let (a, b) = (analyze(original_path), analyze(&back));
    assert_eq!(a["median_pixel_area_cm2"], b["median_pixel_area_cm2"]);
    assert_eq!(a, b);
    // The printed table too, but for the dataset's name.
    let table = |data: &Path| {
        let out = ok(&["analyze", "--data", data.to_str().unwrap()]);
        String::from_utf8(out.stdout).unwrap().lines().skip(1).map(str::to_owned).collect::<Vec<_>>()
    };
    assert_eq!(table(original_path), table(&back));
    // And focus reads it.
    let wav = dir.join("focus.wav");
    ok(&["focus", "--data", back.to_str().unwrap(), "--pixel", "0,0", "--out", wav.to_str().unwrap()]);
}

#[test]
fn a_malformed_file_names_the_record_and_line() {
    let dir = common::scratch("uff-cli", "malformed");
    let file = dir.join("bad.uff");
    // A dataset 58 that ends after its record 6.
    let mut text = String::from("    -1\n    58\n");
    for _ in 0..5 {
        text.push_str("NONE\n");
    }
    text.push_str("    x         0    0         0 NONE               1   3 NONE               1   3\n");
    text.push_str("    -1\n");
    std::fs::write(&file, text).unwrap();
    let out = metaplate(&["import", "--uff", file.to_str().unwrap(), "--out", dir.join("out").to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("record 1 (dataset 58), line 9"), "{stderr}");
}

/// A file of the universal-file corpus (`crates/interchange/tests/corpus/README.md`).
fn corpus(name: &str) -> String {
    format!("{}/../interchange/tests/corpus/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn files_other_writers_wrote_import_with_nodes_and_refusals_name_what_would_be_accepted() {
    let dir = common::scratch("uff-cli", "corpus");
    let nodes = dir.join("nodes.csv");
    std::fs::write(&nodes, "node,x_m,y_m\n0,0.0,0.0\n").unwrap();
    let (nodes, out) = (nodes.to_str().unwrap(), dir.join("catman"));
    // catman's acceleration time history (no dataset 2411): one point, integrated to velocity, the mapping printed.
    let catman = corpus("time-history-not-all-columns-filled.uff");
    let done = ok(&["import", "--uff", &catman, "--nodes", nodes, "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert!(stderr.contains("imported 1 responses (0 from frequency responses)"), "{stderr}");
    assert!(stderr.contains("1 x 1 grid at 1 mm (from one point), 20000 Hz, 13 samples, in m/s"), "{stderr}");
    assert!(
        stderr.contains("ordinate: acceleration (m/s²) from data type 1 (general), units label \"m/s²\""),
        "{stderr}"
    );
    assert!(stderr.contains("actuator 0: reference node 0 direction 0"), "{stderr}");
    // `analyze` on one point of 13 samples says why it cannot.
    let analysis = metaplate(&["analyze", "--data", out.to_str().unwrap()]);
    assert!(!analysis.status.success());
    assert!(!String::from_utf8_lossy(&analysis.stderr).trim().is_empty());

    // Sound pressure is refused by name, with the flag that takes it.
    let pressure = corpus("Sample_UFF58b_bin.uff");
    let refused =
        metaplate(&["import", "--uff", &pressure, "--nodes", nodes, "--out", dir.join("p").to_str().unwrap()]);
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("record 1 (dataset 58 from line 1), line 11, record 9 (ordinate data characteristics)"),
        "{stderr}"
    );
    assert!(
        stderr.contains("sound pressure (data type 21, \"Pa\")") && stderr.contains("--accept-unknown-quantity"),
        "{stderr}"
    );
    // A PSD alone: no response, and the PSD named as skipped.
    let psd = corpus("sample_dataset58_psd.uff");
    let refused = metaplate(&["import", "--uff", &psd, "--out", dir.join("psd").to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(stderr.contains("skipped: 1 x dataset 58, function type 9 (power spectral density)"), "{stderr}");
}

/// The export benchmark (README's benchmark table): a full-size synthetic dataset, 1225 points (the metamaterial
/// scene's 49 x 25 grid) x 8 actuators x 12000 f32 samples (470 MB), written through the store, then exported by the
/// binary in each format; prints MB/s and records/s as `metaplate export` reports them.
/// `cargo test -p metaplate-cli --test uff -- --ignored export_benchmark --nocapture` (DIR: `$METAPLATE_BENCH_DIR`,
/// default the target's temporary directory; about 6 GB of disk for the ASCII double file).
#[test]
#[ignore = "a benchmark: writes 470 MB and exports it several times"]
fn export_benchmark() {
    use metaplate_core::scene::Scene;
    use metaplate_store::{DatasetMeta, DatasetWriter, IfExists, IrMeta, IrRecord, Status};

    let base = std::env::var_os("METAPLATE_BENCH_DIR")
        .map_or_else(|| Path::new(env!("CARGO_TARGET_TMPDIR")).join("uff-bench"), PathBuf::from);
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    let data = base.join("full");
    let scene = Scene::builtin("metamaterial").unwrap();
    let grid = scene.grid;
    let config = serde_json::json!({"synthetic": true}).as_object().cloned().unwrap();
    let meta = DatasetMeta::new("simulate-greens", config, scene.id(), "bench", 1, grid);
    let mut writer = DatasetWriter::create(&data, meta, IfExists::Refuse).unwrap();
    let (ir_len, actuators) = (12_000usize, 8u16);
    // Decaying, noise-like responses (incompressible, as measurements are), deterministic.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    for first in (0..grid.len()).step_by(25) {
        let mut batch = Vec::new();
        for p in first..(first + 25).min(grid.len()) {
            let (ix, iy) = grid.indices(p);
            for actuator in 0..actuators {
                let mut meta = IrMeta::at_grid(&grid, ix as u32, iy as u32, actuator, 24_000.0).unwrap();
                meta.status = Some(Status::GroundTruth);
                let ir = (0..ir_len).map(|i| noise() * (-(i as f32) / 3000.0).exp() * 1e-3).collect();
                batch.push(IrRecord { meta, ir });
            }
        }
        writer.commit_batch(&batch).unwrap();
    }
    writer.finish().unwrap();
    for (format, precision, frequency) in [
        ("uff58b", "single", false),
        ("uff58b", "double", false),
        ("uff58b", "single", true),
        ("uff58", "single", false),
    ] {
        let out = base.join("full.uff");
        let mut args = vec!["export", "--data", data.to_str().unwrap(), "--format", format, "--precision", precision];
        args.extend(["--out", out.to_str().unwrap()]);
        if frequency {
            args.push("--frequency");
        }
        let report = ok(&args);
        let line = String::from_utf8_lossy(&report.stderr).lines().last().unwrap_or_default().to_owned();
        println!("{format} {precision}{}: {line}", if frequency { " --frequency" } else { "" });
        std::fs::remove_file(&out).unwrap();
    }
    std::fs::remove_dir_all(&base).unwrap();
}

//! The corpus of universal files other software wrote (`tests/corpus/README.md`): each is read with the values
//! pyuff reads (`tests/corpus/pyuff_expected.json`), and imported, or refused with the reason a user needs.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::path::{Path, PathBuf};

use metaplate_dsp::fft;
use metaplate_interchange::{ImportOptions, ImportSummary};
use metaplate_store::{Dataset, IR_UNIT_M_S_PER_N};
use metaplate_uff::{Complex64, Function58, Ordinate, UffDecoder, UffRecord};
use serde_json::Value;

use crate::common;

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus").join(name)
}

fn expected(name: &str) -> Value {
    let text = std::fs::read_to_string(corpus("pyuff_expected.json")).unwrap();
    let all: Value = serde_json::from_str(&text).unwrap();
    all[name].clone()
}

/// The functions metaplate-uff decodes from a corpus file, and its decoding errors as text.
fn functions(name: &str) -> (Vec<Function58>, Vec<String>) {
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(corpus(name)).unwrap());
    decoder.finish();
    let (mut functions, mut errors) = (Vec::new(), Vec::new());
    for record in decoder.records() {
        match record {
            Ok(UffRecord::Function(f)) => functions.push(*f),
            Ok(_) => {}
            Err(e) => errors.push(e.to_string()),
        }
    }
    (functions, errors)
}

/// pyuff's values as real numbers (a complex value as its real and imaginary parts).
fn flat(list: &Value) -> Vec<f64> {
    list.as_array()
        .unwrap()
        .iter()
        .flat_map(|v| match v {
            Value::Array(pair) => pair.iter().map(|x| x.as_f64().unwrap()).collect::<Vec<_>>(),
            v => vec![v.as_f64().unwrap()],
        })
        .collect()
}

fn reals(ordinate: &Ordinate) -> Vec<f64> {
    match ordinate {
        Ordinate::Real(v) => v.clone(),
        Ordinate::Complex(v) => v.iter().flat_map(|c| [c.re, c.im]).collect(),
    }
}

/// Asserts that metaplate-uff reads `name`'s functions as pyuff does: the same nodes, directions, data types and
/// values. Both parse the same decimal text (or the same IEEE bytes) with correct rounding, so the values are equal.
fn assert_read_as_pyuff_reads(name: &str) -> Vec<Function58> {
    let (functions, errors) = functions(name);
    assert!(errors.is_empty(), "{name}: {errors:?}");
    let want = expected(name);
    let want = want["functions"].as_array().unwrap();
    assert_eq!(functions.len(), want.len(), "{name}");
    for (f, w) in functions.iter().zip(want) {
        let h = &f.header;
        assert_eq!(h.function_type.code(), w["func_type"].as_u64().unwrap() as u32, "{name}");
        assert_eq!(
            (h.response.node, i64::from(h.response.direction)),
            (w["rsp_node"].as_i64().unwrap(), w["rsp_dir"].as_i64().unwrap())
        );
        assert_eq!(
            (h.reference.node, i64::from(h.reference.direction)),
            (w["ref_node"].as_i64().unwrap(), w["ref_dir"].as_i64().unwrap())
        );
        assert_eq!(h.ordinate.data_type, w["ordinate_spec_data_type"].as_u64().unwrap() as u32, "{name}");
        assert_eq!(f.ordinate.len(), w["num_pts"].as_u64().unwrap() as usize, "{name}");
        assert_eq!(h.abscissa_step, w["abscissa_inc"].as_f64().unwrap(), "{name}");
        let ours = reals(&f.ordinate);
        let values = &w["values"];
        if let Some(all) = values.get("all") {
            assert_eq!(ours, flat(all), "{name}");
        } else {
            let (first, last) = (flat(&values["first"]), flat(&values["last"]));
            assert_eq!(&ours[..first.len()], &first[..], "{name}");
            assert_eq!(&ours[ours.len() - last.len()..], &last[..], "{name}");
            let abs_sum: f64 = match &f.ordinate {
                Ordinate::Real(v) => v.iter().map(|x| x.abs()).sum(),
                Ordinate::Complex(v) => v.iter().map(|c| c.norm()).sum(),
            };
            let theirs = values["abs_sum"].as_f64().unwrap();
            // Summed in another order: equal within the rounding of the sum.
            assert!((abs_sum - theirs).abs() <= 1e-12 * theirs, "{name}: {abs_sum} vs {theirs}");
        }
    }
    functions
}

/// A one-node CSV placing `node` at the origin.
fn nodes_csv(dir: &Path, node: i64) -> PathBuf {
    let path = dir.join("nodes.csv");
    std::fs::write(&path, format!("node,x_m,y_m,z_m\n{node},0.0,0.0,0.0\n")).unwrap();
    path
}

fn import(names: &[&str], out: &Path, options: ImportOptions) -> Result<ImportSummary, String> {
    let files: Vec<PathBuf> = names.iter().map(|n| corpus(n)).collect();
    common::import(&files, out, options).map_err(|e| common::message(&e))
}

/// Asserts that the imported response's spectrum, times j2πf, is the source's spectrum times `to_si` at every bin
/// but 0 Hz and Nyquist: the response is the source's acceleration integrated. The import stores `f32`, so
/// agreement is within 10⁻⁵ of the spectrum's peak (f32 keeps 6 × 10⁻⁸ per sample; the FFT adds n such errors).
fn assert_integrated(source: &[f64], to_si: f64, imported: &[f32], sample_rate_hz: f64) {
    let n = source.len();
    assert_eq!(imported.len(), n);
    let a = fft::forward(source, n).unwrap();
    let v = fft::forward(&imported.iter().map(|&x| f64::from(x)).collect::<Vec<_>>(), n).unwrap();
    let peak = a.iter().map(|c| c.norm() * to_si).fold(0.0, f64::max);
    for k in 1..n.div_ceil(2) {
        let jw = Complex64::new(0.0, 2.0 * std::f64::consts::PI * fft::bin_freq_hz(k, n, sample_rate_hz));
        let back = v[k] * jw;
        assert!((back - a[k] * to_si).norm() <= 1e-5 * peak, "bin {k}: {back} vs {}", a[k] * to_si);
    }
}

#[test]
fn each_file_is_read_as_pyuff_reads_it_or_refused_naming_record_and_line() {
    for name in [
        "non_ascii_header.uff",
        "time-history-not-all-columns-filled.uff",
        "binary8byte.uff",
        "Sample_UFF58b_bin.uff",
        "TestLab_161_164_18_15_82.uff",
        "heat_engine_housing.uff",
    ] {
        assert_read_as_pyuff_reads(name);
    }
    // pyuff reads the 42 values there are; the file announces 2 508 876.
    let (read, errors) = functions("dataset_milestone_in_header.uff");
    assert!(read.is_empty());
    assert_eq!(
        errors,
        ["record 1 (dataset 58), line 21: the dataset ends after 42 of the 2508876 values record 7 announces"]
    );
    // The PSD's uneven abscissa is not read (the import steps over it unread, below).
    let (_, errors) = functions("sample_dataset58_psd.uff");
    assert_eq!(errors.len(), 1);
    assert!(errors[0].starts_with("record 1 (dataset 58), line 9: unsupported: uneven abscissa spacing"), "{errors:?}");
}

#[test]
fn motion_responses_import_with_their_nodes_converted_to_velocity() {
    let tmp = tempfile::tempdir().unwrap();
    // catman: acceleration in m/s² (UTF-8), data type 1, node 0: one point.
    let name = "time-history-not-all-columns-filled.uff";
    let source = assert_read_as_pyuff_reads(name).remove(0);
    let options = ImportOptions { nodes: Some(nodes_csv(tmp.path(), 0)), ..ImportOptions::default() };
    let out = tmp.path().join("catman");
    let summary = import(&[name], &out, options).unwrap();
    assert_eq!((summary.rows, summary.grid_from.as_str(), summary.grid.len()), (1, "one point", 1));
    assert_eq!(summary.ir_unit, "m/s", "an operational record: no denominator");
    assert!(
        summary.conversion.starts_with("acceleration (m/s²) from data type 1 (general), units label \"m/s²\""),
        "{}",
        summary.conversion
    );
    assert_eq!(summary.sample_rate_hz, 20_000.0);
    let data = Dataset::open(&out).unwrap();
    assert_integrated(&reals(&source.ordinate), 1.0, data.ir(0, 0).unwrap(), 20_000.0);
    let manifest = metaplate_store::Manifest::read(&out).unwrap();
    assert_eq!(manifest.meta.config["ordinate"], summary.conversion.as_str());

    // A DT9837's 58b in g: × 9.80665 and integrated.
    let name = "binary8byte.uff";
    let source = assert_read_as_pyuff_reads(name).remove(0);
    let options = ImportOptions { nodes: Some(nodes_csv(tmp.path(), 1)), ..ImportOptions::default() };
    let out = tmp.path().join("dt9837");
    let summary = import(&[name], &out, options).unwrap();
    assert!(summary.conversion.contains("standard gravity"), "{}", summary.conversion);
    let data = Dataset::open(&out).unwrap();
    assert_integrated(&reals(&source.ordinate), 9.806_65, data.ir(0, 0).unwrap(), 100.0);

    // An accelerance FRF per newton (Latin-1 `²`): divided by jω, per newton.
    let name = "non_ascii_header.uff";
    let source = assert_read_as_pyuff_reads(name).remove(0);
    let options = ImportOptions { nodes: Some(nodes_csv(tmp.path(), 0)), ..ImportOptions::default() };
    let out = tmp.path().join("accelerance");
    let summary = import(&[name], &out, options).unwrap();
    assert_eq!((summary.ir_unit.as_str(), summary.from_frf), (IR_UNIT_M_S_PER_N, 1));
    let data = Dataset::open(&out).unwrap();
    let ir: Vec<f64> = data.ir(0, 0).unwrap().iter().map(|&x| f64::from(x)).collect();
    // Six bins from 0 Hz: n = 10; the impulse response's spectrum is the FRF over jω at bins 1 to 4.
    let spectrum = fft::forward(&ir, ir.len()).unwrap();
    let Ordinate::Complex(frf) = &source.ordinate else { panic!("complex") };
    let df = source.header.abscissa_step;
    for k in 1..5 {
        let want = frf[k] / Complex64::new(0.0, 2.0 * std::f64::consts::PI * k as f64 * df);
        assert!((spectrum[k] - want).norm() <= 1e-5 * want.norm().max(1e-3), "bin {k}: {} vs {want}", spectrum[k]);
    }
    // 0 Hz has no velocity from an acceleration: zero but for the f32 rounding of the stored response.
    let peak = spectrum.iter().map(|c| c.norm()).fold(0.0, f64::max);
    assert!(spectrum[0].norm() <= 1e-5 * peak, "{} of {peak}", spectrum[0]);

    // Each is one point: `analyze` says so by name.
    for dir in ["catman", "dt9837", "accelerance"] {
        let Err(e) = metaplate_analysis::dataset_report::analyse_dataset(&tmp.path().join(dir), None) else {
            panic!("{dir}: one point analysed")
        };
        assert!(e.to_string().contains("it holds one point, at ("), "{dir}: {e}");
    }
}

#[test]
fn what_is_no_response_or_no_motion_is_refused_by_name_and_what_is_skipped_listed() {
    let tmp = tempfile::tempdir().unwrap();
    let why = import(&["Sample_UFF58b_bin.uff"], &tmp.path().join("a"), ImportOptions::default()).unwrap_err();
    assert!(
        why.starts_with(&format!(
            "{} record 1 (dataset 58 from line 1), line 11, record 9 (ordinate data characteristics): the ordinate is \
             sound pressure (data type 21, \"Pa\")",
            corpus("Sample_UFF58b_bin.uff").display()
        )),
        "{why}"
    );
    let options = ImportOptions {
        accept_unknown_quantity: true,
        nodes: Some(nodes_csv(tmp.path(), 0)),
        ..ImportOptions::default()
    };
    let summary = import(&["Sample_UFF58b_bin.uff"], &tmp.path().join("b"), options).unwrap();
    assert_eq!(summary.ir_unit, "declared unknown (sound pressure (data type 21, \"Pa\"))");
    assert_eq!(summary.ir_len, 79_292);

    for (name, skipped) in [
        ("sample_dataset58_psd.uff", "1 x dataset 58, function type 9 (power spectral density) (first: "),
        ("heat_engine_housing.uff", "1 x dataset 151 (header) (first: "),
        ("TestLab_161_164_18_15_82.uff", "3 x dataset 82 (trace lines) (first: "),
    ] {
        let why = import(&[name], &tmp.path().join(name), ImportOptions::default()).unwrap_err();
        assert!(why.starts_with("the files hold no response (a dataset 58 or 58b of function type 1"), "{why}");
        assert!(why.contains(skipped), "{name}: {why}");
    }
    let why =
        import(&["dataset_milestone_in_header.uff"], &tmp.path().join("m"), ImportOptions::default()).unwrap_err();
    assert_eq!(
        why,
        format!(
            "{} cannot be read: record 1 (dataset 58), line 21: the dataset ends after 42 of the 2508876 values record \
             7 announces",
            corpus("dataset_milestone_in_header.uff").display()
        )
    );
}

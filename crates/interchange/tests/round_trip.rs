//! Dataset -> universal file -> dataset, in every format, from FRFs alone, and placed by the nodes alone.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use metaplate_interchange::{ExportOptions, ImportOptions, Progress};
use metaplate_store::{Dataset, IR_UNIT_M_S_PER_N};
use metaplate_uff::{ByteOrder, Format, FunctionType, Precision, UffRecord};

use crate::common::{self, CALIBRATION, IR_LEN, RATE_HZ, SCAN_UNIT};

#[test]
fn every_format_gives_back_every_response_its_quality_grid_scene_and_description() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 2, 4, SCAN_UNIT);
    let original = Dataset::open(&data).unwrap();
    let binary = |byte_order| Format::Binary { byte_order };
    // (format, precision, bound on the error relative to a response's peak): ASCII single writes 6 significant
    // digits; ASCII double 12, and binary values give the stored f32 back.
    let cases = [
        (Format::Ascii, Precision::Single, 5e-6),
        (Format::Ascii, Precision::Double, 0.0),
        (binary(ByteOrder::LittleEndian), Precision::Single, 0.0),
        (binary(ByteOrder::BigEndian), Precision::Single, 0.0),
        (binary(ByteOrder::BigEndian), Precision::Double, 0.0),
    ];
    for (i, (format, precision, rel)) in cases.into_iter().enumerate() {
        let what = format!("{format:?} {precision:?}");
        let file = tmp.path().join(format!("{i}.uff"));
        let options = ExportOptions { format, precision, frequency: true, points: None };
        let progress = common::export(&data, &file, &options).unwrap();
        assert_eq!(progress.first(), Some(&Progress { done: 0, total: 24 }), "{what}");
        assert_eq!(progress.last(), Some(&Progress { done: 24, total: 24 }), "{what}");
        let back = tmp.path().join(format!("{i}"));
        let summary = common::import(&[file], &back, ImportOptions::default()).unwrap();
        assert_eq!((summary.rows, summary.from_frf, summary.ir_len), (24, 0, IR_LEN), "{what}");
        assert_eq!(summary.sample_rate_hz, RATE_HZ, "{what}");
        assert!(summary.skipped.is_empty(), "{what}");
        let imported = Dataset::open(&back).unwrap();
        common::assert_same(&original, &imported, rel, &what);
        for meta in original.rows() {
            let got = imported.meta(meta.point_index, meta.actuator).unwrap();
            let quality = |m: &metaplate_store::IrMeta| {
                (m.status, m.snr_db, m.retries, m.measured_at_unix_us, m.estimated_error_db)
            };
            assert_eq!(quality(got), quality(meta), "{what}");
        }
        let (want, got) = (&original.manifest().meta, &imported.manifest().meta);
        assert_eq!((got.grid, &got.scene, got.seed), (want.grid, &want.scene, want.seed), "{what}");
        // The scan's unit and calibration, from the export's header (the responses' records say "full scale").
        let description = got.description.as_ref().unwrap();
        assert_eq!((description.ir_unit.as_str(), description.pre_samples), (SCAN_UNIT, 4), "{what}");
        assert_eq!(got.config["calibration"], CALIBRATION, "{what}");
        assert_eq!(summary.calibration.as_deref(), Some(CALIBRATION), "{what}");
        assert_eq!(got.recipe, "import-uff");
        assert_eq!(got.config["source_recipe"], "scan");
        assert_eq!(got.config["grid_from"], "metaplate ID lines");
    }
}

#[test]
fn without_metaplates_header_the_unit_is_the_records_and_another_tools_header_is_skipped() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 1, 0, SCAN_UNIT);
    let file = tmp.path().join("all.uff");
    let options = common::binary_double();
    common::export(&data, &file, &options).unwrap();
    // Without the header: the unit the records give, "m/s per" the denominator's label, and no calibration.
    let headless = tmp.path().join("headless.uff");
    common::rewrite(&file, &headless, options.format, options.precision, |r| !matches!(r, UffRecord::Header(_)));
    let summary = common::import(&[headless], &tmp.path().join("a"), ImportOptions::default()).unwrap();
    assert_eq!((summary.ir_unit.as_str(), summary.calibration), ("m/s per full scale", None));
    assert!(summary.skipped.is_empty());
    let imported = Dataset::open(tmp.path().join("a")).unwrap();
    assert_eq!(imported.manifest().meta.config.get("calibration"), None);
    // Another tool's header (LMS Test.Lab's program in record 3): skipped, restoring nothing.
    let foreign = tmp.path().join("foreign.uff");
    common::rewrite(&file, &foreign, options.format, options.precision, |r| {
        if let UffRecord::Header(h) = r {
            h.db_program = "LMS Test.Lab Rev project-15A".into();
        }
        true
    });
    let summary =
        common::import(std::slice::from_ref(&foreign), &tmp.path().join("b"), ImportOptions::default()).unwrap();
    assert_eq!((summary.ir_unit.as_str(), summary.calibration), ("m/s per full scale", None));
    assert_eq!(
        metaplate_interchange::skipped_summary(&summary.skipped),
        format!("1 x dataset 151 (header) (first: {} record 1, line 1)", foreign.display())
    );
    // Two exports of different calibrations are not merged under one.
    let other = tmp.path().join("other.uff");
    common::rewrite(&file, &other, options.format, options.precision, |r| {
        if let UffRecord::Header(h) = r {
            h.db_program = format!("metaplate cal={}", "0".repeat(64));
        }
        !matches!(r, UffRecord::Function(_))
    });
    let why = common::import(&[file, other.clone()], &tmp.path().join("c"), ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        why.starts_with(&format!(
            "{} record 1 (dataset 151 from line 1): metaplate's header of another dataset",
            other.display()
        )),
        "{why}"
    );
    assert!(!tmp.path().join("c").exists(), "nothing written");
}

#[test]
fn frequency_responses_alone_come_back_as_the_impulse_responses() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 2, 0, IR_UNIT_M_S_PER_N);
    let original = Dataset::open(&data).unwrap();
    let file = tmp.path().join("all.uff");
    let options = ExportOptions { frequency: true, ..common::binary_double() };
    common::export(&data, &file, &options).unwrap();
    let frf_only = tmp.path().join("frf.uff");
    common::rewrite(&file, &frf_only, options.format, options.precision, |record| match record {
        UffRecord::Function(f) => f.header.function_type == FunctionType::FrequencyResponse,
        _ => true,
    });
    let back = tmp.path().join("back");
    let summary = common::import(&[frf_only], &back, ImportOptions::default()).unwrap();
    assert_eq!((summary.rows, summary.from_frf), (24, 24));
    let imported = Dataset::open(&back).unwrap();
    common::assert_same(&original, &imported, 1e-9, "from FRFs");
    assert_eq!(imported.manifest().meta.description.as_ref().map(|d| d.ir_unit.as_str()), Some(IR_UNIT_M_S_PER_N));
}

#[test]
fn without_metaplate_id_lines_the_grid_and_actuators_come_from_the_nodes() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 3, 0, IR_UNIT_M_S_PER_N);
    let original = Dataset::open(&data).unwrap();
    let file = tmp.path().join("all.uff");
    let options = common::binary_double();
    common::export(&data, &file, &options).unwrap();
    // As another tool writes them: no metaplate ID lines.
    let foreign = tmp.path().join("foreign.uff");
    common::rewrite(&file, &foreign, options.format, options.precision, |record| {
        if let UffRecord::Function(f) = record {
            f.header.id_lines = std::array::from_fn(|_| "NONE".to_owned());
        }
        true
    });
    for (path, grid_from_nodes) in [(&foreign, false), (&file, true)] {
        let back = tmp.path().join(format!("back-{grid_from_nodes}"));
        common::import(
            std::slice::from_ref(path),
            &back,
            ImportOptions { grid_from_nodes, ..ImportOptions::default() },
        )
        .unwrap();
        let imported = Dataset::open(&back).unwrap();
        let meta = &imported.manifest().meta;
        assert_eq!(meta.grid, original.manifest().meta.grid, "the 4 x 3 grid found again");
        assert_eq!(meta.config["grid_from"], "nodes");
        common::assert_same(&original, &imported, 0.0, "placed by the nodes");
    }
}

#[test]
fn a_subset_of_points_exports_only_their_nodes_and_responses() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 2, 0, IR_UNIT_M_S_PER_N);
    let file = tmp.path().join("subset.uff");
    let options = ExportOptions { points: Some("2x2".parse().unwrap()), ..common::binary_double() };
    let progress = common::export(&data, &file, &options).unwrap();
    assert_eq!(progress.last(), Some(&Progress { done: 8, total: 8 }));
    let back = tmp.path().join("back");
    let summary = common::import(&[file], &back, ImportOptions::default()).unwrap();
    assert_eq!(summary.rows, 8, "4 points x 2 actuators");
}

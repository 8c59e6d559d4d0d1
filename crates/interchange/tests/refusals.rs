//! What the bridge refuses, and that each refusal says what and where.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::path::{Path, PathBuf};

use metaplate_interchange::{ImportOptions, actuator_sites, default_out};
use metaplate_store::IR_UNIT_M_S_PER_N;
use metaplate_uff::UffRecord;

use crate::common;

/// A dataset of 2 actuators exported in binary double precision: (its directory, the file).
fn exported(dir: &Path) -> (PathBuf, PathBuf) {
    let data = common::dataset(dir, 2, 0, IR_UNIT_M_S_PER_N);
    let file = dir.join("all.uff");
    common::export(&data, &file, &common::binary_double()).unwrap();
    (data, file)
}

fn refusal(files: &[PathBuf], out: &Path) -> String {
    common::message(&common::import(files, out, ImportOptions::default()).unwrap_err())
}

#[test]
fn an_ordinate_that_is_no_motion_is_refused_naming_the_file_record_line_field_and_what_is_accepted() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let pressure = tmp.path().join("pressure.uff");
    let options = common::binary_double();
    common::rewrite(&file, &pressure, options.format, options.precision, |record| {
        if let UffRecord::Function(f) = record {
            f.header.ordinate.data_type = 15;
            f.header.ordinate.units_label = "Pa".into();
        }
        true
    });
    let why = refusal(std::slice::from_ref(&pressure), &tmp.path().join("out"));
    // Records 1 to 3 are the header, units and nodes (lines 1-10, 11-16 and 17-47); the first response opens at
    // line 48.
    assert!(
        why.starts_with(&format!(
            "{} record 4 (dataset 58 from line 48), line 58, record 9 (ordinate data characteristics): the ordinate \
             is pressure (data type 15, \"Pa\"); metaplate imports velocity, and acceleration or displacement",
            pressure.display()
        )),
        "{why}"
    );
    assert!(why.ends_with("--accept-unknown-quantity imports it as declared unknown"), "{why}");
    assert!(!tmp.path().join("out").exists(), "nothing written");
    // Declared unknown, it imports as it is, and says so.
    let options = ImportOptions { accept_unknown_quantity: true, ..ImportOptions::default() };
    let summary = common::import(std::slice::from_ref(&pressure), &tmp.path().join("out"), options).unwrap();
    assert_eq!(summary.ir_unit, "declared unknown (pressure (data type 15, \"Pa\"))");
    assert_eq!(summary.rows, 24);
}

#[test]
fn two_responses_of_one_key_and_type_are_refused_naming_both_records() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let why = refusal(&[file.clone(), file.clone()], &tmp.path().join("out"));
    assert!(why.contains("has two responses of one type"), "{why}");
    let at = format!("{} record 4 (dataset 58 from line 48)", file.display());
    assert!(why.contains(&format!("{at} and {at}")), "{why}");
}

#[test]
fn foreign_responses_without_nodes_cannot_be_placed() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let bare = tmp.path().join("bare.uff");
    let options = common::binary_double();
    common::rewrite(&file, &bare, options.format, options.precision, |record| match record {
        UffRecord::Nodes(_) => false,
        UffRecord::Function(f) => {
            f.header.id_lines = std::array::from_fn(|_| "NONE".to_owned());
            true
        }
        _ => true,
    });
    let why = refusal(std::slice::from_ref(&bare), &tmp.path().join("out"));
    // Without dataset 2411 the header and units take lines 1-16 and the first response opens at line 17.
    assert_eq!(
        why,
        format!(
            "{} record 3 (dataset 58 from line 17), line 24, record 6 (DOF identification), response node: node 1 has \
             no position: no dataset 2411 lists it; give the positions with --nodes FILE (CSV columns node,x_m,y_m \
             and optionally z_m)",
            bare.display()
        )
    );
}

#[test]
fn files_without_responses_and_malformed_files_are_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let headers = tmp.path().join("headers.uff");
    let options = common::binary_double();
    common::rewrite(&file, &headers, options.format, options.precision, |r| !matches!(r, UffRecord::Function(_)));
    assert_eq!(
        refusal(&[headers], &tmp.path().join("a")),
        "the files hold no response (a dataset 58 or 58b of function type 1, time response, or 4, frequency \
         response function)"
    );

    let bad = tmp.path().join("bad.uff");
    let mut text = String::from("    -1\n    58\n");
    for _ in 0..5 {
        text.push_str("NONE\n");
    }
    text.push_str("    x         0    0         0 NONE               1   3 NONE               1   3\n    -1\n");
    std::fs::write(&bad, text).unwrap();
    let why = refusal(std::slice::from_ref(&bad), &tmp.path().join("b"));
    assert!(why.starts_with(&format!("{} cannot be read: record 1 (dataset 58), line 9", bad.display())), "{why}");

    let missing = tmp.path().join("missing.uff");
    assert!(
        refusal(std::slice::from_ref(&missing), &tmp.path().join("c"))
            .starts_with(&format!("opening {}: ", missing.display()))
    );
}

#[test]
fn an_import_never_writes_into_a_dataset_that_is_there() {
    let tmp = tempfile::tempdir().unwrap();
    let (data, file) = exported(tmp.path());
    let why = refusal(&[file], &data);
    assert!(why.starts_with(&format!("creating dataset {}: ", data.display())), "{why}");
}

#[test]
fn an_export_needs_every_actuators_position_and_a_name_for_its_default_file() {
    let tmp = tempfile::tempdir().unwrap();
    let data = common::dataset(tmp.path(), 2, 0, IR_UNIT_M_S_PER_N);
    let out = tmp.path().join("x.uff");
    let error =
        metaplate_interchange::export(&data, &out, &common::binary_double(), &[(0.0, 0.0)], |_| {}).unwrap_err();
    assert_eq!(common::message(&error), "actuator 1 has no position in the scene (1 actuators)");

    assert_eq!(default_out(&data).unwrap(), tmp.path().join("original.uff"));
    assert!(common::message(&default_out(Path::new("/")).unwrap_err()).contains("has no directory name: give --out"));

    assert_eq!(actuator_sites(&data, None).unwrap(), common::sites(), "the dataset's built-in scene");
    let scene_file = tmp.path().join("no-such-scene.toml");
    assert!(
        common::message(&actuator_sites(&data, Some(&scene_file)).unwrap_err())
            .starts_with(&format!("reading scene {}", scene_file.display()))
    );
}

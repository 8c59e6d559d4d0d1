//! What the bridge refuses, and that each refusal says what and where.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::path::{Path, PathBuf};

use metaplate_interchange::{ImportOptions, InterchangeError, actuator_sites, default_out};
use metaplate_store::IR_UNIT_M_S_PER_N;
use metaplate_uff::UffRecord;

use crate::common;

/// The error's message with its causes after colons, as the binary prints it.
fn message(error: &InterchangeError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        text.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    text
}

/// A dataset of 2 actuators exported in binary double precision: (its directory, the file).
fn exported(dir: &Path) -> (PathBuf, PathBuf) {
    let data = common::dataset(dir, 2, 0, IR_UNIT_M_S_PER_N);
    let file = dir.join("all.uff");
    common::export(&data, &file, &common::binary_double()).unwrap();
    (data, file)
}

fn refusal(files: &[PathBuf], out: &Path) -> String {
    message(&common::import(files, out, ImportOptions::default()).unwrap_err())
}

#[test]
fn an_ordinate_that_is_not_velocity_is_refused_naming_the_file_and_record() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let displacement = tmp.path().join("displacement.uff");
    let options = common::binary_double();
    common::rewrite(&file, &displacement, options.format, options.precision, |record| {
        if let UffRecord::Function(f) = record {
            f.header.ordinate.data_type = 8;
            f.header.ordinate.label = "Displacement".into();
        }
        true
    });
    let why = refusal(std::slice::from_ref(&displacement), &tmp.path().join("out"));
    assert!(
        why.starts_with(&format!("{} record 3: the ordinate is Displacement (data type 8)", displacement.display())),
        "{why}"
    );
    assert!(!tmp.path().join("out").exists(), "nothing written");
}

#[test]
fn two_responses_of_one_key_and_type_are_refused_naming_both_records() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let why = refusal(&[file.clone(), file.clone()], &tmp.path().join("out"));
    assert!(why.contains("has two responses of one type"), "{why}");
    assert!(why.contains(&format!("{} record 3 and {} record 3", file.display(), file.display())), "{why}");
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
    let why = refusal(&[bare], &tmp.path().join("out"));
    assert!(why.starts_with("response node 1 has no coordinates (no dataset 2411 lists it)"), "{why}");
}

#[test]
fn files_without_responses_and_malformed_files_are_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, file) = exported(tmp.path());
    let headers = tmp.path().join("headers.uff");
    let options = common::binary_double();
    common::rewrite(&file, &headers, options.format, options.precision, |r| !matches!(r, UffRecord::Function(_)));
    assert_eq!(refusal(&[headers], &tmp.path().join("a")), "the files hold no dataset 58 or 58b (no response)");

    let bad = tmp.path().join("bad.uff");
    let mut text = String::from("    -1\n    58\n");
    for _ in 0..5 {
        text.push_str("NONE\n");
    }
    text.push_str("    x         0    0         0 NONE               1   3 NONE               1   3\n    -1\n");
    std::fs::write(&bad, text).unwrap();
    let why = refusal(std::slice::from_ref(&bad), &tmp.path().join("b"));
    assert!(why.starts_with(&format!("{} is malformed: record 1 (dataset 58), line 9", bad.display())), "{why}");

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
    assert_eq!(message(&error), "actuator 1 has no position in the scene (1 actuators)");

    assert_eq!(default_out(&data).unwrap(), tmp.path().join("original.uff"));
    assert!(message(&default_out(Path::new("/")).unwrap_err()).contains("has no directory name: give --out"));

    assert_eq!(actuator_sites(&data, None).unwrap(), common::sites(), "the dataset's built-in scene");
    let scene_file = tmp.path().join("no-such-scene.toml");
    assert!(
        message(&actuator_sites(&data, Some(&scene_file)).unwrap_err())
            .starts_with(&format!("reading scene {}", scene_file.display()))
    );
}

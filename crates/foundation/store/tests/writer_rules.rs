//! What the writer refuses, and that a refusal leaves nothing behind.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::fs;

use common::{meta, records};
use metaplate_store::{BATCH_DIR, Dataset, DatasetWriter, IfExists, JOURNAL_FILE, MANIFEST_FILE, StoreError};

fn entries(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<_> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    names
}

#[test]
fn duplicates_are_refused_within_and_across_batches_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0, 1], 8)).unwrap();

    let mut twice = records(&[(1, 0)], &[2], 8);
    twice.extend(records(&[(1, 0)], &[2], 8));
    let err = writer.commit_batch(&twice).unwrap_err();
    assert!(matches!(err, StoreError::Duplicate { point_index: 1, actuator: 2, .. }), "{err}");

    let again = records(&[(2, 0), (0, 0)], &[1], 8);
    match writer.commit_batch(&again).unwrap_err() {
        StoreError::Duplicate { point_index: 0, actuator: 1, first, location } => {
            assert_eq!(first, "batch-000000.parquet row 1");
            assert_eq!(location, "batch-000001.parquet row 1");
        }
        other => panic!("expected a duplicate, got {other}"),
    }
    // Refused commits wrote no file, took no batch number and marked no pair as seen.
    assert_eq!(entries(&dir.path().join(BATCH_DIR)), ["batch-000000.parquet"]);
    assert_eq!(writer.rows(), 2);
    let info = writer.commit_batch(&records(&[(2, 0)], &[1], 8)).unwrap();
    assert_eq!(info.file, "batch-000001.parquet");
    writer.finish().unwrap();
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 3);
}

#[test]
fn bad_records_are_refused_with_their_row() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    assert!(matches!(writer.commit_batch(&[]), Err(StoreError::EmptyBatch)));

    let mut bad = records(&[(0, 0), (1, 0)], &[0], 8);
    bad[1].ir[3] = f32::INFINITY;
    let err = writer.commit_batch(&bad).unwrap_err();
    assert!(
        matches!(err, StoreError::InvalidRecord { ref location, .. } if location == "batch-000000.parquet row 1"),
        "{err}"
    );

    let mut bad = records(&[(0, 0)], &[0], 8);
    bad[0].ir.clear();
    assert!(matches!(writer.commit_batch(&bad), Err(StoreError::InvalidRecord { .. })));

    let mut bad = records(&[(0, 0)], &[0], 8);
    bad[0].meta.ix = 4; // the grid is 4 x 3
    assert!(matches!(writer.commit_batch(&bad), Err(StoreError::InvalidRecord { .. })));

    let mut bad = records(&[(0, 0), (1, 0)], &[0], 8);
    bad[1].ir.push(0.0);
    assert!(matches!(writer.commit_batch(&bad), Err(StoreError::Inconsistent { .. })));

    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    let mut other_rate = records(&[(1, 0)], &[0], 8);
    other_rate[0].meta.sample_rate_hz = 48_000.0;
    assert!(matches!(writer.commit_batch(&other_rate), Err(StoreError::Inconsistent { what: "sample_rate_hz", .. })));
    assert_eq!(entries(&dir.path().join(BATCH_DIR)), ["batch-000000.parquet"]);
}

#[test]
fn bad_metadata_is_refused_before_anything_is_created() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("run");
    let mut bad = meta();
    bad.grid.spacing_m = 0.0;
    assert!(matches!(DatasetWriter::create(&target, bad, IfExists::Refuse), Err(StoreError::InvalidMeta { .. })));
    let mut bad = meta();
    bad.schema_version = 99;
    assert!(matches!(
        DatasetWriter::create(&target, bad, IfExists::Refuse),
        Err(StoreError::UnsupportedSchemaVersion { found: 99, .. })
    ));
    assert!(!target.exists());
}

#[test]
fn finishing_an_empty_dataset_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    assert!(matches!(writer.finish(), Err(StoreError::EmptyDataset { .. })));
    assert_eq!(entries(dir.path()), [BATCH_DIR, JOURNAL_FILE, MANIFEST_FILE]);
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::EmptyDataset { .. })));
    assert!(entries(&dir.path().join(BATCH_DIR)).is_empty());
}

#[test]
fn a_non_empty_directory_is_refused_unless_replacing_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    writer.finish().unwrap();

    // Refused: the old dataset is untouched.
    match DatasetWriter::create(dir.path(), meta(), IfExists::Refuse) {
        Err(StoreError::NotEmpty { entry, .. }) => assert_eq!(entry, BATCH_DIR),
        other => panic!("expected NotEmpty, got {other:?}"),
    }
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 1);

    // Replaced: a stale temporary from a crash goes too, and the new dataset starts at batch 0.
    fs::write(dir.path().join(".batch-000001.parquet.tmp"), b"half").unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Replace).unwrap();
    assert_eq!(entries(dir.path()), [BATCH_DIR, JOURNAL_FILE, MANIFEST_FILE]);
    assert!(entries(&dir.path().join(BATCH_DIR)).is_empty());
    writer.commit_batch(&records(&[(3, 2)], &[5], 8)).unwrap();
    writer.finish().unwrap();
    let dataset = Dataset::open(dir.path()).unwrap();
    assert_eq!((dataset.points(), dataset.actuators()), (&[11][..], &[5][..]));
}

#[test]
fn replace_never_deletes_foreign_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    writer.finish().unwrap();
    fs::write(dir.path().join("notes.txt"), b"keep me").unwrap();
    match DatasetWriter::create(dir.path(), meta(), IfExists::Replace) {
        Err(StoreError::NotEmpty { entry, .. }) => assert_eq!(entry, "notes.txt"),
        other => panic!("expected NotEmpty, got {other:?}"),
    }
    // The refusal deleted nothing: the dataset still opens.
    assert_eq!(entries(dir.path()), [BATCH_DIR, JOURNAL_FILE, MANIFEST_FILE, "notes.txt"]);
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 1);
}

#[test]
fn a_file_where_the_directory_should_be_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plain-file");
    fs::write(&file, b"x").unwrap();
    let err = DatasetWriter::create(&file, meta(), IfExists::Refuse).unwrap_err();
    assert!(matches!(err, StoreError::Io { .. }), "{err}");
}

#[test]
fn replace_refuses_a_foreign_file_inside_batches() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    writer.finish().unwrap();
    fs::write(dir.path().join(BATCH_DIR).join("extra.parquet"), b"someone else's").unwrap();
    match DatasetWriter::create(dir.path(), meta(), IfExists::Replace) {
        Err(StoreError::NotEmpty { entry, .. }) => assert_eq!(entry, "batches/extra.parquet"),
        other => panic!("expected NotEmpty, got {other:?}"),
    }
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 1);
}

//! Damaged or hostile datasets are refused with a typed error naming what is wrong, never a panic.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::fs;
use std::path::{Path, PathBuf};

use common::{meta, records};
use metaplate_store::{BATCH_DIR, Dataset, DatasetWriter, IfExists, JOURNAL_FILE, MANIFEST_FILE, StoreError};

const BATCH: &str = "batch-000000.parquet";

/// Where batch file `name` of the dataset in `dir` lives.
fn batch_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(BATCH_DIR).join(name)
}

/// A finished one-batch dataset.
fn dataset(dir: &Path) {
    let mut writer = DatasetWriter::create(dir, meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0), (1, 1)], &[0, 3], 64)).unwrap();
    writer.finish().unwrap();
}

/// Makes the dataset in `dir` look as written before the journal existed (manifest only), so that the tests below
/// that tamper with the manifest's batch list exercise the manifest reader; with a journal, the journal decides.
fn legacy(dir: &Path) {
    fs::remove_file(dir.join(JOURNAL_FILE)).unwrap();
}

/// Rewrites the manifest through a JSON edit.
fn edit_manifest(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join(MANIFEST_FILE);
    let mut json: serde_json::Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut json);
    fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
}

#[test]
fn a_single_bit_flip_anywhere_is_a_checksum_mismatch_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    let path = batch_path(dir.path(), BATCH);
    let original = fs::read(&path).unwrap();
    // Header magic, the middle (data pages) and the footer: a flip in any of them must be caught.
    for offset in [0, original.len() / 2, original.len() - 5] {
        let mut flipped = original.clone();
        flipped[offset] ^= 0x10;
        fs::write(&path, &flipped).unwrap();
        match Dataset::open(dir.path()) {
            Err(StoreError::ChecksumMismatch { file, expected, actual }) => {
                assert_eq!(file, BATCH);
                assert_ne!(expected, actual);
            }
            other => panic!("flip at {offset}: expected a checksum mismatch, got {other:?}"),
        }
    }
    fs::write(&path, &original).unwrap();
    assert!(Dataset::open(dir.path()).is_ok(), "restoring the bytes restores the dataset");
}

#[test]
fn a_truncated_file_is_a_size_mismatch() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    let path = batch_path(dir.path(), BATCH);
    let original = fs::read(&path).unwrap();
    for keep in [0, 1, original.len() / 2, original.len() - 1] {
        fs::write(&path, &original[..keep]).unwrap();
        match Dataset::open(dir.path()) {
            Err(StoreError::SizeMismatch { file, expected_bytes, actual_bytes }) => {
                assert_eq!((file.as_str(), expected_bytes, actual_bytes), (BATCH, original.len() as u64, keep as u64));
            }
            other => panic!("truncated to {keep}: expected a size mismatch, got {other:?}"),
        }
    }
}

#[test]
fn a_missing_batch_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    fs::remove_file(batch_path(dir.path(), BATCH)).unwrap();
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::BatchMissing { file }) if file == BATCH));
}

#[test]
fn a_commit_is_readable_before_finish_and_a_directory_without_manifest_is_not_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    // Committed but never finished (a run that stopped): the journal makes the batch readable.
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0], 4)).unwrap();
    drop(writer);
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 1);
    // Without its manifest the directory is not a dataset.
    fs::remove_file(dir.path().join(MANIFEST_FILE)).unwrap();
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::ManifestMissing { .. })));
    // And a directory that does not exist at all.
    assert!(matches!(Dataset::open(dir.path().join("nowhere")), Err(StoreError::ManifestMissing { .. })));
}

#[test]
fn malformed_manifests_are_refused_with_the_reason() {
    type Damage = Box<dyn Fn(&Path)>;
    let cases: [(&str, Damage); 5] = [
        ("not JSON", Box::new(|d| fs::write(d.join(MANIFEST_FILE), b"{ \"schema_version\": 1,").unwrap())),
        ("empty file", Box::new(|d| fs::write(d.join(MANIFEST_FILE), b"").unwrap())),
        ("a field missing", Box::new(|d| edit_manifest(d, |j| drop(j.as_object_mut().unwrap().remove("grid"))))),
        ("a field of the wrong type", Box::new(|d| edit_manifest(d, |j| j["seed"] = "seven".into()))),
        ("a bad checksum text", Box::new(|d| edit_manifest(d, |j| j["batches"][0]["checksum"] = "md5:abc".into()))),
    ];
    for (what, damage) in cases {
        let dir = tempfile::tempdir().unwrap();
        dataset(dir.path());
        damage(dir.path());
        let err = Dataset::open(dir.path()).unwrap_err();
        assert!(matches!(err, StoreError::ManifestMalformed { .. }), "{what}: {err}");
    }
}

#[test]
fn a_manifest_cannot_point_outside_its_directory() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    for name in ["../batch-000000.parquet", "/etc/passwd", ".hidden.parquet", "sub/batch.parquet"] {
        edit_manifest(dir.path(), |j| j["batches"][0]["file"] = name.into());
        let err = Dataset::open(dir.path()).unwrap_err();
        assert!(matches!(err, StoreError::ManifestMalformed { ref reason, .. } if reason.contains("plain")), "{err}");
    }
}

#[test]
fn an_edited_configuration_breaks_the_config_hash() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    edit_manifest(dir.path(), |j| j["config"]["ir_len"] = 17.into());
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::ConfigHashMismatch { .. })));
}

#[test]
fn a_newer_schema_version_is_reported_as_such() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    edit_manifest(dir.path(), |j| j["schema_version"] = 2.into());
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::UnsupportedSchemaVersion { found: 2, supported: 1 })));
}

#[test]
fn a_row_count_that_disagrees_with_the_manifest_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    legacy(dir.path());
    edit_manifest(dir.path(), |j| j["batches"][0]["rows"] = 5.into());
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::RowCountMismatch { expected: 5, actual: 4, .. })));
}

#[test]
fn a_batch_listed_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    legacy(dir.path());
    edit_manifest(dir.path(), |j| {
        let first = j["batches"][0].clone();
        j["batches"].as_array_mut().unwrap().push(first);
    });
    let err = Dataset::open(dir.path()).unwrap_err();
    assert!(matches!(err, StoreError::ManifestMalformed { ref reason, .. } if reason.contains("twice")), "{err}");
}

#[test]
fn duplicate_rows_across_files_are_refused_on_read() {
    // Two writers each produce a valid dataset with the same (point, actuator); a manifest that lists both files
    // (a bad merge by hand) must not read as one dataset.
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    dataset(a.path());
    dataset(b.path());
    merge_second_dataset(a.path(), b.path());
    match Dataset::open(a.path()) {
        Err(StoreError::Duplicate { point_index: 0, actuator: 0, first, location }) => {
            assert_eq!(
                (first.as_str(), location.as_str()),
                ("batch-000000.parquet row 0", "batch-000001.parquet row 0")
            );
        }
        other => panic!("expected a duplicate, got {other:?}"),
    }
}

/// Appends `b`'s only batch to `a` as `batch-000001.parquet`, listed with its true size and checksum: a hand-made
/// merge that the writer would never produce.
fn merge_second_dataset(a: &Path, b: &Path) {
    legacy(a);
    fs::copy(batch_path(b, BATCH), batch_path(a, "batch-000001.parquet")).unwrap();
    let b_manifest: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(b.join(MANIFEST_FILE)).unwrap()).unwrap();
    edit_manifest(a, |j| {
        let mut entry = b_manifest["batches"][0].clone();
        entry["file"] = "batch-000001.parquet".into();
        j["batches"].as_array_mut().unwrap().push(entry);
    });
}

/// A finished one-batch dataset of `records`.
fn dataset_of(dir: &Path, records: &[metaplate_store::IrRecord]) {
    let mut writer = DatasetWriter::create(dir, meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(records).unwrap();
    writer.finish().unwrap();
}

#[test]
fn mixed_ir_lengths_across_files_are_refused_on_read() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    dataset_of(a.path(), &records(&[(0, 0)], &[0], 64));
    dataset_of(b.path(), &records(&[(1, 0)], &[0], 65));
    merge_second_dataset(a.path(), b.path());
    let err = Dataset::open(a.path()).unwrap_err();
    assert!(
        matches!(err, StoreError::Inconsistent { what: "ir length (samples)", ref expected, ref found, .. }
            if expected == "64" && found == "65"),
        "{err}"
    );
}

#[test]
fn mixed_sample_rates_across_files_are_refused_on_read() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    dataset_of(a.path(), &records(&[(0, 0)], &[0], 64));
    let mut other = records(&[(1, 0)], &[0], 64);
    other[0].meta.sample_rate_hz = 48_000.0;
    dataset_of(b.path(), &other);
    merge_second_dataset(a.path(), b.path());
    let err = Dataset::open(a.path()).unwrap_err();
    assert!(matches!(err, StoreError::Inconsistent { what: "sample_rate_hz", .. }), "{err}");
}

/// Replaces every occurrence of `from` in the batch file (the value, and its copies in the statistics) by `to` of
/// the same length, and reseals the manifest entry (size and checksum), as a foreign tool writing a bad value would.
fn patch_and_reseal(dir: &Path, from: &[u8], to: &[u8]) {
    let path = batch_path(dir, BATCH);
    let mut bytes = fs::read(&path).unwrap();
    let at: Vec<usize> = bytes.windows(from.len()).enumerate().filter(|(_, w)| *w == from).map(|(i, _)| i).collect();
    assert!(!at.is_empty(), "the pattern must occur in the file for the patch to mean anything");
    for i in at {
        bytes[i..i + from.len()].copy_from_slice(to);
    }
    fs::write(&path, &bytes).unwrap();
    legacy(dir);
    edit_manifest(dir, |j| {
        j["batches"][0]["size_bytes"] = (bytes.len() as u64).into();
        j["batches"][0]["checksum"] = metaplate_store::sha256(&bytes).into();
    });
}

#[test]
fn a_nan_sample_written_by_a_foreign_tool_is_refused_on_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut written = records(&[(0, 0)], &[0], 64);
    // A sentinel that is neither the smallest nor the largest sample, so that only the sample itself is patched (the
    // page statistics hold the extremes), and whose bytes Snappy leaves as a literal (f32 noise does not compress).
    let sentinel = 0.123_456_79_f32;
    written[0].ir[10] = sentinel;
    written[0].ir[20] = 2.0;
    written[0].ir[30] = -2.0;
    dataset_of(dir.path(), &written);
    patch_and_reseal(dir.path(), &sentinel.to_le_bytes(), &f32::NAN.to_le_bytes());
    let err = Dataset::open(dir.path()).unwrap_err();
    assert!(
        matches!(err, StoreError::InvalidRecord { ref location, ref reason }
            if location == "batch-000000.parquet row 0" && reason.contains("sample 10")),
        "{err}"
    );
}

#[test]
fn an_unknown_status_written_by_a_foreign_tool_is_refused_on_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut written = records(&[(0, 0)], &[0], 64);
    written[0].meta.status = Some(metaplate_store::Status::Overrange);
    dataset_of(dir.path(), &written);
    // Same length, so only the value changes.
    patch_and_reseal(dir.path(), b"overrange", b"overwrite");
    let err = Dataset::open(dir.path()).unwrap_err();
    assert!(matches!(err, StoreError::InvalidRecord { ref reason, .. } if reason.contains("overwrite")), "{err}");
}

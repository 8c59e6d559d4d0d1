//! Writing a dataset and reading it back.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{bits, meta, records};
use metaplate_store::{
    BATCH_DIR, Dataset, DatasetWriter, IfExists, IrRecord, JOURNAL_FILE, MANIFEST_FILE, Manifest, StoreError, sha256,
};

/// Two batches over a 4 x 3 grid and three actuators.
fn write_two_batches(dir: &std::path::Path) -> (Vec<IrRecord>, Manifest) {
    let first = records(&[(0, 0), (1, 0), (3, 2)], &[0, 1, 7], 16);
    let second = records(&[(2, 1)], &[0, 1, 7], 16);
    let mut writer = DatasetWriter::create(dir, meta(), IfExists::Refuse).unwrap();
    let info = writer.commit_batch(&first).unwrap();
    assert_eq!((info.file.as_str(), info.rows), ("batch-000000.parquet", 9));
    writer.commit_batch(&second).unwrap();
    let manifest = writer.finish().unwrap();
    (first.into_iter().chain(second).collect(), manifest)
}

#[test]
fn a_dataset_reads_back_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let (written, manifest) = write_two_batches(dir.path());
    let dataset = Dataset::open(dir.path()).unwrap();

    assert_eq!(dataset.manifest(), &manifest);
    assert_eq!(dataset.len(), written.len());
    assert_eq!(dataset.ir_len(), 16);
    assert_eq!(dataset.sample_rate_hz(), 24_000.0);
    assert_eq!(dataset.points(), [0, 1, 6, 11]);
    assert_eq!(dataset.actuators(), [0, 1, 7]);
    // Rows come back in commit order, every field and every IR bit identical.
    assert_eq!(dataset.rows(), written.iter().map(|r| r.meta).collect::<Vec<_>>());
    for (row, record) in written.iter().enumerate() {
        let by_key = dataset.ir(record.meta.point_index, record.meta.actuator).unwrap();
        assert_eq!(bits(by_key), bits(&record.ir));
        assert_eq!(bits(dataset.row_ir(row).unwrap()), bits(&record.ir));
        assert_eq!(dataset.meta(record.meta.point_index, record.meta.actuator), Some(&record.meta));
    }
    assert_eq!(dataset.irs().len(), written.len() * 16);
    // Pairs that were never written are absent, not invented.
    assert_eq!(dataset.ir(2, 0), None);
    assert_eq!(dataset.ir(0, 2), None);
    assert_eq!(dataset.row_ir(written.len()), None);
}

#[test]
fn the_manifest_lists_each_file_with_its_true_size_and_sha256() {
    let dir = tempfile::tempdir().unwrap();
    let (_, manifest) = write_two_batches(dir.path());
    assert_eq!(manifest.batches.len(), 2);
    for batch in &manifest.batches {
        let bytes = std::fs::read(dir.path().join(BATCH_DIR).join(&batch.file)).unwrap();
        assert_eq!(batch.size_bytes, bytes.len() as u64);
        assert_eq!(batch.checksum, sha256(&bytes));
    }
    assert_eq!(manifest.config_hash, manifest.meta.config_hash());
    // created_at is ISO-8601 UTC with milliseconds: "YYYY-MM-DDTHH:MM:SS.mmmZ".
    let created_at = &manifest.created_at;
    assert_eq!(created_at.len(), 24, "{created_at}");
    assert!(created_at.ends_with('Z') && created_at.as_bytes()[10] == b'T', "{created_at}");
    // Nothing else is left: no temporary files, and batches/ holds only the batch files (what directory readers need).
    let names = |d: &std::path::Path| {
        let mut names: Vec<_> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        names.sort();
        names
    };
    assert_eq!(names(dir.path()), [BATCH_DIR, JOURNAL_FILE, MANIFEST_FILE]);
    assert_eq!(names(&dir.path().join(BATCH_DIR)), ["batch-000000.parquet", "batch-000001.parquet"]);
}

#[test]
fn the_manifest_json_is_flat_with_the_documented_fields() {
    let dir = tempfile::tempdir().unwrap();
    write_two_batches(dir.path());
    let text = std::fs::read_to_string(dir.path().join(MANIFEST_FILE)).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let keys: Vec<_> = json.as_object().unwrap().keys().cloned().collect();
    for key in [
        "schema_version",
        "recipe",
        "config",
        "scene",
        "software_version",
        "seed",
        "grid",
        "created_at",
        "batches",
        "config_hash",
    ] {
        assert!(keys.iter().any(|k| k == key), "{key} missing from {keys:?}");
    }
    assert_eq!(json["recipe"], "simulate-greens");
    assert_eq!(json["grid"]["nx"], 4);
    assert_eq!(json["batches"][1]["file"], "batch-000001.parquet");
}

#[test]
fn checkpoint_makes_progress_readable_and_can_be_repeated() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    assert!(matches!(writer.checkpoint(), Err(StoreError::EmptyDataset { .. })));
    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    writer.checkpoint().unwrap();
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 1);
    writer.commit_batch(&records(&[(1, 0)], &[0], 8)).unwrap();
    // The journal makes the second batch readable at once; the manifest's list still holds the first checkpoint.
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 2);
    assert_eq!(Manifest::read(dir.path()).unwrap().batches.len(), 1);
    writer.finish().unwrap();
    assert_eq!(Manifest::read(dir.path()).unwrap().batches.len(), 2);
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 2);
}

#[test]
fn ir_lengths_at_the_extremes() {
    // One sample, and a full-size 12000-sample response (the paper's 0.5 s at 24 kHz).
    for len in [1, 12_000] {
        let dir = tempfile::tempdir().unwrap();
        let written = records(&[(3, 2)], &[0, 7], len);
        let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
        writer.commit_batch(&written).unwrap();
        writer.finish().unwrap();
        let dataset = Dataset::open(dir.path()).unwrap();
        assert_eq!(dataset.ir_len(), len);
        for record in &written {
            assert_eq!(bits(dataset.ir(record.meta.point_index, record.meta.actuator).unwrap()), bits(&record.ir));
        }
    }
}

#[test]
fn extreme_f32_values_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mut written = records(&[(0, 0)], &[0], 1);
    written[0].ir = vec![f32::MAX, f32::MIN, f32::MIN_POSITIVE, f32::MIN_POSITIVE / 4.0, -0.0, 0.0, f32::EPSILON];
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&written).unwrap();
    writer.finish().unwrap();
    assert_eq!(bits(Dataset::open(dir.path()).unwrap().ir(0, 0).unwrap()), bits(&written[0].ir));
}

#[test]
fn a_follower_sees_each_commit_with_its_time_and_reads_it_file_by_file_while_the_writer_is_open() {
    let dir = tempfile::tempdir().unwrap();
    assert!(metaplate_store::journal::view(dir.path()).unwrap().is_none(), "no journal yet");
    let first = records(&[(0, 0), (1, 0)], &[0, 1], 16);
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&first).unwrap();
    // A line being appended: the follower reports it as a torn tail and reads the rest.
    let journal = dir.path().join(JOURNAL_FILE);
    let mut text = std::fs::read(&journal).unwrap();
    text.extend_from_slice(b"{\"seq\":1,\"at\":");
    std::fs::write(&journal, &text).unwrap();
    let view = metaplate_store::journal::view(dir.path()).unwrap().unwrap();
    assert_eq!(view.commits.len(), 1);
    assert!(view.issues.len() == 1 && view.issues[0].torn_tail, "{:?}", view.issues);
    let commit = &view.commits[0];
    assert_eq!((commit.seq, commit.batch.file.as_str()), (0, "batch-000000.parquet"));
    assert!(chrono::DateTime::parse_from_rfc3339(&commit.at).is_ok(), "{}", commit.at);
    assert_eq!(view.live, std::slice::from_ref(&commit.batch));
    let read = Dataset::read_batch(dir.path(), &view.live[0], metaplate_store::ReadOptions::default()).unwrap();
    assert_eq!(read, first);
    // A file that no longer matches its entry is refused, not half read.
    let mut wrong = view.live[0].clone();
    wrong.keys.swap(0, 1);
    let err = Dataset::read_batch(dir.path(), &wrong, metaplate_store::ReadOptions::default()).unwrap_err();
    assert!(matches!(err, StoreError::KeysMismatch { .. }), "{err}");
}

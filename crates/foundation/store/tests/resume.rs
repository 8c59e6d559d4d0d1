//! Stops of every kind, then resume: what was committed survives and verifies, what cannot be trusted is set aside
//! and re-measured, and no key is ever committed twice.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::collections::BTreeSet;
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use common::{bits, meta, records};
use metaplate_store::{
    BATCH_DIR, Dataset, DatasetWriter, IfExists, JOURNAL_FILE, QUARANTINE_DIR, StoreError, compact, export_wav,
    read_wav, write_wav_f32,
};

/// A dataset of three committed batches (points (0,0), (1,0), (2,0); actuators 0 and 1), left unfinished as a
/// killed run leaves it.
fn three_batches(dir: &Path) {
    let mut writer = DatasetWriter::create(dir, meta(), IfExists::Refuse).unwrap();
    for point in [(0, 0), (1, 0), (2, 0)] {
        writer.commit_batch(&records(&[point], &[0, 1], 32)).unwrap();
    }
}

fn batch(dir: &Path, n: u64) -> PathBuf {
    dir.join(BATCH_DIR).join(format!("batch-{n:06}.parquet"))
}

fn keys(pairs: &[(u32, u16)]) -> BTreeSet<(u32, u16)> {
    pairs.iter().copied().collect()
}

fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<_> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    names
}

#[test]
fn a_clean_resume_continues_numbering_and_refuses_committed_keys() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let (mut writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.committed, keys(&[(0, 0), (0, 1), (1, 0), (1, 1), (2, 0), (2, 1)]));
    assert!(report.quarantined.is_empty() && report.journal_issues.is_empty() && report.removed.is_empty());
    assert_eq!(writer.committed_keys(), report.committed);
    assert!(writer.is_committed(1, 1) && !writer.is_committed(3, 0));
    // A key committed before the stop is refused: never twice.
    let err = writer.commit_batch(&records(&[(1, 0)], &[1], 32)).unwrap_err();
    assert!(matches!(err, StoreError::Duplicate { point_index: 1, actuator: 1, .. }), "{err}");
    let info = writer.commit_batch(&records(&[(3, 0)], &[0, 1], 32)).unwrap();
    assert_eq!(info.file, "batch-000003.parquet");
    writer.finish().unwrap();
    let dataset = Dataset::open(dir.path()).unwrap();
    assert_eq!(dataset.len(), 8);
    assert_eq!(dataset.manifest().batches.len(), 4);
}

#[test]
fn only_one_writer_at_a_time() {
    let dir = tempfile::tempdir().unwrap();
    let writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    assert!(matches!(DatasetWriter::resume(dir.path(), &meta(), false), Err(StoreError::Locked { .. })));
    drop(writer);
    assert!(DatasetWriter::resume(dir.path(), &meta(), false).is_ok());
}

#[test]
fn a_changed_configuration_is_refused_naming_each_difference_unless_forced() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let mut changed = meta();
    changed.config.insert("ir_len".into(), 17.into());
    changed.seed = 8;
    match DatasetWriter::resume(dir.path(), &changed, false) {
        Err(StoreError::ConfigChanged { differences, .. }) => {
            assert_eq!(differences, ["config.ir_len: 16 -> 17", "seed: 7 -> 8"]);
        }
        other => panic!("expected ConfigChanged, got {other:?}"),
    }
    let (writer, report) = DatasetWriter::resume(dir.path(), &changed, true).unwrap();
    assert_eq!(report.forced_differences.len(), 2);
    assert_eq!(report.committed.len(), 6);
    drop(writer);
    // The forced resume is on record in the journal, and the manifest keeps the dataset's own metadata.
    let journal = fs::read_to_string(dir.path().join(JOURNAL_FILE)).unwrap();
    assert!(journal.contains("\"kind\":\"forced-resume\"") && journal.contains("seed: 7 -> 8"), "{journal}");
    assert_eq!(Dataset::open(dir.path()).unwrap().manifest().meta, meta());
}

#[test]
fn a_batch_file_without_its_journal_line_is_quarantined_and_its_keys_re_measured() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    // A kill between the batch file's rename and its journal line: the file is there, the line is not.
    let journal_path = dir.path().join(JOURNAL_FILE);
    let journal = fs::read_to_string(&journal_path).unwrap();
    let two_lines: String = journal.split_inclusive('\n').take(2).collect();
    fs::write(&journal_path, two_lines).unwrap();
    // And a stale temporary of a fourth batch.
    fs::write(dir.path().join(".batch-000003.parquet.tmp"), b"half").unwrap();
    let (mut writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.committed, keys(&[(0, 0), (0, 1), (1, 0), (1, 1)]));
    assert_eq!(report.quarantined.len(), 1);
    assert_eq!(report.quarantined[0].file, "batch-000002.parquet");
    assert!(report.quarantined[0].reason.contains("not in the journal"), "{:?}", report.quarantined);
    assert_eq!(names(&dir.path().join(QUARANTINE_DIR)), ["batch-000002.parquet", "notes.jsonl"]);
    assert!(!dir.path().join(".batch-000003.parquet.tmp").exists());
    // The point is measured again, under a fresh name.
    let info = writer.commit_batch(&records(&[(2, 0)], &[0, 1], 32)).unwrap();
    assert_eq!(info.file, "batch-000002.parquet");
    drop(writer);
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 6);
}

/// `{"velocity_range_m_s": v}`.
fn range_state(v: f64) -> Option<serde_json::Map<String, serde_json::Value>> {
    serde_json::json!({ "velocity_range_m_s": v }).as_object().cloned()
}

#[test]
fn resume_returns_the_state_of_the_last_committed_batch_or_of_the_one_before_a_torn_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    // A batch without state (as before the field existed), then two with.
    writer.commit_batch(&records(&[(0, 0)], &[0, 1], 32)).unwrap();
    writer.commit_batch_with_state(&records(&[(1, 0)], &[0, 1], 32), range_state(1.0)).unwrap();
    writer.commit_batch_with_state(&records(&[(2, 0)], &[0, 1], 32), range_state(10.0)).unwrap();
    drop(writer);
    let (writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.state, range_state(10.0), "the last batch's state");
    drop(writer);
    // Power lost mid-append of the last line: its rows and its state are not committed, the previous ones are.
    let journal_path = dir.path().join(JOURNAL_FILE);
    let journal = fs::read(&journal_path).unwrap();
    fs::write(&journal_path, &journal[..journal.len() - 40]).unwrap();
    let (writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert!(report.journal_issues[0].torn_tail, "{:?}", report.journal_issues);
    assert_eq!(report.committed.len(), 4);
    assert_eq!(report.state, range_state(1.0), "the state of the batch before the torn line");
    drop(writer);
    // A compaction carries the state on; a dataset without any state resumes with none.
    compact(dir.path()).unwrap();
    let (_, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.state, range_state(1.0), "after a compaction");
    let plain = tempfile::tempdir().unwrap();
    three_batches(plain.path());
    assert_eq!(DatasetWriter::resume(plain.path(), &meta(), false).unwrap().1.state, None);
}

#[test]
fn a_torn_last_journal_line_is_ignored_reported_and_cut_away() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let journal_path = dir.path().join(JOURNAL_FILE);
    let journal = fs::read(&journal_path).unwrap();
    // Power lost mid-append: the last line stops half way, without its newline.
    let torn = &journal[..journal.len() - 40];
    fs::write(&journal_path, torn).unwrap();
    // Readers already skip it, and say so.
    let dataset = Dataset::open(dir.path()).unwrap();
    assert_eq!(dataset.len(), 4);
    assert_eq!(dataset.notes().len(), 1, "{:?}", dataset.notes());
    let (writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.journal_issues.len(), 1);
    assert!(report.journal_issues[0].torn_tail && report.journal_issues[0].line == 3, "{:?}", report.journal_issues);
    assert_eq!(report.committed.len(), 4);
    // Its batch file is now an orphan: quarantined.
    assert_eq!(report.quarantined.iter().map(|q| q.file.as_str()).collect::<Vec<_>>(), ["batch-000002.parquet"]);
    drop(writer);
    // The journal was rewritten without the torn line: the next resume finds nothing to report.
    let text = fs::read_to_string(&journal_path).unwrap();
    assert!(text.ends_with('\n'));
    let (_, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert!(report.journal_issues.is_empty() && report.quarantined.is_empty());
    assert!(Dataset::open(dir.path()).unwrap().notes().is_empty());
}

#[test]
fn a_corrupted_middle_journal_line_drops_only_its_batch() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let journal_path = dir.path().join(JOURNAL_FILE);
    let text = fs::read_to_string(&journal_path).unwrap();
    // Change one digit of the first line's size_bytes: the line's CRC no longer matches.
    let at = text.find("\"size_bytes\":").unwrap() + "\"size_bytes\":".len();
    let mut bytes = text.into_bytes();
    bytes[at] = if bytes[at] == b'9' { b'8' } else { bytes[at] + 1 };
    fs::write(&journal_path, bytes).unwrap();
    let (_, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.journal_issues.len(), 1);
    assert!(!report.journal_issues[0].torn_tail && report.journal_issues[0].reason.contains("crc32"));
    assert_eq!(report.committed, keys(&[(1, 0), (1, 1), (2, 0), (2, 1)]));
    assert_eq!(report.quarantined[0].file, "batch-000000.parquet");
}

#[test]
fn bit_flipped_truncated_and_missing_files_are_quarantined_and_the_rest_verifies() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let before = Dataset::open(dir.path()).unwrap();
    let mut flipped = fs::read(batch(dir.path(), 0)).unwrap();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0x04;
    fs::write(batch(dir.path(), 0), flipped).unwrap();
    let whole = fs::read(batch(dir.path(), 2)).unwrap();
    fs::write(batch(dir.path(), 2), &whole[..whole.len() - 1]).unwrap();
    assert!(matches!(Dataset::open(dir.path()), Err(StoreError::ChecksumMismatch { .. })));

    let (writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.committed, keys(&[(1, 0), (1, 1)]));
    let reasons: Vec<_> = report.quarantined.iter().map(|q| (q.file.as_str(), q.reason.as_str())).collect();
    assert_eq!(reasons.len(), 2, "{reasons:?}");
    assert!(reasons[0].0 == "batch-000000.parquet" && reasons[0].1.contains("corrupt"), "{reasons:?}");
    assert!(reasons[1].0 == "batch-000002.parquet" && reasons[1].1.contains("truncated"), "{reasons:?}");
    drop(writer);
    // What is left verifies, bit for bit.
    let dataset = Dataset::open(dir.path()).unwrap();
    assert_eq!(dataset.len(), 2);
    for actuator in [0, 1] {
        assert_eq!(bits(dataset.ir(1, actuator).unwrap()), bits(before.ir(1, actuator).unwrap()));
        assert!(dataset.ir(0, actuator).is_none() && dataset.ir(2, actuator).is_none());
    }

    // A committed file that vanished: quarantined by name, nothing to move.
    fs::remove_file(batch(dir.path(), 1)).unwrap();
    let (_, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert!(report.committed.is_empty());
    assert_eq!((report.quarantined[0].reason.as_str(), report.quarantined[0].moved_to.is_none()), ("missing", true));
}

#[test]
fn a_full_disk_commits_nothing_loses_nothing_and_resume_continues() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap().with_write_budget(20_000);
    writer.commit_batch(&records(&[(0, 0)], &[0, 1], 512)).unwrap();
    // Each batch is about 9 kB (2 x 512 f32 plus Parquet overhead): the budget runs out within the next two.
    let mut failure = None;
    for point in [(1, 0), (2, 0), (3, 0)] {
        if let Err(e) = writer.commit_batch(&records(&[point], &[0, 1], 512)) {
            failure = Some((point, e));
            break;
        }
    }
    let (point, err) = failure.expect("the budget must run out");
    assert!(matches!(err, StoreError::DiskFull { .. }), "{err}");
    assert!(err.to_string().contains("disk is full"), "{err}");
    // Nothing half-written is left: no temporary, no uncommitted batch file.
    let committed = writer.rows();
    assert!(!names(dir.path()).iter().any(|n| n.ends_with(".tmp")), "{:?}", names(dir.path()));
    assert_eq!(names(&dir.path().join(BATCH_DIR)).len(), committed / 2);
    drop(writer);
    let (mut writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.committed.len(), committed);
    assert!(report.quarantined.is_empty() && report.journal_issues.is_empty(), "{report:?}");
    // Space freed (no budget on the resumed writer): the failed point goes in.
    writer.commit_batch(&records(&[point], &[0, 1], 512)).unwrap();
    drop(writer);
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), committed + 2);
}

#[test]
fn a_full_disk_during_the_journal_append_takes_the_batch_back() {
    // A budget that fits the batch file but not its journal line: found by trying budgets from just below the
    // batch's size upwards.
    let records = records(&[(0, 0)], &[0], 64);
    let probe = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(probe.path(), meta(), IfExists::Refuse).unwrap();
    let size = writer.commit_batch(&records).unwrap().size_bytes;
    drop(writer);
    let journal_line = fs::metadata(probe.path().join(JOURNAL_FILE)).unwrap().len();
    let dir = tempfile::tempdir().unwrap();
    let writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    let mut writer = writer.with_write_budget(size + journal_line - 1);
    let err = writer.commit_batch(&records).unwrap_err();
    assert!(matches!(err, StoreError::DiskFull { ref path, .. } if path.ends_with(JOURNAL_FILE)), "{err}");
    assert!(names(&dir.path().join(BATCH_DIR)).is_empty());
    assert_eq!(fs::metadata(dir.path().join(JOURNAL_FILE)).unwrap().len(), 0);
    assert!(writer.committed_keys().is_empty());
}

#[test]
fn compaction_keeps_every_row_and_a_crash_at_any_step_is_safe() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let before = Dataset::open(dir.path()).unwrap();
    let old: Vec<(PathBuf, Vec<u8>)> =
        (0..3).map(|n| (batch(dir.path(), n), fs::read(batch(dir.path(), n)).unwrap())).collect();

    let report = compact(dir.path()).unwrap();
    assert_eq!(report.file.as_deref(), Some("compacted-000003.parquet"));
    assert_eq!((report.rows, report.superseded.len()), (6, 3));
    assert_eq!(names(&dir.path().join(BATCH_DIR)), ["compacted-000003.parquet"]);
    let after = Dataset::open(dir.path()).unwrap();
    assert_eq!(after.len(), before.len());
    let sorted: Vec<_> = after.rows().iter().map(|m| m.key()).collect();
    assert!(sorted.windows(2).all(|w| w[0] < w[1]), "rows sorted by (point, actuator): {sorted:?}");
    for meta in before.rows() {
        assert_eq!(after.meta(meta.point_index, meta.actuator), Some(meta));
        assert_eq!(
            bits(after.ir(meta.point_index, meta.actuator).unwrap()),
            bits(before.ir(meta.point_index, meta.actuator).unwrap())
        );
    }
    // Crash after the journal line, before the deletions: the old files are back, readers ignore them, resume
    // deletes them.
    for (path, bytes) in &old {
        fs::write(path, bytes).unwrap();
    }
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 6);
    let (writer, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.removed.len(), 3);
    assert_eq!(report.committed.len(), 6);
    drop(writer);
    assert_eq!(names(&dir.path().join(BATCH_DIR)), ["compacted-000003.parquet"]);
    // A single file: nothing to do.
    assert_eq!(compact(dir.path()).unwrap().file, None);
}

#[test]
fn a_compaction_that_never_reached_the_journal_leaves_the_batches_authoritative() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    // As if a crash hit after the compacted file was written: a copy under a compacted name, no journal line.
    fs::copy(batch(dir.path(), 1), dir.path().join(BATCH_DIR).join("compacted-000003.parquet")).unwrap();
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 6);
    let (_, report) = DatasetWriter::resume(dir.path(), &meta(), false).unwrap();
    assert_eq!(report.removed, ["compacted-000003.parquet"]);
    assert_eq!(report.committed.len(), 6);
}

#[test]
fn compaction_refuses_a_locked_or_damaged_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0)], &[0], 8)).unwrap();
    writer.commit_batch(&records(&[(1, 0)], &[0], 8)).unwrap();
    assert!(matches!(compact(dir.path()), Err(StoreError::Locked { .. })));
    drop(writer);
    let mut journal = fs::OpenOptions::new().append(true).open(dir.path().join(JOURNAL_FILE)).unwrap();
    journal.write_all(b"{\"seq\":2,").unwrap();
    assert!(matches!(compact(dir.path()), Err(StoreError::Journal { .. })));
}

#[test]
fn wav_export_round_trips_each_actuator_as_a_channel() {
    let dir = tempfile::tempdir().unwrap();
    three_batches(dir.path());
    let dataset = Dataset::open(dir.path()).unwrap();
    let path = dir.path().join("point1.wav");
    assert_eq!(export_wav(&dataset, 1, &path).unwrap(), [0, 1]);
    let mut reader = hound::WavReader::open(&path).unwrap();
    let spec = reader.spec();
    assert_eq!((spec.channels, spec.sample_rate, spec.bits_per_sample), (2, 24_000, 32));
    assert_eq!(spec.sample_format, hound::SampleFormat::Float);
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    // f32 in, f32 out: bit-exact, interleaved.
    for (channel, actuator) in [0u16, 1].into_iter().enumerate() {
        let got: Vec<f32> = samples.iter().skip(channel).step_by(2).copied().collect();
        assert_eq!(bits(&got), bits(dataset.ir(1, actuator).unwrap()));
    }
    let matrix = dataset.ir_matrix(&[1, 2], &[1, 0]).unwrap();
    assert_eq!(bits(&matrix[32..64]), bits(dataset.ir(1, 0).unwrap()));
    assert_eq!(bits(&matrix[64..96]), bits(dataset.ir(2, 1).unwrap()));
    assert!(matches!(export_wav(&dataset, 11, &path), Err(StoreError::NotInDataset { point_index: 11, .. })));
}

#[test]
fn drive_signals_write_as_float_wav_and_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("drive.wav");
    let drive = [vec![0.5f64, -0.25, 1e-30], vec![0.0, 1.0, -1.0], vec![3.0e38, -3.0e38, 0.125]];
    write_wav_f32(&path, &drive, 48_000.0).unwrap();
    let mut reader = hound::WavReader::open(&path).unwrap();
    assert_eq!((reader.spec().channels, reader.spec().sample_rate), (3, 48_000));
    let samples: Vec<f32> = reader.samples::<f32>().map(Result::unwrap).collect();
    // Written as f32: equal to each f64 rounded to f32.
    let expected: Vec<f32> = (0..3).flat_map(|i| drive.iter().map(move |c| c[i] as f32)).collect();
    assert_eq!(bits(&samples), bits(&expected));
    // Read back: the same f32 values per channel, and the rate.
    let (rate_hz, channels) = read_wav(&path).unwrap();
    assert_eq!(rate_hz, 48_000.0);
    for (read, written) in channels.iter().zip(&drive) {
        let written_f32: Vec<f64> = written.iter().map(|&v| f64::from(v as f32)).collect();
        assert_eq!(read, &written_f32);
    }
    let bad = dir.path().join("bad.wav");
    for (channels, rate) in [
        (vec![vec![0.0f64; 3], vec![0.0; 2]], 48_000.0),
        (vec![vec![f64::NAN]], 48_000.0),
        (vec![vec![1e39]], 48_000.0),
        (vec![vec![0.0]], 44_100.5),
        (vec![vec![0.0]], 0.0),
        (vec![], 48_000.0),
    ] {
        assert!(matches!(write_wav_f32(&bad, &channels, rate), Err(StoreError::Wav { .. })), "{channels:?} {rate}");
        assert!(!bad.exists());
    }
    // Reading: a missing file and a file that is not WAV are errors, not panics.
    assert!(matches!(read_wav(dir.path().join("missing.wav")), Err(StoreError::Io { .. })));
    let junk = dir.path().join("junk.wav");
    std::fs::write(&junk, b"not a wav file").unwrap();
    assert!(matches!(read_wav(&junk), Err(StoreError::Wav { .. })));
}

#[test]
fn integer_wav_reads_scaled_to_full_scale() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("int.wav");
    let spec = hound::WavSpec {
        channels: 2,
        sample_rate: 24_000,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut writer = hound::WavWriter::create(&path, spec).unwrap();
    for v in [16_384i16, -32_768, 0, 8_192] {
        writer.write_sample(v).unwrap();
    }
    writer.finalize().unwrap();
    let (rate_hz, channels) = read_wav(&path).unwrap();
    assert_eq!(rate_hz, 24_000.0);
    assert_eq!(channels, vec![vec![0.5, 0.0], vec![-1.0, 0.25]]);
}

//! Damage to a stopped scan's dataset (a truncated batch file, a flipped bit in another, a torn last journal line)
//! is detected on resume, quarantined with its reason, and just those points are measured again; a full disk
//! stops the scan with a clear error, loses nothing committed, and a resume with space completes it. Either way the
//! final dataset is the uninterrupted run's.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use std::fs::{self, OpenOptions};
use std::path::Path;

use common::{assert_same_rows, image, metamaterial, output, run_scan, small_plan};
use metaplate_recipes::{RecipeError, RunControl, Silent};
use metaplate_store::{BATCH_DIR, Dataset, QUARANTINE_DIR, StoreError};

const POINTS: usize = 6;

/// An uninterrupted run's rows, and its first batch file's size, bytes.
fn uninterrupted() -> (std::collections::BTreeMap<(u32, u16), common::RowImage>, u64) {
    let dir = tempfile::tempdir().unwrap();
    run_scan(&small_plan(POINTS), &output(dir.path(), &metamaterial(), false), &RunControl::new(), &mut Silent)
        .unwrap();
    let size = Dataset::open(dir.path()).unwrap().manifest().batches[0].size_bytes;
    (image(dir.path()), size)
}

/// The batch files of `dir`, sorted (commit order).
fn batch_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = fs::read_dir(dir.join(BATCH_DIR)).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    files
}

#[test]
fn damaged_files_and_a_torn_journal_are_quarantined_and_just_their_points_measured_again() {
    let scene = metamaterial();
    let plan = small_plan(POINTS);
    let (reference, _) = uninterrupted();
    let dir = tempfile::tempdir().unwrap();
    let control = RunControl::new();
    control.stop_after_commits(3);
    let err = run_scan(&plan, &output(dir.path(), &scene, false), &control, &mut Silent).unwrap_err();
    // Stopped after the 3rd commit; the point in flight is finished too.
    assert!(matches!(err, RecipeError::Interrupted { committed: 4 }), "{err}");
    let files = batch_files(dir.path());
    assert_eq!(files.len(), 4, "one batch per point");

    // Truncate the first batch by 100 bytes, flip one bit in the middle of the third.
    let first = OpenOptions::new().write(true).open(&files[0]).unwrap();
    first.set_len(first.metadata().unwrap().len() - 100).unwrap();
    let mut bytes = fs::read(&files[2]).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x10;
    fs::write(&files[2], bytes).unwrap();
    // Tear the journal's last line (the fourth batch's entry) as a crash in its append would: its file becomes an
    // orphan that the journal never committed.
    let journal = dir.path().join("journal.jsonl");
    let text = fs::read(&journal).unwrap();
    fs::write(&journal, &text[..text.len() - 20]).unwrap();

    let summary = run_scan(&plan, &output(dir.path(), &scene, true), &RunControl::new(), &mut Silent).unwrap();
    // Three points lost their batch (truncated, corrupt, orphaned) and two were never measured: five measured now.
    assert_eq!((summary.committed_now, summary.committed), (POINTS - 1, POINTS), "{summary:?}");
    // The quarantine holds the three files, each with a reason naming what was wrong.
    let notes = fs::read_to_string(dir.path().join(QUARANTINE_DIR).join("notes.jsonl")).unwrap();
    let notes: Vec<serde_json::Value> = notes.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let name = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
    for (file, word) in [(&files[0], "truncated"), (&files[2], "checksum"), (&files[3], "journal")] {
        let note = notes.iter().find(|n| n["file"] == name(file)).unwrap_or_else(|| panic!("{file:?}: {notes:?}"));
        let reason = note["reason"].as_str().unwrap().to_lowercase();
        eprintln!("{}: {reason}", name(file));
        assert!(reason.contains(word), "{file:?}: reason `{reason}`");
        assert!(dir.path().join(QUARANTINE_DIR).join(name(file)).exists(), "{file:?} moved, not deleted");
    }
    assert_eq!(notes.len(), 3, "{notes:?}");
    assert_same_rows(&reference, &image(dir.path()), "repaired vs uninterrupted");
}

#[test]
fn a_full_disk_stops_the_scan_clearly_and_a_resume_with_space_completes_it() {
    let scene = metamaterial();
    let plan = small_plan(POINTS);
    let (reference, batch_bytes) = uninterrupted();
    let dir = tempfile::tempdir().unwrap();
    // Room for the manifest, two batches and their journal lines, not three: 2.5 batches (the manifest and a
    // journal line are a few kilobytes, a batch of 8 responses of 12000 f32 samples some 390 kB).
    let control = RunControl::new();
    control.limit_writes(batch_bytes * 5 / 2);
    let err = run_scan(&plan, &output(dir.path(), &scene, false), &control, &mut Silent).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, RecipeError::Store(StoreError::DiskFull { .. })), "{message}");
    assert!(message.contains("disk is full") && message.contains("resume"), "says what and what to do: {message}");

    // Nothing committed before is lost: the two points are there, as the uninterrupted run measured them.
    let partial = image(dir.path());
    assert_eq!(partial.len(), 2 * scene.actuators.len(), "two points committed before the disk filled");
    let before: std::collections::BTreeMap<_, _> =
        reference.iter().filter(|(k, _)| partial.contains_key(k)).map(|(k, v)| (*k, v.clone())).collect();
    assert_same_rows(&before, &partial, "committed before the full disk");

    let summary = run_scan(&plan, &output(dir.path(), &scene, true), &RunControl::new(), &mut Silent).unwrap();
    assert_eq!((summary.committed_now, summary.committed), (POINTS - 2, POINTS));
    assert_same_rows(&reference, &image(dir.path()), "resumed after a full disk vs uninterrupted");
}

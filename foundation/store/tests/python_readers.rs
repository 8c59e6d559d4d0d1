//! Polars and pyarrow read a dataset as it is, with no code of ours: `tests/python/read_dataset.py` checks row
//! counts, column names and types, and a known impulse response. Needs a Python with polars and pyarrow:
//! `$METAPLATE_PYTHON`, else the project's `.venv/bin/python` that `scripts/install-deps.sh` makes (`.ci/run`
//! installs it and then runs this test explicitly).

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use std::process::Command;

use common::{meta, records};
use metaplate_store::{Dataset, DatasetWriter, IfExists, compact};

#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with polars and pyarrow: run by .ci/run"]
fn polars_and_pyarrow_read_the_committed_files() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0), (1, 0)], &[0, 3], 100)).unwrap();
    writer.commit_batch(&records(&[(2, 1)], &[0, 3], 100)).unwrap();
    drop(writer);
    // An orphan (never journaled) that a directory glob would pick up, but the journal excludes.
    std::fs::copy(dir.path().join("batches/batch-000000.parquet"), dir.path().join("batches/batch-000009.parquet"))
        .unwrap();
    let dataset = Dataset::open(dir.path()).unwrap();
    let ir = dataset.ir(6, 3).unwrap();
    // Python floats are f64; an f32 widens exactly, so the comparison in the script is exact.
    let head: Vec<f64> = ir[..8].iter().map(|&v| f64::from(v)).collect();
    let expected = serde_json::json!({"rows": 6, "ir_len": 100, "point_index": 6, "actuator": 3, "ir_head": head});
    let expected_path = dir.path().join("expected.json");
    std::fs::write(&expected_path, expected.to_string()).unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_dataset.py");
    let run = |what: &str| {
        let out = Command::new(python()).arg(script).arg(dir.path()).arg(&expected_path).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{what}: {stdout}{}", String::from_utf8_lossy(&out.stderr));
    };
    run("after commits");
    compact(dir.path()).unwrap();
    run("after compaction");
}

/// The interpreter with the cross-check packages: `$METAPLATE_PYTHON`, else the workspace's `.venv`.
fn python() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("METAPLATE_PYTHON") {
        return p.into();
    }
    let venv = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(venv.exists(), "no {} and no METAPLATE_PYTHON: run scripts/install-deps.sh", venv.display());
    venv
}

/// `Dataset::lazy` scans exactly the committed files, in the dataset's columns.
#[cfg(feature = "polars")]
#[test]
fn the_polars_lazy_frame_reads_the_committed_rows() {
    use polars::prelude::{DataType, col, lit};
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0), (1, 0)], &[0, 3], 50)).unwrap();
    writer.commit_batch(&records(&[(2, 1)], &[0, 3], 50)).unwrap();
    drop(writer);
    // An orphan that must not be scanned.
    std::fs::copy(dir.path().join("batches/batch-000000.parquet"), dir.path().join("batches/batch-000009.parquet"))
        .unwrap();
    let frame = Dataset::lazy(dir.path()).unwrap().collect().unwrap();
    assert_eq!(frame.height(), 6);
    let schema = frame.schema();
    assert_eq!(schema.get("point_index"), Some(&DataType::UInt32));
    assert_eq!(schema.get("ir"), Some(&DataType::List(Box::new(DataType::Float32))));
    let one = Dataset::lazy(dir.path())
        .unwrap()
        .filter(col("point_index").eq(lit(6u32)).and(col("actuator").eq(lit(3u16))))
        .collect()
        .unwrap();
    assert_eq!(one.height(), 1);
}

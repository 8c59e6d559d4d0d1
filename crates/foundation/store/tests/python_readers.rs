//! Polars and pyarrow read a dataset as it is, with no code of ours: `tests/python/read_dataset.py` checks row
//! counts, column names and types, and a known impulse response. Needs a Python with polars and pyarrow:
//! `$METAPLATE_PYTHON`, else the project's `.venv/bin/python` that `scripts/install-deps.sh` makes (`.ci/run`
//! installs it and then runs this test explicitly).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::process::Command;

use common::{meta, records};
use metaplate_store::{Dataset, DatasetDescription, DatasetMeta, DatasetWriter, IR_UNIT_M_S_PER_N, IfExists, compact};

/// The test dataset's metadata, with its description (what the batch files' key-value metadata states).
fn described_meta() -> DatasetMeta {
    meta().with_description(DatasetDescription { ir_unit: IR_UNIT_M_S_PER_N.into(), pre_samples: 0 })
}

/// A dataset of 3 points x 2 actuators in two batch files, with an orphan file the journal does not list.
fn dataset(dir: &std::path::Path) {
    let mut writer = DatasetWriter::create(dir, described_meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0), (1, 0)], &[0, 3], 100)).unwrap();
    writer.commit_batch(&records(&[(2, 1)], &[0, 3], 100)).unwrap();
    drop(writer);
    // An orphan (never journaled) that a directory glob would pick up, but the journal excludes.
    std::fs::copy(dir.join("batches/batch-000000.parquet"), dir.join("batches/batch-000009.parquet")).unwrap();
}

#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with polars and pyarrow: run by .ci/run"]
fn polars_and_pyarrow_read_the_committed_files() {
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    let dataset = Dataset::open(dir.path()).unwrap();
    let ir = dataset.ir(6, 3).unwrap();
    // Python floats are f64; an f32 widens exactly, so the comparison in the script is exact.
    let head: Vec<f64> = ir[..8].iter().map(|&v| f64::from(v)).collect();
    let meta = described_meta();
    let file_metadata = serde_json::json!({
        "metaplate.recipe": meta.recipe,
        "metaplate.scene": meta.scene.name,
        "metaplate.scene_hash": meta.scene.hash,
        "metaplate.grid": {"nx": 4, "ny": 3, "spacing_m": 0.005, "origin_x_m": -0.0075, "origin_y_m": -0.005},
        "metaplate.sample_rate_hz": "24000",
        "metaplate.ir_unit": "m/s/N",
        "metaplate.pre_samples": "0",
        "metaplate.software_version": meta.software_version,
        "metaplate.schema_version": "1",
        "metaplate.seed": "7",
    });
    let expected = serde_json::json!({"rows": 6, "ir_len": 100, "point_index": 6, "actuator": 3, "ir_head": head,
        "file_metadata": file_metadata});
    let expected_path = dir.path().join("expected.json");
    std::fs::write(&expected_path, expected.to_string()).unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_dataset.py");
    let run = |what: &str| {
        let out = Command::new(metaplate_fixtures::python())
            .arg(script)
            .arg(dir.path())
            .arg(&expected_path)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{what}: {stdout}{}", String::from_utf8_lossy(&out.stderr));
    };
    run("after commits");
    compact(dir.path()).unwrap();
    run("after compaction");
}

/// The README's reading example (between its `reading-example` markers), run on a dataset with an orphan file: it
/// reads only the committed files, in polars and pyarrow, and its G[point, actuator, t] holds every response where
/// it belongs.
#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with polars, pyarrow and numpy: run by .ci/run"]
fn the_readme_reading_example_runs() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../README.md")).unwrap();
    let start = readme.find("<!-- reading-example:start -->").expect("README lacks the reading-example markers");
    let end = readme.find("<!-- reading-example:end -->").unwrap();
    let block = &readme[start..end];
    let code = block.split("```python").nth(1).and_then(|b| b.split("```").next()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    dataset(dir.path());
    let dataset = Dataset::open(dir.path()).unwrap();
    // The script sees its dataset where the README's `run = Path(...)` line points.
    let code = code
        .lines()
        .map(|l| if l.starts_with("run = Path(") { format!("run = Path({:?})", dir.path()) } else { l.to_owned() })
        .collect::<Vec<_>>()
        .join("\n");
    let (points, actuators) = (dataset.points().to_vec(), dataset.actuators().to_vec());
    let expected = dataset.ir_matrix(&points, &actuators).unwrap();
    let checks = format!(
        "\nassert G.shape == ({}, {}, {}), G.shape\nassert G_pa.shape == G.shape\n\
         assert G.ravel().tolist() == {:?}\nassert (G == G_pa).all()\nassert meta['metaplate.ir_unit'] == 'm/s/N'\n\
         print('ok')\n",
        points.len(),
        actuators.len(),
        dataset.ir_len(),
        expected.iter().map(|&v| f64::from(v)).collect::<Vec<_>>(),
    );
    let script = dir.path().join("example.py");
    std::fs::write(&script, code + &checks).unwrap();
    let out = Command::new(metaplate_fixtures::python()).arg(&script).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && stdout.contains("ok"), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
}

/// A dataset of two committed batches (6 rows of 50 samples), and a copy of the first that no journal entry names
/// (an orphan, which no reader must take).
fn two_batches_and_an_orphan() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = DatasetWriter::create(dir.path(), meta(), IfExists::Refuse).unwrap();
    writer.commit_batch(&records(&[(0, 0), (1, 0)], &[0, 3], 50)).unwrap();
    writer.commit_batch(&records(&[(2, 1)], &[0, 3], 50)).unwrap();
    drop(writer);
    std::fs::copy(dir.path().join("batches/batch-000000.parquet"), dir.path().join("batches/batch-000009.parquet"))
        .unwrap();
    dir
}

/// `Dataset::committed_files` lists exactly the committed files, in commit order.
#[test]
fn the_committed_files_are_the_journaled_ones() {
    let dir = two_batches_and_an_orphan();
    let files = Dataset::committed_files(dir.path()).unwrap();
    let names: Vec<String> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["batch-000000.parquet", "batch-000001.parquet"]);
    let empty = tempfile::tempdir().unwrap();
    drop(DatasetWriter::create(empty.path(), meta(), IfExists::Refuse).unwrap());
    assert!(matches!(Dataset::committed_files(empty.path()), Err(metaplate_store::StoreError::EmptyDataset { .. })));
}

/// `Dataset::dataframe` holds exactly the committed rows, verified, in the dataset's columns, and only the columns
/// asked for.
#[cfg(feature = "polars")]
#[test]
fn the_polars_dataframe_holds_the_committed_rows() {
    use polars_core::prelude::{ChunkCompareEq, DataType, TimeUnit, TimeZone};
    let dir = two_batches_and_an_orphan();
    let frame = Dataset::dataframe(dir.path(), None).unwrap();
    // Two committed batches of three rows; the orphan batch's rows are not read.
    assert_eq!(frame.height(), 6);
    let schema = frame.schema();
    assert_eq!(schema.get("point_index"), Some(&DataType::UInt32));
    assert_eq!(schema.get("actuator"), Some(&DataType::UInt16));
    assert_eq!(schema.get("ir"), Some(&DataType::Array(Box::new(DataType::Float32), 50)));
    assert!(matches!(schema.get("measured_at"), Some(DataType::Datetime(..))), "{:?}", schema.get("measured_at"));
    let point = frame.column("point_index").unwrap().u32().unwrap();
    let actuator = frame.column("actuator").unwrap().u16().unwrap();
    let one = frame.filter(&(point.equal(6) & actuator.equal(3))).unwrap();
    assert_eq!(one.height(), 1);

    let small = Dataset::dataframe(dir.path(), Some(&["actuator", "point_index"])).unwrap();
    assert_eq!(small.get_column_names(), ["actuator", "point_index"]);
    assert_eq!(small.height(), 6);
    let unknown = Dataset::dataframe(dir.path(), Some(&["no_such_column"])).unwrap_err();
    assert!(matches!(unknown, metaplate_store::StoreError::Polars { .. }), "{unknown}");

    // The values are the dataset's: a response as the reader reads it, the times in µs, UTC.
    let dataset = Dataset::open(dir.path()).unwrap();
    let ir = one.column("ir").unwrap().array().unwrap().get_as_series(0).unwrap();
    let values: Vec<f32> = ir.f32().unwrap().into_no_null_iter().collect();
    assert_eq!(values, dataset.ir(6, 3).unwrap());
    assert_eq!(schema.get("measured_at"), Some(&DataType::Datetime(TimeUnit::Microseconds, Some(TimeZone::UTC))));
    let times: Vec<Option<i64>> = frame.column("measured_at").unwrap().datetime().unwrap().physical().iter().collect();
    assert_eq!(times, dataset.rows().iter().map(|r| r.measured_at_unix_us).collect::<Vec<_>>());

    // Read and verified as `Dataset::open` reads: a committed file damaged in place is refused, not read.
    let batch = dir.path().join("batches/batch-000001.parquet");
    let mut bytes = std::fs::read(&batch).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x01;
    std::fs::write(&batch, bytes).unwrap();
    let damaged = Dataset::dataframe(dir.path(), Some(&["point_index"])).unwrap_err();
    assert!(matches!(damaged, metaplate_store::StoreError::ChecksumMismatch { .. }), "{damaged}");
}

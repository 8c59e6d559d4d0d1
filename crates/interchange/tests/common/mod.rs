//! A small dataset written through the store, and the export and import calls the tests make.

#![allow(clippy::unwrap_used)] // Helpers of tests: a failure is the test failing.

use std::path::{Path, PathBuf};

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::Scene;
use metaplate_interchange::{ExportOptions, ImportOptions, ImportSummary, InterchangeError, Progress};
use metaplate_store::{Dataset, DatasetDescription, DatasetMeta, DatasetWriter, IfExists, IrMeta, IrRecord, Status};
use metaplate_uff::{Format, Precision, UffDecoder, UffEncoder, UffRecord};

/// Responses of this many samples.
pub const IR_LEN: usize = 64;
/// Their sample rate, Hz.
pub const RATE_HZ: f64 = 24_000.0;

/// The built-in metamaterial scene (its id in the dataset: export finds the actuators' positions by it).
pub fn scene() -> Scene {
    Scene::builtin("metamaterial").unwrap()
}

/// A 4 x 3 dataset of `actuators` actuators in `dir`: decaying, deterministic responses with a quality on every row,
/// `pre_samples` before time 0 and `ir_unit` as its description says.
/// The content hash of the calibration [`dataset`]'s scan names.
pub const CALIBRATION: &str = "sha256:5d41402abc4b2a76b9719d911017c592aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa";

/// The unit of a scan through a calibration (as the recipes write it).
pub const SCAN_UNIT: &str = "m/s per full-scale drive, through the calibration's inverse filters";

pub fn dataset(dir: &Path, actuators: u16, pre_samples: u32, ir_unit: &str) -> PathBuf {
    let grid = GridSpec::centred(4, 3, 0.005);
    // A scan's configuration names the calibration it was measured through.
    let config = serde_json::json!({"synthetic": true, "calibration": CALIBRATION}).as_object().cloned().unwrap();
    let meta = DatasetMeta::new("scan", config, scene().id(), "test", 7, grid)
        .with_description(DatasetDescription { ir_unit: ir_unit.into(), pre_samples });
    let data = dir.join("original");
    let mut writer = DatasetWriter::create(&data, meta, IfExists::Refuse).unwrap();
    for point in 0..grid.len() {
        let (ix, iy) = grid.indices(point);
        let rows: Vec<IrRecord> = (0..actuators)
            .map(|actuator| {
                let mut meta = IrMeta::at_grid(&grid, ix as u32, iy as u32, actuator, RATE_HZ).unwrap();
                meta.status = Some(if point % 5 == 1 { Status::ReMeasured } else { Status::Valid });
                meta.snr_db = Some(40.0 + point as f64 + 0.25 * f64::from(actuator));
                meta.retries = Some(u32::from(point % 5 == 1));
                // A long SNR with every other field: up to 0.6 ID line 4 was cut at 80 columns and lost the time.
                if point % 5 == 1 {
                    meta.snr_db = Some(-123.456_789_012_345_67);
                }
                meta.measured_at_unix_us = Some(1_700_000_000_000_000 + point as i64);
                meta.estimated_error_db = (actuator == 0).then_some(-30.5);
                let seed = (point * 7 + usize::from(actuator) * 13) as f32;
                let ir =
                    (0..IR_LEN).map(|i| ((i as f32 + seed) * 0.7).sin() * (-(i as f32) / 12.0).exp() * 1e-3).collect();
                IrRecord { meta, ir }
            })
            .collect();
        writer.commit_batch(&rows).unwrap();
    }
    writer.finish().unwrap();
    data
}

/// The actuators' positions of the scene.
pub fn sites() -> Vec<(f64, f64)> {
    scene().actuators.iter().map(|a| (a.x_m, a.y_m)).collect()
}

/// Exports `data` to `out`; returns the progress reports seen.
pub fn export(data: &Path, out: &Path, options: &ExportOptions) -> Result<Vec<Progress>, InterchangeError> {
    let mut seen = Vec::new();
    metaplate_interchange::export(data, out, options, &sites(), |p| seen.push(p))?;
    Ok(seen)
}

/// Imports `files` into `out`.
pub fn import(files: &[PathBuf], out: &Path, options: ImportOptions) -> Result<ImportSummary, InterchangeError> {
    metaplate_interchange::import(files, out, options, |_| {})
}

/// The options of a binary export in double precision, time responses only.
pub fn binary_double() -> ExportOptions {
    ExportOptions {
        format: Format::Binary { byte_order: metaplate_uff::ByteOrder::LittleEndian },
        precision: Precision::Double,
        frequency: false,
        points: None,
    }
}

/// `from`'s records that `keep` keeps, written to `to` in `format` and `precision`.
pub fn rewrite(
    from: &Path,
    to: &Path,
    format: Format,
    precision: Precision,
    mut keep: impl FnMut(&mut UffRecord) -> bool,
) {
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(from).unwrap());
    decoder.finish();
    let encoder = UffEncoder::new(format, precision);
    let mut out = Vec::new();
    for record in decoder.records() {
        let mut record = record.unwrap();
        if keep(&mut record) {
            encoder.encode(&record, &mut out).unwrap();
        }
    }
    std::fs::write(to, out).unwrap();
}

/// The nodes of dataset 2411 in the universal file `path`: label -> position.
pub fn decode_nodes(path: &Path) -> std::collections::HashMap<u32, [f64; 3]> {
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(path).unwrap());
    decoder.finish();
    decoder
        .records()
        .filter_map(|r| if let Ok(UffRecord::Nodes(n)) = r { Some(n.nodes) } else { None })
        .flatten()
        .map(|n| (n.label, n.position_m))
        .collect()
}

/// Asserts that `imported` holds `original`'s rows: keys, responses within `rel` of each response's peak, positions
/// and quality exactly.
pub fn assert_same(original: &Dataset, imported: &Dataset, rel: f64, what: &str) {
    assert_eq!(imported.len(), original.len(), "{what}");
    for meta in original.rows() {
        let (p, a) = meta.key();
        let want = original.ir(p, a).unwrap();
        let got = imported.ir(p, a).unwrap_or_else(|| panic!("{what}: point {p} actuator {a} missing"));
        assert_eq!(got.len(), want.len(), "{what}");
        let peak = want.iter().fold(0.0f64, |m, &v| m.max(f64::from(v).abs()));
        let worst = want.iter().zip(got).map(|(&w, &g)| (f64::from(w) - f64::from(g)).abs()).fold(0.0, f64::max);
        assert!(worst <= rel * peak, "{what}: point {p} actuator {a}: error {worst:e} of peak {peak:e}");
        let m = imported.meta(p, a).unwrap();
        assert_eq!((m.x_m, m.y_m, m.sample_rate_hz), (meta.x_m, meta.y_m, meta.sample_rate_hz), "{what}");
    }
}

/// The error's message with its causes after colons, as the binary prints it.
pub fn message(error: &InterchangeError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        text.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    text
}

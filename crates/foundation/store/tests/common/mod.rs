//! Shared fixtures of the store's integration tests.

#![allow(dead_code)] // Each test binary uses a different part.

use metaplate_store::{DatasetMeta, GridSpec, IrMeta, IrRecord, SceneId, Status};

/// A 4 x 3 grid, 5 mm apart, centred.
pub fn grid() -> GridSpec {
    GridSpec::centred(4, 3, 0.005)
}

/// Metadata of a small simulated dataset on [`grid`].
pub fn meta() -> DatasetMeta {
    let config = serde_json::json!({"band_hz": [62.0, 625.0], "ir_len": 16, "plate": "acrylic-1.5mm"});
    DatasetMeta::new(
        "simulate-greens",
        config.as_object().cloned().unwrap_or_default(),
        SceneId { name: "acrylic".into(), hash: metaplate_store::sha256(b"scene") },
        "0.1.0-test",
        7,
        grid(),
    )
}

/// A deterministic, non-trivial IR for (point, actuator): distinct per pair, with values of many magnitudes.
pub fn ir(point_index: u32, actuator: u16, len: usize) -> Vec<f32> {
    (0..len).map(|i| ((i as f32 + 1.0) * 0.37 + point_index as f32).sin() * 10f32.powi(actuator as i32 - 3)).collect()
}

/// Records for the given grid points and actuators, each point's quality fields filled differently.
pub fn records(points: &[(u32, u32)], actuators: &[u16], len: usize) -> Vec<IrRecord> {
    let grid = grid();
    let mut out = Vec::new();
    for &(ix, iy) in points {
        for &actuator in actuators {
            let mut meta = IrMeta::at_grid(&grid, ix, iy, actuator, 24_000.0).unwrap();
            if (ix + iy) % 2 == 0 {
                meta.snr_db = Some(30.0 + f64::from(ix));
                meta.estimated_error_db = Some(-30.0 - f64::from(ix));
                meta.status = Some(Status::Valid);
                meta.retries = Some(iy);
                meta.measured_at_unix_us = Some(1_767_225_600_000_000 + i64::from(ix));
            } else {
                meta.status = Some(Status::GroundTruth);
            }
            out.push(IrRecord { ir: ir(meta.point_index, actuator, len), meta });
        }
    }
    out
}

/// Bit patterns of an IR, to compare exactly (including -0.0 and subnormals).
pub fn bits(ir: &[f32]) -> Vec<u32> {
    ir.iter().map(|v| v.to_bits()).collect()
}

//! A band diagram's points as Parquet (`metaplate design band --parquet`): one row per branch point, the design's
//! name in the file's metadata (`metaplate.design`).

use std::path::Path;
use std::sync::Arc;

use arrow_array::{ArrayRef, Float64Array, RecordBatch, UInt32Array};
use arrow_schema::{DataType, Field, Schema};
use metaplate_store::StoreError;

use crate::band::{BandDiagram, BranchPoint};

/// Writes every branch point of `band` to `path`, durably: mode, path index and position, wave vector, frequency,
/// phase velocity, wavelength, plate energy share (phase velocity and wavelength null at Gamma).
///
/// # Errors
/// [`StoreError`] when the file cannot be encoded or written.
pub fn write_parquet(path: &Path, band: &BandDiagram) -> Result<(), StoreError> {
    let points = || band.branches.iter().flat_map(|b| b.points.iter().map(move |p| (b.mode, p)));
    let f64s = |f: &dyn Fn(&BranchPoint) -> f64| -> ArrayRef {
        Arc::new(Float64Array::from(points().map(|(_, p)| f(p)).collect::<Vec<_>>()))
    };
    let optional = |f: &dyn Fn(&BranchPoint) -> Option<f64>| -> ArrayRef {
        Arc::new(Float64Array::from(points().map(|(_, p)| f(p)).collect::<Vec<_>>()))
    };
    // Modes and path indices are small (at most the options' counts): saturating is never reached.
    let u32s = |v: Vec<usize>| -> ArrayRef {
        Arc::new(UInt32Array::from(v.into_iter().map(|i| u32::try_from(i).unwrap_or(u32::MAX)).collect::<Vec<_>>()))
    };
    let position = |i: usize| band.path.get(i).map_or(f64::NAN, |p| p.path_position);
    let schema = Arc::new(Schema::new(vec![
        Field::new("mode", DataType::UInt32, false),
        Field::new("path_index", DataType::UInt32, false),
        Field::new("path_position", DataType::Float64, false),
        Field::new("kx_rad_m", DataType::Float64, false),
        Field::new("ky_rad_m", DataType::Float64, false),
        Field::new("freq_hz", DataType::Float64, false),
        Field::new("phase_velocity_m_s", DataType::Float64, true),
        Field::new("wavelength_m", DataType::Float64, true),
        Field::new("plate_energy_share", DataType::Float64, false),
    ]));
    let columns = vec![
        u32s(points().map(|(m, _)| m).collect()),
        u32s(points().map(|(_, p)| p.path_index).collect()),
        f64s(&|p| position(p.path_index)),
        f64s(&|p| p.kx_rad_m),
        f64s(&|p| p.ky_rad_m),
        f64s(&|p| p.freq_hz),
        optional(&|p| p.phase_velocity_m_s),
        optional(&|p| p.wavelength_m),
        f64s(&|p| p.plate_energy_share),
    ];
    let batch = RecordBatch::try_new(schema, columns)
        .map_err(|source| StoreError::Arrow { file: path.display().to_string(), source })?;
    metaplate_store::write_table(path, &batch, &[("metaplate.design", &band.design)])
}

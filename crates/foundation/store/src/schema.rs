//! The columns of a batch file: one row per (grid point, actuator) impulse response.
//!
//! The schema is plain Arrow/Parquet so that pyarrow, polars and pandas read a batch file without our code. Each field
//! carries its unit in the field metadata under the key `"unit"` (dimensionless columns carry none).
//!
//! | column | type | nullable | meaning |
//! |---|---|---|---|
//! | `point_index` | u32 | no | grid point index, `iy * nx + ix` |
//! | `ix`, `iy` | u32 | no | grid column and row |
//! | `x_m`, `y_m` | f64 | no | where the response was taken, m (plate coordinates) |
//! | `actuator` | u16 | no | actuator number (audio interface channel, 0-based) |
//! | `sample_rate_hz` | f64 | no | sample rate of `ir`, Hz; the same for every row of a dataset |
//! | `ir` | fixed-size list of f32 (one size per dataset; files written before it existed hold a list) | no | impulse response, output per unit input (a scan: surface velocity in m/s per full-scale drive; the key-value metadata's `metaplate.ir_unit` and the manifest's `description` say) |
//! | `snr_db` | f64 | yes | signal-to-noise ratio of the measurement, dB |
//! | `status` | utf8 | yes | quality flag, one of [`Status`] |
//! | `retries` | u32 | yes | how many times the point was re-measured |
//! | `measured_at` | timestamp (µs, UTC) | yes | when the response was measured |
//! | `kind` | utf8 | yes | what a row of a calibration dataset is, one of [`RowKind`] (`filter`, `response`, `verification`); null elsewhere. Optional when reading: files written before it existed lack the column |
//! | `estimated_error_db` | f64 | yes | the response's estimated error against the truth over 80..600 Hz, dB (relative error energy, as the mock lab's truth comparisons measure it), from the spread of the repetitions or shots: the noise's part of the error; null where nothing estimates it (one period per shot, a simulation, a calibration). Optional when reading: files written before it existed lack the column |
//!
//! Every batch file also carries file-level key-value metadata ([`file_metadata`]), so that one file read alone says
//! what it holds (polars and pyarrow keep these, where polars drops the fields' metadata): `metaplate.recipe`,
//! `metaplate.scene` and `metaplate.scene_hash`, `metaplate.grid` (the grid as JSON: `nx`, `ny`, `spacing_m`,
//! `origin_x_m`, `origin_y_m`), `metaplate.sample_rate_hz`, `metaplate.ir_unit` (`unstated` for a dataset without a
//! [`DatasetDescription`]), `metaplate.pre_samples` (empty when unstated), `metaplate.software_version`,
//! `metaplate.schema_version` and `metaplate.seed`.

use std::collections::HashMap;
use std::sync::Arc;

use arrow_schema::{DataType, Field, Schema, SchemaRef, TimeUnit};
use parquet::file::metadata::KeyValue;

use crate::manifest::{DatasetDescription, DatasetMeta};

/// Column `point_index`: grid point index `iy * nx + ix` (u32).
pub const POINT_INDEX: &str = "point_index";
/// Column `ix`: grid column, 0-based (u32).
pub const IX: &str = "ix";
/// Column `iy`: grid row, 0-based (u32).
pub const IY: &str = "iy";
/// Column `x_m`: x position of the point, m (f64).
pub const X_M: &str = "x_m";
/// Column `y_m`: y position of the point, m (f64).
pub const Y_M: &str = "y_m";
/// Column `actuator`: actuator number, 0-based (u16).
pub const ACTUATOR: &str = "actuator";
/// Column `sample_rate_hz`: sample rate of `ir`, Hz (f64).
pub const SAMPLE_RATE_HZ: &str = "sample_rate_hz";
/// Column `ir`: the impulse response (list of f32).
pub const IR: &str = "ir";
/// Column `snr_db`: signal-to-noise ratio, dB (f64, nullable).
pub const SNR_DB: &str = "snr_db";
/// Column `status`: quality flag (utf8, nullable; see [`Status`]).
pub const STATUS: &str = "status";
/// Column `retries`: re-measurements of the point (u32, nullable).
pub const RETRIES: &str = "retries";
/// Column `measured_at`: measurement time (timestamp in µs since the Unix epoch, UTC; nullable).
pub const MEASURED_AT: &str = "measured_at";
/// Column `kind`: what a calibration row is (utf8, nullable; see [`RowKind`]).
pub const KIND: &str = "kind";
/// Column `estimated_error_db`: the response's estimated error over 80..600 Hz, dB (f64, nullable).
pub const ESTIMATED_ERROR_DB: &str = "estimated_error_db";

/// What a row of a calibration dataset holds (column `kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RowKind {
    /// An inverse filter's taps.
    Filter,
    /// A measured response.
    Response,
    /// A verification response, measured through the filter.
    Verification,
}

impl RowKind {
    /// Every kind, in the order of the enum.
    pub const ALL: [RowKind; 3] = [RowKind::Filter, RowKind::Response, RowKind::Verification];

    /// The string stored in the `kind` column.
    pub fn as_str(self) -> &'static str {
        match self {
            RowKind::Filter => "filter",
            RowKind::Response => "response",
            RowKind::Verification => "verification",
        }
    }

    /// Parses a `kind` column string; `None` if it is not one of [`RowKind::as_str`]'s values.
    pub fn parse(s: &str) -> Option<RowKind> {
        RowKind::ALL.into_iter().find(|kind| kind.as_str() == s)
    }
}

/// Name of the list items of the `ir` column (Arrow's default for a list).
const IR_ITEM: &str = "item";

/// Quality flag of one impulse response.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// Measured, and within every quality limit.
    Valid,
    /// Measured again after a failed first attempt, and now valid.
    ReMeasured,
    /// The vibrometer or the DAQ clipped.
    Overrange,
    /// The signal dropped out (laser speckle, lost samples).
    Dropout,
    /// Every attempt failed; the response is kept only for diagnosis.
    Failed,
    /// Computed by the simulated plate, not measured.
    GroundTruth,
}

impl Status {
    /// Every status, in the order of the enum.
    pub const ALL: [Status; 6] =
        [Status::Valid, Status::ReMeasured, Status::Overrange, Status::Dropout, Status::Failed, Status::GroundTruth];

    /// The string stored in the `status` column.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Valid => "valid",
            Status::ReMeasured => "re-measured",
            Status::Overrange => "overrange",
            Status::Dropout => "dropout",
            Status::Failed => "failed",
            Status::GroundTruth => "ground-truth",
        }
    }

    /// Parses a `status` column string; `None` if it is not one of [`Status::as_str`]'s values.
    pub fn parse(s: &str) -> Option<Status> {
        Status::ALL.into_iter().find(|status| status.as_str() == s)
    }
}

/// A field with its unit in the metadata (none for dimensionless columns).
fn field(name: &str, data_type: DataType, nullable: bool, unit: Option<&str>) -> Field {
    let field = Field::new(name, data_type, nullable);
    match unit {
        Some(unit) => field.with_metadata(HashMap::from([("unit".to_string(), unit.to_string())])),
        None => field,
    }
}

/// The item field of the `ir` list: f32 samples, never null.
pub(crate) fn ir_item_field() -> Field {
    Field::new(IR_ITEM, DataType::Float32, false)
}

/// Time zone of the `measured_at` column.
pub(crate) const MEASURED_AT_TZ: &str = "UTC";

/// The Arrow schema of a batch file whose responses are `ir_len` samples long (see the module documentation for
/// each column's meaning and unit): `ir` is a fixed-size list, which polars reads as an Array and NumPy as a 2-D
/// array without copies.
pub fn arrow_schema(ir_len: i32) -> SchemaRef {
    Arc::new(Schema::new(vec![
        field(POINT_INDEX, DataType::UInt32, false, None),
        field(IX, DataType::UInt32, false, None),
        field(IY, DataType::UInt32, false, None),
        field(X_M, DataType::Float64, false, Some("m")),
        field(Y_M, DataType::Float64, false, Some("m")),
        field(ACTUATOR, DataType::UInt16, false, None),
        field(SAMPLE_RATE_HZ, DataType::Float64, false, Some("Hz")),
        // No field unit: the file's key-value metadata states it (`metaplate.ir_unit`).
        field(IR, DataType::FixedSizeList(Arc::new(ir_item_field()), ir_len), false, None),
        field(SNR_DB, DataType::Float64, true, Some("dB")),
        field(STATUS, DataType::Utf8, true, None),
        field(RETRIES, DataType::UInt32, true, None),
        field(MEASURED_AT, DataType::Timestamp(TimeUnit::Microsecond, Some(MEASURED_AT_TZ.into())), true, None),
        field(KIND, DataType::Utf8, true, None),
        field(ESTIMATED_ERROR_DB, DataType::Float64, true, Some("dB")),
    ]))
}

/// Prefix of every key of the file-level key-value metadata this crate writes.
pub const FILE_METADATA_PREFIX: &str = "metaplate.";

/// The file-level key-value metadata of a batch file of the dataset `meta` whose responses are sampled at
/// `sample_rate_hz` (keys in the module documentation).
pub fn file_metadata(meta: &DatasetMeta, sample_rate_hz: f64) -> Vec<KeyValue> {
    let grid = &meta.grid;
    let grid_json = serde_json::json!({
        "nx": grid.nx, "ny": grid.ny, "spacing_m": grid.spacing_m,
        "origin_x_m": grid.origin_x_m, "origin_y_m": grid.origin_y_m,
    });
    let (ir_unit, pre_samples) = match &meta.description {
        Some(DatasetDescription { ir_unit, pre_samples }) => (ir_unit.clone(), pre_samples.to_string()),
        None => ("unstated".to_owned(), String::new()),
    };
    [
        ("recipe", meta.recipe.clone()),
        ("scene", meta.scene.name.clone()),
        ("scene_hash", meta.scene.hash.clone()),
        ("grid", grid_json.to_string()),
        ("sample_rate_hz", sample_rate_hz.to_string()),
        ("ir_unit", ir_unit),
        ("pre_samples", pre_samples),
        ("software_version", meta.software_version.clone()),
        ("schema_version", meta.schema_version.to_string()),
        ("seed", meta.seed.to_string()),
    ]
    .into_iter()
    .map(|(key, value)| KeyValue::new(format!("{FILE_METADATA_PREFIX}{key}"), value))
    .collect()
}

/// Whether `found` can be read as the column type `expected`: equal, except that a list of samples may be a list or
/// a fixed-size list of any size (files written before `ir` was fixed-size hold a list), and its item field may
/// have any name and nullability (pyarrow names it `element` when it rewrites a file; nulls are refused when
/// decoding).
pub(crate) fn compatible(expected: &DataType, found: &DataType) -> bool {
    let items = |t: &DataType| match t {
        DataType::List(f) | DataType::FixedSizeList(f, _) => Some(f.data_type().clone()),
        _ => None,
    };
    match (items(expected), items(found)) {
        (Some(e), Some(f)) => e == f,
        (None, None) => expected == found,
        _ => false,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn status_strings_round_trip_and_are_distinct() {
        for status in Status::ALL {
            assert_eq!(Status::parse(status.as_str()), Some(status));
        }
        let mut names: Vec<_> = Status::ALL.iter().map(|s| s.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Status::ALL.len());
        assert_eq!(Status::parse("Valid"), None, "status strings are case-sensitive");
        assert_eq!(Status::parse(""), None);
    }

    #[test]
    fn schema_has_the_documented_columns_and_units() {
        let schema = arrow_schema(12);
        let names: Vec<_> = schema.fields().iter().map(|f| f.name().as_str()).collect();
        assert_eq!(
            names,
            [
                POINT_INDEX,
                IX,
                IY,
                X_M,
                Y_M,
                ACTUATOR,
                SAMPLE_RATE_HZ,
                IR,
                SNR_DB,
                STATUS,
                RETRIES,
                MEASURED_AT,
                KIND,
                ESTIMATED_ERROR_DB
            ]
        );
        let unit = |name: &str| schema.field_with_name(name).ok().and_then(|f| f.metadata().get("unit").cloned());
        assert_eq!(unit(X_M).as_deref(), Some("m"));
        assert_eq!(unit(SAMPLE_RATE_HZ).as_deref(), Some("Hz"));
        assert_eq!(unit(SNR_DB).as_deref(), Some("dB"));
        assert_eq!(unit(ESTIMATED_ERROR_DB).as_deref(), Some("dB"));
        // Keys and the response itself are required; the quality columns are filled only by scans.
        for f in schema.fields() {
            let optional =
                [SNR_DB, STATUS, RETRIES, MEASURED_AT, KIND, ESTIMATED_ERROR_DB].contains(&f.name().as_str());
            assert_eq!(f.is_nullable(), optional, "{}", f.name());
        }
    }

    #[test]
    fn list_compatibility_ignores_item_name_only() {
        let ours = DataType::FixedSizeList(Arc::new(ir_item_field()), 12);
        let pyarrow = DataType::List(Arc::new(Field::new("element", DataType::Float32, true)));
        let other_size = DataType::FixedSizeList(Arc::new(ir_item_field()), 7);
        let wrong = DataType::List(Arc::new(Field::new("item", DataType::Float64, false)));
        assert!(compatible(&ours, &pyarrow));
        assert!(compatible(&ours, &other_size));
        assert!(!compatible(&ours, &wrong));
        assert!(!compatible(&DataType::UInt32, &DataType::UInt64));
    }
}

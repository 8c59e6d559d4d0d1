//! A polars `DataFrame` of a dataset (cargo feature `polars`).

use std::path::Path;

use polars_core::datatypes::ReshapeDimension;
use polars_core::prelude::{
    Column, DataFrame, Float32Chunked, Int64Chunked, IntoSeries, NamedFrom, NewChunkedArray, PlSmallStr, Series,
    TimeUnit, TimeZone,
};

use crate::error::StoreError;
use crate::reader::Dataset;
use crate::schema;

impl Dataset {
    /// A polars `DataFrame` of every row of the dataset in `dir`, read and verified as [`Dataset::open`] reads it
    /// (the committed files, in commit order), in the columns of [`crate::schema`] with their types: `ir` a
    /// fixed-size array of f32, `measured_at` a UTC datetime in µs, `status` and `kind` strings; a column that files
    /// written before it existed lack (`kind`, `estimated_error_db`) is null in their rows. `columns`: only these, in
    /// this order (`None`: all).
    ///
    /// The frame is `polars_core`'s, the one the `polars` crate re-exports: a program with polars' `lazy` feature
    /// turns it into a `LazyFrame` with `.lazy()`. Memory: the dataset is read whole (about 4 bytes per
    /// impulse-response sample: 1,225 points x 8 actuators x 12,000 samples is 470 MB), and the frame holds a copy of
    /// the columns asked for; naming only the small ones (`point_index`, `actuator`, `snr_db`) copies no response.
    ///
    /// # Errors
    /// [`StoreError::Polars`] for a column name the schema does not have (before anything is read), or if polars
    /// refuses to build a column; otherwise as [`Dataset::open`] (a damaged or missing file, nothing committed).
    pub fn dataframe(dir: impl AsRef<Path>, columns: Option<&[&str]>) -> Result<DataFrame, StoreError> {
        let dir = dir.as_ref();
        let polars = |reason: String| StoreError::Polars { dir: dir.to_path_buf(), reason };
        let all: Vec<String> = schema::arrow_schema(1).fields().iter().map(|f| f.name().clone()).collect();
        let names: Vec<&str> = match columns {
            Some(names) => names.to_vec(),
            None => all.iter().map(String::as_str).collect(),
        };
        if let Some(unknown) = names.iter().find(|name| !all.iter().any(|a| a == *name)) {
            return Err(polars(format!("no column `{unknown}`: a dataset's columns are {}", all.join(", "))));
        }
        let dataset = Dataset::open(dir)?;
        let rows = dataset.rows();
        let mut frame = Vec::with_capacity(names.len());
        for name in names {
            let label = PlSmallStr::from_str(name);
            let series = match name {
                schema::POINT_INDEX => Series::new(label, rows.iter().map(|r| r.point_index).collect::<Vec<u32>>()),
                schema::IX => Series::new(label, rows.iter().map(|r| r.ix).collect::<Vec<u32>>()),
                schema::IY => Series::new(label, rows.iter().map(|r| r.iy).collect::<Vec<u32>>()),
                schema::X_M => Series::new(label, rows.iter().map(|r| r.x_m).collect::<Vec<f64>>()),
                schema::Y_M => Series::new(label, rows.iter().map(|r| r.y_m).collect::<Vec<f64>>()),
                schema::ACTUATOR => Series::new(label, rows.iter().map(|r| r.actuator).collect::<Vec<u16>>()),
                schema::SAMPLE_RATE_HZ => {
                    Series::new(label, rows.iter().map(|r| r.sample_rate_hz).collect::<Vec<f64>>())
                }
                schema::IR => {
                    let width = i64::try_from(dataset.ir_len()).map_err(|e| polars(e.to_string()))?;
                    Float32Chunked::from_vec(label, dataset.irs().to_vec())
                        .into_series()
                        .reshape_array(&[ReshapeDimension::Infer, ReshapeDimension::new(width)])
                        .map_err(|e| polars(format!("column `{name}`: {e}")))?
                }
                schema::SNR_DB => Series::new(label, rows.iter().map(|r| r.snr_db).collect::<Vec<Option<f64>>>()),
                schema::STATUS => {
                    Series::new(label, rows.iter().map(|r| r.status.map(|s| s.as_str())).collect::<Vec<Option<&str>>>())
                }
                schema::RETRIES => Series::new(label, rows.iter().map(|r| r.retries).collect::<Vec<Option<u32>>>()),
                schema::MEASURED_AT => {
                    let us: Vec<Option<i64>> = rows.iter().map(|r| r.measured_at_unix_us).collect();
                    Int64Chunked::from_iter_options(label, us.into_iter())
                        .into_datetime(TimeUnit::Microseconds, Some(TimeZone::UTC))
                        .into_series()
                }
                schema::KIND => {
                    Series::new(label, rows.iter().map(|r| r.kind.map(|k| k.as_str())).collect::<Vec<Option<&str>>>())
                }
                schema::ESTIMATED_ERROR_DB => {
                    Series::new(label, rows.iter().map(|r| r.estimated_error_db).collect::<Vec<Option<f64>>>())
                }
                // Every name was checked against the schema above; a column added to the schema without a case here
                // is refused by name rather than left out.
                other => return Err(polars(format!("column `{other}` has no polars conversion"))),
            };
            frame.push(Column::from(series));
        }
        DataFrame::new(dataset.len(), frame).map_err(|e| polars(e.to_string()))
    }
}

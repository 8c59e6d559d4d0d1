//! Small tables outside a dataset (an experiment's scored trials, a unit cell's band points) as one Parquet file,
//! written with the dataset files' codec (Snappy, read by polars and pyarrow) and durably (temporary name, fsync,
//! rename).

use std::path::Path;

use arrow_array::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;

use crate::durable::write_bytes;
use crate::error::StoreError;

/// Writes `batch` as the Parquet file `path` (one row group), with `metadata` as the file's key-value metadata
/// (for example `("metaplate.experiment", name)`). The file appears complete or not at all.
///
/// # Errors
/// [`StoreError::Parquet`] when the batch cannot be encoded; [`StoreError::Io`] / [`StoreError::DiskFull`] when it
/// cannot be written; [`StoreError::Io`] too when `path` names no file.
pub fn write_table(path: &Path, batch: &RecordBatch, metadata: &[(&str, &str)]) -> Result<(), StoreError> {
    let name = path.file_name().and_then(|n| n.to_str()).ok_or_else(|| StoreError::Io {
        op: "write",
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file"),
    })?;
    let parquet = |source| StoreError::Parquet { file: name.to_owned(), source };
    let key_values = metadata.iter().map(|(k, v)| KeyValue::new((*k).to_owned(), (*v).to_owned())).collect();
    let properties = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_key_value_metadata(Some(key_values))
        .build();
    let mut bytes = Vec::new();
    let mut writer = ArrowWriter::try_new(&mut bytes, batch.schema(), Some(properties)).map_err(parquet)?;
    writer.write(batch).map_err(parquet)?;
    writer.close().map_err(parquet)?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    write_bytes(dir, name, &bytes)
}

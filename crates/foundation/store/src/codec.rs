//! Records to Parquet bytes and back, in the columns of [`crate::schema`].
//!
//! Encoding assumes records already checked ([`crate::index::RowIndex::check`]); decoding trusts nothing: a wrong
//! column type, a null in a required column or an unknown status is a typed error, never a panic.

use std::io::Write;
use std::ops::Range;
use std::sync::Arc;

use arrow_array::builder::{FixedSizeListBuilder, Float32Builder};
use arrow_array::cast::AsArray;
use arrow_array::types::{
    ArrowPrimitiveType, Float32Type, Float64Type, TimestampMicrosecondType, UInt16Type, UInt32Type,
};
use arrow_array::{
    Array, ArrayRef, Float64Array, PrimitiveArray, RecordBatch, StringArray, TimestampMicrosecondArray, UInt16Array,
    UInt32Array,
};
use bytes::Bytes;
use parquet::arrow::ArrowWriter;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::basic::Compression;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::schema::types::ColumnPath;

use crate::error::StoreError;
use crate::record::{IrMeta, IrRecord};
use crate::schema::{self, RowKind, Status, arrow_schema};

/// Writer settings: Snappy (pure Rust, read by every Parquet reader); no dictionaries, which only cost time on
/// impulse responses (nearly every f32 distinct) and save nothing worth having on the small key columns; no
/// statistics on the samples of `ir` (a page's min and max sample select nothing, and cost a pass over every
/// sample); one row group per batch. Plain encoding: BYTE_STREAM_SPLIT made the files of noise-like responses 8%
/// smaller with Snappy but decoded at two thirds of the speed. The reader assumes none of this.
fn writer_properties(key_values: Vec<KeyValue>) -> WriterProperties {
    // The Parquet path of the samples: Arrow writes a list as a repeated group `list` holding the item field.
    let ir_samples =
        ColumnPath::new(vec![schema::IR.to_string(), "list".to_string(), schema::ir_item_field().name().clone()]);
    WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_dictionary_enabled(false)
        .set_column_statistics_enabled(ir_samples, EnabledStatistics::None)
        .set_max_row_group_row_count(None)
        .set_max_row_group_bytes(None)
        .set_key_value_metadata(Some(key_values))
        .build()
}

/// Assembles checked records (one IR length) into one Arrow record batch of the dataset schema.
fn to_record_batch(records: &[IrRecord]) -> Result<RecordBatch, arrow_schema::ArrowError> {
    let metas = || records.iter().map(|r| &r.meta);
    let samples: usize = records.iter().map(|r| r.ir.len()).sum();
    let ir_len = records.first().map_or(0, |r| r.ir.len());
    let ir_len = i32::try_from(ir_len)
        .map_err(|_| arrow_schema::ArrowError::InvalidArgumentError(format!("ir of {ir_len} samples")))?;
    let mut ir = FixedSizeListBuilder::with_capacity(Float32Builder::with_capacity(samples), ir_len, records.len())
        .with_field(Arc::new(schema::ir_item_field()));
    for record in records {
        ir.values().append_slice(&record.ir);
        ir.append(true);
    }
    let columns: Vec<ArrayRef> = vec![
        Arc::new(UInt32Array::from_iter_values(metas().map(|m| m.point_index))),
        Arc::new(UInt32Array::from_iter_values(metas().map(|m| m.ix))),
        Arc::new(UInt32Array::from_iter_values(metas().map(|m| m.iy))),
        Arc::new(Float64Array::from_iter_values(metas().map(|m| m.x_m))),
        Arc::new(Float64Array::from_iter_values(metas().map(|m| m.y_m))),
        Arc::new(UInt16Array::from_iter_values(metas().map(|m| m.actuator))),
        Arc::new(Float64Array::from_iter_values(metas().map(|m| m.sample_rate_hz))),
        Arc::new(ir.finish()),
        Arc::new(Float64Array::from_iter(metas().map(|m| m.snr_db))),
        Arc::new(StringArray::from_iter(metas().map(|m| m.status.map(Status::as_str)))),
        Arc::new(UInt32Array::from_iter(metas().map(|m| m.retries))),
        Arc::new(
            TimestampMicrosecondArray::from_iter(metas().map(|m| m.measured_at_unix_us))
                .with_timezone(schema::MEASURED_AT_TZ),
        ),
        Arc::new(StringArray::from_iter(metas().map(|m| m.kind.map(RowKind::as_str)))),
        Arc::new(Float64Array::from_iter(metas().map(|m| m.estimated_error_db))),
    ];
    RecordBatch::try_new(arrow_schema(ir_len), columns)
}

/// Writes `records` as one Parquet file (one row group) to `sink`; `file` names it in errors.
///
/// # Errors
/// [`StoreError::Arrow`] or [`StoreError::Parquet`] (including I/O errors of `sink`, which Parquet wraps).
pub(crate) fn write_parquet(
    sink: impl Write + Send,
    records: &[IrRecord],
    key_values: Vec<KeyValue>,
    file: &str,
) -> Result<(), StoreError> {
    write_parquet_parts(sink, std::iter::once(Ok(records)), key_values, file)
}

/// Writes the records of `parts` as one Parquet file, one row group per part, so that a large file (a compaction)
/// never holds more than one part in memory; `file` names it in errors.
///
/// # Errors
/// The first error of `parts`, or as [`write_parquet`].
pub(crate) fn write_parquet_parts<P: AsRef<[IrRecord]>>(
    sink: impl Write + Send,
    parts: impl IntoIterator<Item = Result<P, StoreError>>,
    key_values: Vec<KeyValue>,
    file: &str,
) -> Result<(), StoreError> {
    let parquet = |source| StoreError::Parquet { file: file.to_string(), source };
    // Opened with the first part: the schema's `ir` size is the parts' IR length.
    let (mut sink, mut properties) = (Some(sink), Some(writer_properties(key_values)));
    let mut writer = None;
    for part in parts {
        let batch =
            to_record_batch(part?.as_ref()).map_err(|source| StoreError::Arrow { file: file.to_string(), source })?;
        let writer = match &mut writer {
            Some(writer) => writer,
            None => writer.insert(
                ArrowWriter::try_new(
                    sink.take().into_iter().next().ok_or_else(no_sink(file))?,
                    batch.schema(),
                    properties.take(),
                )
                .map_err(parquet)?,
            ),
        };
        writer.write(&batch).map_err(parquet)?;
        writer.flush().map_err(parquet)?;
    }
    let writer = match (writer, sink) {
        (Some(writer), _) => writer,
        // No part: an empty file of the schema.
        (None, Some(sink)) => ArrowWriter::try_new(sink, arrow_schema(0), properties).map_err(parquet)?,
        (None, None) => return Err(no_sink(file)()),
    };
    writer.close().map_err(parquet)?;
    Ok(())
}

/// The error of a sink used twice (not reachable: the writer takes it once).
fn no_sink(file: &str) -> impl Fn() -> StoreError + '_ {
    move || StoreError::Io {
        op: "write",
        path: file.into(),
        source: std::io::Error::other("internal: the Parquet sink was already taken"),
    }
}

/// The rows of one batch file: metadata per row, and the impulse responses back to back (row `r` spans
/// `ir_offsets[r]..ir_offsets[r + 1]` of `ir_values`).
#[derive(Debug, Default)]
pub(crate) struct Decoded {
    pub metas: Vec<IrMeta>,
    pub ir_values: Vec<f32>,
    pub ir_offsets: Vec<usize>,
}

impl Decoded {
    /// `(meta, ir)` of every row, in file order.
    pub(crate) fn rows(&self) -> impl Iterator<Item = (&IrMeta, &[f32])> {
        self.metas.iter().zip(self.ir_offsets.windows(2)).map(|(meta, w)| (meta, &self.ir_values[w[0]..w[1]]))
    }
}

/// Uncompressed bytes of one decoded record batch that [`read_parquet_into`] aims at: small enough that a batch's
/// values, levels and page buffers stay in the CPU caches and its allocations are recycled from batch to batch
/// (a whole 392-row file of 12000-sample responses in one batch decodes at less than half the speed), large enough
/// that the per-batch overhead of the 12 columns does not count.
const BATCH_TARGET_BYTES: u64 = 1 << 20;

/// Most rows of one decoded record batch (the Arrow reader's default).
const BATCH_MAX_ROWS: u64 = 1024;

/// Rows per decoded record batch for a file whose footer is `metadata`: [`BATCH_TARGET_BYTES`] over the average
/// uncompressed row size, within 1..=[`BATCH_MAX_ROWS`]. The footer is not trusted: a wrong size only changes the
/// batch size, never what is decoded.
fn batch_rows(metadata: &parquet::file::metadata::ParquetMetaData) -> usize {
    let groups = metadata.row_groups();
    let rows: u64 = groups.iter().map(|g| u64::try_from(g.num_rows()).unwrap_or(0)).fold(0, u64::saturating_add);
    let bytes: u64 =
        groups.iter().map(|g| u64::try_from(g.total_byte_size()).unwrap_or(0)).fold(0, u64::saturating_add);
    let row_bytes = bytes.checked_div(rows).unwrap_or(0).max(1);
    let batch = (BATCH_TARGET_BYTES / row_bytes).clamp(1, BATCH_MAX_ROWS);
    usize::try_from(batch).unwrap_or(1)
}

/// Decodes a whole Parquet batch file held in memory; `file` names it in errors.
///
/// # Errors
/// As [`read_parquet_into`].
#[cfg(test)]
pub(crate) fn read_parquet(bytes: Bytes, file: &str) -> Result<Decoded, StoreError> {
    let mut decoded = Decoded::default();
    read_parquet_into(bytes, file, &mut decoded)?;
    Ok(decoded)
}

/// Decodes a whole Parquet batch file held in memory into `out`, replacing what it held (its buffers are reused, so
/// that decoding file after file does not allocate and fault in fresh memory for each); `file` names it in errors.
///
/// Reads any Parquet encoding and page layout the `parquet` crate reads (the settings of [`writer_properties`] are
/// not assumed: files written by earlier versions, or rewritten by pyarrow, decode the same). On error `out` holds
/// a partial decode and is only good for reuse.
///
/// # Errors
/// [`StoreError::Parquet`] for bytes that are not a readable Parquet file, [`StoreError::Arrow`] for pages that do
/// not decode, [`StoreError::SchemaMismatch`] for a column missing or of another type, [`StoreError::InvalidRecord`]
/// for a null in a required column or an unknown status string.
pub(crate) fn read_parquet_into(bytes: Bytes, file: &str, out: &mut Decoded) -> Result<(), StoreError> {
    let parquet = |source| StoreError::Parquet { file: file.to_string(), source };
    let builder = ParquetRecordBatchReaderBuilder::try_new(bytes).map_err(parquet)?;
    check_schema(builder.schema(), file)?;
    let batch_rows = batch_rows(builder.metadata());
    // No pre-allocation from the footer's row count: a hostile footer could ask for more than memory holds.
    let reader = builder.with_batch_size(batch_rows).build().map_err(parquet)?;
    out.metas.clear();
    out.ir_values.clear();
    out.ir_offsets.clear();
    out.ir_offsets.push(0);
    for batch in reader {
        let batch = batch.map_err(|source| StoreError::Arrow { file: file.to_string(), source })?;
        decode_batch(&batch, file, out)?;
    }
    Ok(())
}

/// Checks that every column of the dataset schema is present with a readable type (extra columns are ignored, so
/// that a later schema version's additions do not break old readers of the same version).
fn check_schema(found: &arrow_schema::Schema, file: &str) -> Result<(), StoreError> {
    for expected in arrow_schema(1).fields() {
        let reason = match found.field_with_name(expected.name()) {
            // Files written before the column existed.
            Err(_) if [schema::KIND, schema::ESTIMATED_ERROR_DB].contains(&expected.name().as_str()) => continue,
            Err(_) => format!("column {} is missing", expected.name()),
            Ok(f) if !schema::compatible(expected.data_type(), f.data_type()) => {
                format!("column {} has type {}, expected {}", f.name(), f.data_type(), expected.data_type())
            }
            Ok(_) => continue,
        };
        return Err(StoreError::SchemaMismatch { file: file.to_string(), reason });
    }
    Ok(())
}

/// A column of `batch` as a primitive array of type `T`.
fn primitive<'a, T: ArrowPrimitiveType>(
    batch: &'a RecordBatch,
    name: &str,
    file: &str,
) -> Result<&'a PrimitiveArray<T>, StoreError> {
    batch.column_by_name(name).and_then(|c| c.as_primitive_opt::<T>()).ok_or_else(|| StoreError::SchemaMismatch {
        file: file.to_string(),
        reason: format!("column {name} is missing or has the wrong type"),
    })
}

/// The value of a required (non-null) column at `row`.
fn required<T: ArrowPrimitiveType>(
    array: &PrimitiveArray<T>,
    row: usize,
    name: &str,
    location: &dyn Fn() -> String,
) -> Result<T::Native, StoreError> {
    if array.is_null(row) {
        return Err(StoreError::InvalidRecord { location: location(), reason: format!("{name} is null") });
    }
    Ok(array.value(row))
}

/// The value of an optional column at `row`.
fn optional<T: ArrowPrimitiveType>(array: &PrimitiveArray<T>, row: usize) -> Option<T::Native> {
    if array.is_null(row) { None } else { Some(array.value(row)) }
}

/// Appends the rows of one record batch to `out`: per-row metadata, and the samples of all rows in one copy.
fn decode_batch(batch: &RecordBatch, file: &str, out: &mut Decoded) -> Result<(), StoreError> {
    let mismatch = |reason: &str| StoreError::SchemaMismatch { file: file.to_string(), reason: reason.to_string() };
    let point_index = primitive::<UInt32Type>(batch, schema::POINT_INDEX, file)?;
    let ix = primitive::<UInt32Type>(batch, schema::IX, file)?;
    let iy = primitive::<UInt32Type>(batch, schema::IY, file)?;
    let x_m = primitive::<Float64Type>(batch, schema::X_M, file)?;
    let y_m = primitive::<Float64Type>(batch, schema::Y_M, file)?;
    let actuator = primitive::<UInt16Type>(batch, schema::ACTUATOR, file)?;
    let sample_rate_hz = primitive::<Float64Type>(batch, schema::SAMPLE_RATE_HZ, file)?;
    let snr_db = primitive::<Float64Type>(batch, schema::SNR_DB, file)?;
    let retries = primitive::<UInt32Type>(batch, schema::RETRIES, file)?;
    let measured_at = primitive::<TimestampMicrosecondType>(batch, schema::MEASURED_AT, file)?;
    let status = batch
        .column_by_name(schema::STATUS)
        .and_then(|c| c.as_string_opt::<i32>())
        .ok_or_else(|| mismatch("column status is missing or not utf8"))?;
    let kind = match batch.column_by_name(schema::KIND) {
        None => None,
        Some(c) => Some(c.as_string_opt::<i32>().ok_or_else(|| mismatch("column kind is not utf8"))?),
    };
    let estimated_error_db = match batch.column_by_name(schema::ESTIMATED_ERROR_DB) {
        None => None,
        Some(c) => {
            Some(c.as_primitive_opt::<Float64Type>().ok_or_else(|| mismatch("column estimated_error_db is not f64"))?)
        }
    };
    let ir = batch.column_by_name(schema::IR).ok_or_else(|| mismatch("column ir is missing"))?;
    // A fixed-size list (this version), or a list (files written before): the items and each row's offsets.
    let fixed_offsets: Vec<i32>;
    let (ir_items, ir_offsets): (&ArrayRef, &[i32]) = if let Some(list) = ir.as_list_opt::<i32>() {
        (list.values(), list.value_offsets())
    } else if let Some(list) = ir.as_fixed_size_list_opt() {
        let len = list.value_length();
        let rows = i32::try_from(list.len()).map_err(|_| mismatch("too many rows"))?;
        fixed_offsets = (0..=rows).map(|r| r.saturating_mul(len)).collect();
        (list.values(), &fixed_offsets)
    } else {
        return Err(mismatch("column ir is not a list"));
    };
    let ir_values = ir_items.as_primitive_opt::<Float32Type>().ok_or_else(|| mismatch("ir items are not f32"))?;

    let values = ir_values.values();
    // The samples of this batch's rows are copied in one go after the loop: `span` of the child array (a list array
    // may start its offsets past 0), each row's offsets shifted to where the samples land.
    let base = out.ir_values.len();
    let mut span: Option<Range<usize>> = None;
    for row in 0..batch.num_rows() {
        let global = out.metas.len();
        let location = || format!("{file} row {global}");
        let invalid = |reason: String| StoreError::InvalidRecord { location: location(), reason };
        let status = if status.is_null(row) {
            None
        } else {
            let text = status.value(row);
            Some(Status::parse(text).ok_or_else(|| invalid(format!("unknown status {text:?}")))?)
        };
        let kind = match kind {
            Some(kind) if !kind.is_null(row) => {
                let text = kind.value(row);
                Some(RowKind::parse(text).ok_or_else(|| invalid(format!("unknown kind {text:?}")))?)
            }
            _ => None,
        };
        out.metas.push(IrMeta {
            point_index: required(point_index, row, schema::POINT_INDEX, &location)?,
            ix: required(ix, row, schema::IX, &location)?,
            iy: required(iy, row, schema::IY, &location)?,
            x_m: required(x_m, row, schema::X_M, &location)?,
            y_m: required(y_m, row, schema::Y_M, &location)?,
            actuator: required(actuator, row, schema::ACTUATOR, &location)?,
            sample_rate_hz: required(sample_rate_hz, row, schema::SAMPLE_RATE_HZ, &location)?,
            snr_db: optional(snr_db, row),
            status,
            retries: optional(retries, row),
            measured_at_unix_us: optional(measured_at, row),
            kind,
            estimated_error_db: estimated_error_db.and_then(|c| optional(c, row)),
        });
        if ir.is_null(row) {
            return Err(invalid("ir is null".into()));
        }
        // Arrow validated the offsets when it built the array; checking them again (in range, each row starting
        // where the previous one ended) keeps a bad one an error rather than a panic or a shifted response.
        let bad_offsets = || invalid("ir offsets out of range".into());
        let index = |offset: i32| usize::try_from(offset).map_err(|_| bad_offsets());
        let (start, end) = match ir_offsets.get(row..row + 2) {
            Some(&[start, end]) => (index(start)?, index(end)?),
            _ => return Err(bad_offsets()),
        };
        let from = span.as_ref().map_or(start, |s| s.start);
        if start > end || end > values.len() || span.as_ref().is_some_and(|s| s.end != start) {
            return Err(bad_offsets());
        }
        if ir_values.null_count() > 0 && (start..end).any(|i| ir_values.is_null(i)) {
            return Err(invalid("ir holds a null sample".into()));
        }
        out.ir_offsets.push(base + (end - from));
        span = Some(from..end);
    }
    if let Some(span) = span {
        // In range: every row's `start..end` was checked against `values.len()` above, and they are contiguous.
        out.ir_values.extend_from_slice(&values[span]);
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;
    use crate::manifest::GridSpec;

    fn records() -> Vec<IrRecord> {
        let grid = GridSpec { nx: 2, ny: 2, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };
        let mut first = IrMeta::at_grid(&grid, 1, 1, 7, 24_000.0).unwrap();
        first.snr_db = Some(41.5);
        first.status = Some(Status::ReMeasured);
        first.retries = Some(2);
        first.measured_at_unix_us = Some(1_767_225_600_000_000);
        first.kind = Some(RowKind::Verification);
        let second = IrMeta::at_grid(&grid, 0, 1, 0, 24_000.0).unwrap();
        vec![
            IrRecord { meta: first, ir: vec![1.5, -0.0, f32::MIN_POSITIVE / 2.0] },
            IrRecord { meta: second, ir: vec![f32::MAX, f32::MIN, 3.25] },
        ]
    }

    #[test]
    fn parquet_round_trip_is_bit_exact() {
        let records = records();
        let mut bytes = Vec::new();
        write_parquet(&mut bytes, &records, Vec::new(), "t.parquet").unwrap();
        let decoded = read_parquet(Bytes::from(bytes), "t.parquet").unwrap();
        let back: Vec<IrRecord> = decoded.rows().map(|(meta, ir)| IrRecord { meta: *meta, ir: ir.to_vec() }).collect();
        assert_eq!(back.len(), records.len());
        for (a, b) in records.iter().zip(&back) {
            assert_eq!(a.meta, b.meta);
            // Compare bits: -0.0 and subnormals must survive, which `==` on f32 would not show.
            let bits = |ir: &[f32]| ir.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.ir), bits(&b.ir));
        }
    }

    #[test]
    fn a_file_without_a_column_is_a_schema_mismatch() {
        let batch = to_record_batch(&records()).unwrap();
        let without_ir = batch.project(&[0, 1, 2, 3, 4, 5, 6, 8, 9, 10, 11]).unwrap();
        let mut bytes = Vec::new();
        let mut writer = ArrowWriter::try_new(&mut bytes, without_ir.schema(), None).unwrap();
        writer.write(&without_ir).unwrap();
        writer.close().unwrap();
        let err = read_parquet(Bytes::from(bytes), "t.parquet").unwrap_err();
        assert!(matches!(err, StoreError::SchemaMismatch { ref reason, .. } if reason.contains("ir")), "{err}");
    }

    #[test]
    fn a_file_written_before_the_kind_column_reads_with_no_kind() {
        let batch = to_record_batch(&records()).unwrap();
        let without_kind = batch.project(&[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]).unwrap();
        let mut bytes = Vec::new();
        let mut writer = ArrowWriter::try_new(&mut bytes, without_kind.schema(), None).unwrap();
        writer.write(&without_kind).unwrap();
        writer.close().unwrap();
        let decoded = read_parquet(Bytes::from(bytes), "t.parquet").unwrap();
        assert!(decoded.metas.iter().all(|m| m.kind.is_none() && m.estimated_error_db.is_none()));
        assert_eq!(decoded.metas[0].status, Some(Status::ReMeasured));
        // A file with `kind` but written before `estimated_error_db` existed.
        let without_estimate = batch.project(&[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]).unwrap();
        let mut bytes = Vec::new();
        let mut writer = ArrowWriter::try_new(&mut bytes, without_estimate.schema(), None).unwrap();
        writer.write(&without_estimate).unwrap();
        writer.close().unwrap();
        let decoded = read_parquet(Bytes::from(bytes), "t.parquet").unwrap();
        assert!(decoded.metas.iter().all(|m| m.estimated_error_db.is_none()));
    }

    /// Records of `rows` rows with `len`-sample responses, every sample distinct.
    fn many_records(rows: u32, len: usize) -> Vec<IrRecord> {
        let grid = GridSpec { nx: rows as usize, ny: 1, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };
        (0..rows)
            .map(|ix| IrRecord {
                meta: IrMeta::at_grid(&grid, ix, 0, 3, 24_000.0).unwrap(),
                ir: (0..len).map(|i| (i as f32 + 0.25) * if ix % 2 == 0 { 1.0 } else { -1.0e-3 } + ix as f32).collect(),
            })
            .collect()
    }

    fn assert_decodes_to(bytes: Vec<u8>, records: &[IrRecord]) {
        let decoded = read_parquet(Bytes::from(bytes), "t.parquet").unwrap();
        assert_eq!(decoded.metas.len(), records.len());
        for ((meta, ir), record) in decoded.rows().zip(records) {
            assert_eq!(*meta, record.meta);
            let bits = |ir: &[f32]| ir.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(ir), bits(&record.ir), "row {}", meta.point_index);
        }
    }

    #[test]
    fn a_file_decoded_in_several_record_batches_keeps_every_row_in_place() {
        // 90 rows of 40 000 samples: 14 MB, decoded some 6 rows at a time; into a `Decoded` that held another file.
        let records = many_records(90, 40_000);
        let mut bytes = Vec::new();
        write_parquet(&mut bytes, &records, Vec::new(), "t.parquet").unwrap();
        let mut decoded = read_parquet(Bytes::from(bytes.clone()), "t.parquet").unwrap();
        assert_decodes_to(bytes, &records);
        let small = self::records();
        let mut small_bytes = Vec::new();
        write_parquet(&mut small_bytes, &small, Vec::new(), "s.parquet").unwrap();
        read_parquet_into(Bytes::from(small_bytes), "s.parquet", &mut decoded).unwrap();
        assert_eq!(decoded.ir_offsets, [0, 3, 6]);
        assert_eq!(
            decoded.rows().map(|(meta, _)| *meta).collect::<Vec<_>>(),
            small.iter().map(|r| r.meta).collect::<Vec<_>>()
        );
    }

    #[test]
    fn files_written_with_other_properties_decode_the_same() {
        // What earlier versions or other writers may have done: dictionaries, statistics, small pages, several
        // row groups, no compression, and pyarrow's nullable `element` items.
        let records = many_records(40, 3_000);
        let dictionary = WriterProperties::builder()
            .set_dictionary_enabled(true)
            .set_statistics_enabled(EnabledStatistics::Page)
            .set_data_page_size_limit(1000)
            .set_max_row_group_row_count(Some(7))
            .build();
        let plain = WriterProperties::builder().set_compression(Compression::UNCOMPRESSED).build();
        let batch = to_record_batch(&records).unwrap();
        let nullable_items = {
            let mut fields: Vec<arrow_schema::Field> =
                batch.schema().fields().iter().map(|f| f.as_ref().clone()).collect();
            let element = Arc::new(arrow_schema::Field::new("element", arrow_schema::DataType::Float32, true));
            fields[7] = arrow_schema::Field::new(schema::IR, arrow_schema::DataType::List(Arc::clone(&element)), true);
            // As files written before `ir` was fixed-size: a list.
            let mut ir = arrow_array::builder::ListBuilder::new(Float32Builder::new()).with_field(Arc::clone(&element));
            for record in &records {
                ir.values().append_slice(&record.ir);
                ir.append(true);
            }
            let mut columns = batch.columns().to_vec();
            columns[7] = Arc::new(ir.finish());
            RecordBatch::try_new(Arc::new(arrow_schema::Schema::new(fields)), columns).unwrap()
        };
        for (batch, properties) in
            [(&batch, dictionary), (&batch, plain), (&nullable_items, writer_properties(Vec::new()))]
        {
            let mut bytes = Vec::new();
            let mut writer = ArrowWriter::try_new(&mut bytes, batch.schema(), Some(properties)).unwrap();
            writer.write(batch).unwrap();
            writer.close().unwrap();
            assert_decodes_to(bytes, &records);
        }
    }

    #[test]
    fn garbage_is_a_parquet_error() {
        let err = read_parquet(Bytes::from_static(b"not a parquet file at all"), "t.parquet").unwrap_err();
        assert!(matches!(err, StoreError::Parquet { .. }), "{err}");
        let err = read_parquet(Bytes::new(), "t.parquet").unwrap_err();
        assert!(matches!(err, StoreError::Parquet { .. }), "{err}");
    }
}

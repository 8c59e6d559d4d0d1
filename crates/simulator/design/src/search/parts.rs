//! A search's results on disk: one Parquet file per design as it is computed (`parts/design-NNNNNN.parquet`,
//! written durably, so a killed run keeps every design it finished), and the gathered results (`results.parquet`,
//! one row per design in index order, the trade-off front marked), from one run or from the parts of several
//! shards.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use arrow_array::{Array, ArrayRef, BooleanArray, Float64Array, RecordBatch, StringArray, UInt64Array};
use arrow_schema::{DataType, Field, Schema};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

use crate::error::DesignError;
use crate::search::evaluate::{DesignResult, mark_front};
use crate::search::spec::{Candidate, SearchSpec};

/// The folder of a search's per-design files.
pub const PARTS_DIR: &str = "parts";

/// The gathered results' file name.
pub const RESULTS_FILE: &str = "results.parquet";

const FINGERPRINT_KEY: &str = "metaplate.search";

/// The file of design `index` in `dir`'s parts.
pub fn part_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(PARTS_DIR).join(format!("design-{index:06}.parquet"))
}

fn schema() -> Arc<Schema> {
    let f64s = ["top_hz", "max_phase_velocity_m_s", "added_mass_kg_m2", "mass_ratio", "resonator_mode_hz"];
    let mut fields = vec![
        Field::new("index", DataType::UInt64, false),
        Field::new("rod_height_m", DataType::Float64, false),
        Field::new("rod_diameter_m", DataType::Float64, false),
        Field::new("lattice_constant_m", DataType::Float64, false),
        Field::new("plate_thickness_m", DataType::Float64, false),
        Field::new("rod_material", DataType::Utf8, false),
        Field::new("plate_material", DataType::Utf8, false),
        Field::new("feasible", DataType::Boolean, false),
        Field::new("reason", DataType::Utf8, false),
    ];
    fields.extend(f64s.iter().map(|n| Field::new(*n, DataType::Float64, false)));
    fields.push(Field::new("on_front", DataType::Boolean, false));
    Arc::new(Schema::new(fields))
}

fn batch(results: &[DesignResult], file: &Path) -> Result<RecordBatch, DesignError> {
    let f64s = |f: &dyn Fn(&DesignResult) -> f64| -> ArrayRef {
        Arc::new(Float64Array::from(results.iter().map(f).collect::<Vec<_>>()))
    };
    let strings = |f: &dyn Fn(&DesignResult) -> &str| -> ArrayRef {
        Arc::new(StringArray::from(results.iter().map(f).collect::<Vec<_>>()))
    };
    let bools = |f: &dyn Fn(&DesignResult) -> bool| -> ArrayRef {
        Arc::new(BooleanArray::from(results.iter().map(f).collect::<Vec<_>>()))
    };
    let columns = vec![
        Arc::new(UInt64Array::from(results.iter().map(|r| r.candidate.index as u64).collect::<Vec<_>>())) as ArrayRef,
        f64s(&|r| r.candidate.rod_height_m),
        f64s(&|r| r.candidate.rod_diameter_m),
        f64s(&|r| r.candidate.lattice_constant_m),
        f64s(&|r| r.candidate.plate_thickness_m),
        strings(&|r| &r.candidate.rod_material),
        strings(&|r| &r.candidate.plate_material),
        bools(&|r| r.feasible),
        strings(&|r| &r.reason),
        f64s(&|r| r.top_hz),
        f64s(&|r| r.max_phase_velocity_m_s),
        f64s(&|r| r.added_mass_kg_m2),
        f64s(&|r| r.mass_ratio),
        f64s(&|r| r.resonator_mode_hz),
        bools(&|r| r.on_front),
    ];
    RecordBatch::try_new(schema(), columns).map_err(|e| output(file, e))
}

fn output(file: &Path, e: impl std::fmt::Display) -> DesignError {
    DesignError::Results { path: file.display().to_string(), why: e.to_string() }
}

fn write(path: &Path, results: &[DesignResult], fingerprint: &str) -> Result<(), DesignError> {
    let batch = batch(results, path)?;
    metaplate_store::write_table(path, &batch, &[(FINGERPRINT_KEY, fingerprint)]).map_err(|e| output(path, e))
}

/// Writes one design's result durably into `dir`'s parts (the folder made when missing).
///
/// # Errors
/// [`DesignError::Results`] when it cannot be written.
pub fn write_part(dir: &Path, result: &DesignResult, fingerprint: &str) -> Result<(), DesignError> {
    let parts = dir.join(PARTS_DIR);
    std::fs::create_dir_all(&parts).map_err(|e| output(&parts, e))?;
    write(&part_path(dir, result.candidate.index), std::slice::from_ref(result), fingerprint)
}

/// The rows of one results or part file, with its search's fingerprint.
///
/// # Errors
/// [`DesignError::Results`] naming the file when it cannot be read or is not a search's results.
pub fn read(path: &Path) -> Result<(Vec<DesignResult>, String), DesignError> {
    let bad = |e: &dyn std::fmt::Display| output(path, e);
    let file = std::fs::File::open(path).map_err(|e| bad(&e))?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(file).map_err(|e| bad(&e))?;
    let meta = builder.metadata().file_metadata().key_value_metadata().cloned().unwrap_or_default();
    let value = |key: &str| meta.iter().find(|kv| kv.key == key).and_then(|kv| kv.value.clone());
    let fingerprint = value(FINGERPRINT_KEY).ok_or_else(|| bad(&"not a design search's results (no fingerprint)"))?;
    let mut rows = Vec::new();
    for batch in builder.build().map_err(|e| bad(&e))? {
        let batch = batch.map_err(|e| bad(&e))?;
        rows.extend(decode(&batch).map_err(|e| bad(&e))?);
    }
    Ok((rows, fingerprint))
}

fn decode(batch: &RecordBatch) -> Result<Vec<DesignResult>, String> {
    fn column<'a, T: 'static>(batch: &'a RecordBatch, name: &str) -> Result<&'a T, String> {
        batch
            .column_by_name(name)
            .and_then(|c| c.as_any().downcast_ref::<T>())
            .ok_or_else(|| format!("column `{name}` missing or of another type"))
    }
    let index = column::<UInt64Array>(batch, "index")?;
    let f = |name: &str| column::<Float64Array>(batch, name);
    let s = |name: &str| column::<StringArray>(batch, name);
    let b = |name: &str| column::<BooleanArray>(batch, name);
    let (height, diameter, lattice, thickness) =
        (f("rod_height_m")?, f("rod_diameter_m")?, f("lattice_constant_m")?, f("plate_thickness_m")?);
    let (rod_material, plate_material, reason) = (s("rod_material")?, s("plate_material")?, s("reason")?);
    let (top, c_max, added, ratio, fn_hz) =
        (f("top_hz")?, f("max_phase_velocity_m_s")?, f("added_mass_kg_m2")?, f("mass_ratio")?, f("resonator_mode_hz")?);
    let (feasible, on_front) = (b("feasible")?, b("on_front")?);
    if index.null_count() > 0 {
        return Err("null index".into());
    }
    (0..batch.num_rows())
        .map(|i| {
            Ok(DesignResult {
                candidate: Candidate {
                    index: usize::try_from(index.value(i)).map_err(|e| e.to_string())?,
                    rod_height_m: height.value(i),
                    rod_diameter_m: diameter.value(i),
                    lattice_constant_m: lattice.value(i),
                    plate_thickness_m: thickness.value(i),
                    rod_material: rod_material.value(i).to_owned(),
                    plate_material: plate_material.value(i).to_owned(),
                },
                feasible: feasible.value(i),
                reason: reason.value(i).to_owned(),
                top_hz: top.value(i),
                max_phase_velocity_m_s: c_max.value(i),
                added_mass_kg_m2: added.value(i),
                mass_ratio: ratio.value(i),
                resonator_mode_hz: fn_hz.value(i),
                on_front: on_front.value(i),
            })
        })
        .collect()
}

/// The per-design files in `dir`'s parts, in index order (none when the folder is absent); temporary files of a
/// write cut off are not parts.
fn part_files(dir: &Path) -> Result<Vec<PathBuf>, DesignError> {
    let parts = dir.join(PARTS_DIR);
    let entries = match std::fs::read_dir(&parts) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(output(&parts, e)),
    };
    let mut files = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| output(&parts, e))?.path();
        let is_part = path.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
            n.strip_prefix("design-")
                .and_then(|n| n.strip_suffix(".parquet"))
                .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        });
        if is_part {
            files.push(path);
        }
    }
    files.sort();
    Ok(files)
}

/// The designs finished in `dir` (its parts), by index; a part that cannot be read is left out (it is computed
/// again) and named in the second list.
///
/// # Errors
/// [`DesignError::Results`] when the parts folder cannot be listed, or a part belongs to another search.
pub fn finished(dir: &Path, fingerprint: &str) -> Result<(BTreeMap<usize, DesignResult>, Vec<PathBuf>), DesignError> {
    let mut done = BTreeMap::new();
    let mut unreadable = Vec::new();
    for path in part_files(dir)? {
        match read(&path) {
            Ok((_, fp)) if fp != fingerprint => {
                return Err(output(&path, format!("belongs to another search ({fp}, this one is {fingerprint})")));
            }
            Ok((rows, _)) if rows.len() == 1 => {
                done.insert(rows[0].candidate.index, rows.into_iter().next().ok_or_else(|| output(&path, "empty"))?);
            }
            _ => unreadable.push(path),
        }
    }
    Ok((done, unreadable))
}

/// Gathers the parts of `dirs` (the runs of `spec`'s shards, or its one run) into `out`: every design exactly once,
/// in index order, the trade-off front over the objectives' goals marked. Equal designs found twice (a shard run
/// twice) are kept once.
///
/// # Errors
/// [`DesignError::Results`] when a part is of another search, a design was computed twice with different results,
/// designs are missing (the first few named), or `out` cannot be written.
pub fn merge(spec: &SearchSpec, dirs: &[PathBuf], out: &Path) -> Result<Vec<DesignResult>, DesignError> {
    let (fingerprint, count) = (spec.fingerprint.as_str(), spec.count());
    let mut all: BTreeMap<usize, DesignResult> = BTreeMap::new();
    for dir in dirs {
        for path in part_files(dir)? {
            let (rows, fp) = read(&path)?;
            if fp != fingerprint {
                return Err(output(&path, format!("is of another search ({fp}) than the search file ({fingerprint})")));
            }
            for row in rows {
                if let Some(seen) = all.get(&row.candidate.index) {
                    if !same(seen, &row) {
                        return Err(output(
                            &path,
                            format!("design {} differs from its other copy", row.candidate.index),
                        ));
                    }
                    continue;
                }
                all.insert(row.candidate.index, row);
            }
        }
    }
    let missing: Vec<usize> = (0..count).filter(|i| !all.contains_key(i)).collect();
    if !missing.is_empty() {
        let first: Vec<String> = missing.iter().take(10).map(ToString::to_string).collect();
        return Err(output(
            out,
            format!("{} of {count} designs are missing (first: {}): run their shards", missing.len(), first.join(", ")),
        ));
    }
    let mut results: Vec<DesignResult> = all.into_values().collect();
    mark_front(&mut results, &spec.objectives.minimise);
    write(out, &results, fingerprint)?;
    Ok(results)
}

/// Equal as recorded (NaN equal to NaN: an uncomputed value).
fn same(a: &DesignResult, b: &DesignResult) -> bool {
    let eq = |x: f64, y: f64| x.to_bits() == y.to_bits();
    a.candidate == b.candidate
        && a.feasible == b.feasible
        && a.reason == b.reason
        && eq(a.top_hz, b.top_hz)
        && eq(a.max_phase_velocity_m_s, b.max_phase_velocity_m_s)
        && eq(a.added_mass_kg_m2, b.added_mass_kg_m2)
        && eq(a.mass_ratio, b.mass_ratio)
        && eq(a.resonator_mode_hz, b.resonator_mode_hz)
}

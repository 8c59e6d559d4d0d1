//! A metaplate dataset from universal files (datasets 164, 2411, 58 and 58b), in two streaming passes over the
//! files (the first reads the headers, nodes and units; the second converts and commits, a batch at a time),
//! through the store's writer as the recipes write: manifest, journal, Parquet batches, checksums.
//!
//! - **Grid and keys.** A file metaplate exported carries the grid and each response's (point, actuator) in its ID
//!   lines ([`IdLines`]): they are used as written. Otherwise (or with [`ImportOptions::grid_from_nodes`]) the grid
//!   comes from the response nodes' positions in dataset 2411, snapped to the regular grid they lie on
//!   ([`metaplate_core::grid::snap_to_grid`], refused with the reason when they form none), and the actuators are
//!   the reference nodes, numbered from 0 in ascending label order.
//! - **Sample rate:** from the abscissa step by [`metaplate_uff::sample_rate_from_step`] (the whole hertz within
//!   10⁻⁵ of `1 / step`).
//! - **Which function per (point, actuator):** the time response (function type 1) when the files hold one; else the
//!   frequency response function (type 4), turned into an impulse response: its bins placed on the grid of a real
//!   FFT of `n = 2 × (index of its last bin)` points at the file's frequency step (the band is the FRF's own,
//!   from its first to its last frequency, bins outside it zero, no taper; the last bin is taken as Nyquist), so the
//!   response is `n` samples long at `n × step` Hz, causal from time 0 (`pre_samples` 0). Other function types are
//!   skipped.
//! - **Units:** ordinates are converted to SI with dataset 164's factors (velocity over force: × force factor ÷
//!   length factor; positions ÷ length factor). Ordinates of displacement or acceleration are refused (a metaplate
//!   dataset holds velocity). The `ir` unit is m/s/N when the denominator is a force, else "m/s per" its units label.
//! - **Other datasets** (not 164, 2411, 58 or 58b) are skipped and counted ([`ImportSummary::skipped`]).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use metaplate_core::grid::{GridSpec, snap_to_grid};
use metaplate_core::scene::SceneId;
use metaplate_store::{DatasetDescription, DatasetMeta, DatasetWriter, IR_UNIT_M_S_PER_N, IfExists, IrMeta, IrRecord};
use metaplate_uff::{FunctionType, UffDecoder, UffRecord, Units164};
use serde_json::json;

use crate::convert::to_ir;
use crate::error::{InterchangeError, refuse};
use crate::{IdLines, Progress};

/// Rows per committed batch file.
const BATCH_ROWS: usize = 256;

/// Bytes read from a file at a time.
const READ_CHUNK: usize = 1 << 20;

/// How to import.
#[derive(Debug, Clone, Copy, Default)]
pub struct ImportOptions {
    /// Take the grid from the nodes' positions even when the files carry metaplate's grid.
    pub grid_from_nodes: bool,
}

/// What an import built.
#[derive(Debug, Clone)]
pub struct ImportSummary {
    /// Rows committed.
    pub rows: usize,
    /// Of which converted from frequency response functions.
    pub from_frf: usize,
    /// The dataset's grid.
    pub grid: GridSpec,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Impulse response length, samples.
    pub ir_len: usize,
    /// Records of other datasets than 164, 2411, 58 and 58b, skipped: count by dataset number.
    pub skipped: BTreeMap<u32, usize>,
}

/// One function of the files, as the first pass saw it.
struct Seen {
    /// File index and the record's ordinal in it.
    at: (usize, u64),
    function_type: FunctionType,
    response: u32,
    reference: u32,
    /// The metaplate key of ID line 1, if any.
    key: Option<(u32, u16)>,
}

/// What the first pass gathers.
#[derive(Default)]
struct Survey {
    units: Option<Units164>,
    nodes: HashMap<u32, [f64; 3]>,
    functions: Vec<Seen>,
    /// ID lines 2 and 3 (grid, scene) and 5 (source) of the first function.
    first_ids: Option<[String; 5]>,
    skipped: BTreeMap<u32, usize>,
}

/// Decodes each file in turn, handing every record to `visit` with the file's index and the record's ordinal.
fn for_each_record(
    files: &[PathBuf],
    mut visit: impl FnMut(usize, u64, UffRecord) -> Result<(), InterchangeError>,
) -> Result<(), InterchangeError> {
    let mut chunk = vec![0u8; READ_CHUNK];
    for (f, path) in files.iter().enumerate() {
        let mut file = File::open(path)
            .map_err(|source| InterchangeError::File { what: format!("opening {}", path.display()), source })?;
        let mut decoder = UffDecoder::new();
        let mut ordinal = 0u64;
        loop {
            let n = file
                .read(&mut chunk)
                .map_err(|source| InterchangeError::File { what: format!("reading {}", path.display()), source })?;
            if n == 0 {
                decoder.finish();
            } else {
                decoder.push(&chunk[..n]);
            }
            while let Some(record) = decoder.poll() {
                let record = record
                    .map_err(|source| InterchangeError::Malformed { file: path.display().to_string(), source })?;
                ordinal += 1;
                visit(f, ordinal, record)?;
            }
            if n == 0 {
                break;
            }
        }
    }
    Ok(())
}

/// The first pass: units, nodes, and every function's header.
fn survey(files: &[PathBuf]) -> Result<Survey, InterchangeError> {
    let mut survey = Survey::default();
    for_each_record(files, |f, ordinal, record| {
        match record {
            UffRecord::Units(units) => {
                if survey.units.as_ref().is_some_and(|u| *u != units) {
                    refuse!("{} gives other units than an earlier dataset 164", files[f].display());
                }
                survey.units = Some(units);
            }
            UffRecord::Nodes(nodes) => {
                for node in nodes.nodes {
                    survey.nodes.insert(node.label, node.position_m);
                }
            }
            UffRecord::Function(function) => {
                let h = &function.header;
                if matches!(h.ordinate.data_type, 8 | 12) {
                    refuse!(
                        "{} record {ordinal}: the ordinate is {} (data type {}); a metaplate dataset holds velocity",
                        files[f].display(),
                        h.ordinate.label,
                        h.ordinate.data_type
                    );
                }
                if survey.first_ids.is_none() {
                    survey.first_ids = Some(h.id_lines.clone());
                }
                survey.functions.push(Seen {
                    at: (f, ordinal),
                    function_type: h.function_type,
                    response: h.response.node,
                    reference: h.reference.node,
                    key: IdLines::parse_key(&h.id_lines[0]),
                });
            }
            UffRecord::Other(other) => *survey.skipped.entry(other.dataset_number).or_default() += 1,
        }
        Ok(())
    })?;
    Ok(survey)
}

/// What the second pass imports: the grid, the record chosen for each key, and where the grid came from.
struct Plan {
    grid: GridSpec,
    /// (file index, record ordinal) of the function imported for each key.
    by_at: HashMap<(usize, u64), (u32, u16)>,
    grid_from: &'static str,
}

/// The grid and each key's function: one per key, the time response, else the FRF.
fn plan(
    files: &[PathBuf],
    survey: &Survey,
    first_ids: &[String; 5],
    options: ImportOptions,
    length_per_m: f64,
) -> Result<Plan, InterchangeError> {
    let metaplate_grid = IdLines::parse_grid(&first_ids[1]).filter(|_| !options.grid_from_nodes);
    let (grid, keys, grid_from) = match metaplate_grid {
        Some(grid) if survey.functions.iter().all(|s| s.key.is_some()) => {
            let keys: Vec<(u32, u16)> = survey.functions.iter().filter_map(|s| s.key).collect();
            (grid, keys, "metaplate ID lines")
        }
        _ => {
            let (grid, keys) = keys_from_nodes(survey, length_per_m)?;
            (grid, keys, "nodes")
        }
    };
    let mut chosen: BTreeMap<(u32, u16), usize> = BTreeMap::new();
    let rank = |t: FunctionType| match t {
        FunctionType::TimeResponse => Some(0),
        FunctionType::FrequencyResponse => Some(1),
        FunctionType::Other(_) => None,
    };
    for (i, (seen, key)) in survey.functions.iter().zip(&keys).enumerate() {
        let Some(r) = rank(seen.function_type) else { continue };
        match chosen.get(key) {
            Some(&j) if rank(survey.functions[j].function_type) == Some(r) => {
                let (a, b) = (survey.functions[j].at, seen.at);
                refuse!(
                    "point {} actuator {} has two responses of one type: {} record {} and {} record {}",
                    key.0,
                    key.1,
                    files[a.0].display(),
                    a.1,
                    files[b.0].display(),
                    b.1
                );
            }
            Some(&j) if rank(survey.functions[j].function_type) < Some(r) => {}
            _ => {
                chosen.insert(*key, i);
            }
        }
    }
    if chosen.is_empty() {
        refuse!("the files hold no time response (type 1) or frequency response (type 4)");
    }
    let by_at = chosen.iter().map(|(key, &i)| (survey.functions[i].at, *key)).collect();
    Ok(Plan { grid, by_at, grid_from })
}

/// Builds the dataset `out` (which must not exist, or be empty) from the universal files `files`, read in order.
/// `progress` is told the responses committed, out of those the files hold.
///
/// # Errors
/// A file that cannot be read or is malformed (with the record and line), nodes that form no grid, a response
/// without its node, ordinates that are not velocity, inconsistent sample rates or lengths, a store error.
pub fn import(
    files: &[PathBuf],
    out: &Path,
    options: ImportOptions,
    mut progress: impl FnMut(Progress),
) -> Result<ImportSummary, InterchangeError> {
    let survey = survey(files)?;
    let Some(first_ids) = survey.first_ids.clone() else {
        refuse!("the files hold no dataset 58 or 58b (no response)")
    };
    let length_per_m = survey.units.as_ref().map_or(1.0, |u| u.length_per_m);
    let force_per_n = survey.units.as_ref().map_or(1.0, |u| u.force_per_n);
    if !(length_per_m.is_finite() && length_per_m > 0.0 && force_per_n.is_finite() && force_per_n > 0.0) {
        refuse!("dataset 164's unit factors must be finite and positive ({length_per_m}, {force_per_n})");
    }
    let Plan { grid, by_at, grid_from } = plan(files, &survey, &first_ids, options, length_per_m)?;
    let scene = IdLines::parse_scene(&first_ids[2])
        .unwrap_or_else(|| SceneId { name: "uff-import".into(), hash: "unknown".into() });
    let seed = IdLines::value(&first_ids[4], "seed").and_then(|v| v.parse().ok()).unwrap_or(0);
    let source_recipe = IdLines::value(&first_ids[4], "recipe").map(str::to_owned);
    let total = by_at.len() as u64;
    progress(Progress { done: 0, total });

    // Second pass: convert and commit.
    let mut writer: Option<DatasetWriter> = None;
    let mut pending: Vec<IrRecord> = Vec::with_capacity(BATCH_ROWS);
    let mut from_frf = 0;
    let mut ir_unit = None;
    let mut pre_samples = None;
    let mut spectrum = Vec::new();
    let mut shape = None;
    for_each_record(files, |f, ordinal, record| {
        let UffRecord::Function(function) = record else { return Ok(()) };
        let Some(&(point, actuator)) = by_at.get(&(f, ordinal)) else { return Ok(()) };
        let where_ = || format!("{} record {ordinal}", files[f].display());
        let converted =
            to_ir(&function, length_per_m, force_per_n, &mut spectrum).map_err(InterchangeError::at(where_))?;
        from_frf += usize::from(converted.from_frf);
        let unit = if function.header.denominator.data_type == 13 {
            IR_UNIT_M_S_PER_N.to_owned()
        } else {
            format!("m/s per {}", function.header.denominator.units_label)
        };
        match (&ir_unit, &pre_samples) {
            (None, _) => {
                ir_unit = Some(unit);
                pre_samples = Some(converted.pre_samples);
            }
            (Some(u), Some(p)) if *u != unit || *p != converted.pre_samples => refuse!(
                "{}: the response is in {unit} from {} samples before time 0; earlier ones in {u} from {p}",
                where_(),
                converted.pre_samples
            ),
            _ => {}
        }
        let (ix, iy) = grid.indices(point as usize);
        let mut meta = IrMeta::at_grid(&grid, ix as u32, iy as u32, actuator, converted.sample_rate_hz)
            .map_err(InterchangeError::at(where_))?;
        if let Some(position) = survey.nodes.get(&function.header.response.node) {
            meta.x_m = position[0] / length_per_m;
            meta.y_m = position[1] / length_per_m;
        }
        let (status, snr_db, retries, measured_at) = IdLines::parse_quality(&function.header.id_lines[3]);
        (meta.status, meta.snr_db, meta.retries, meta.measured_at_unix_us) = (status, snr_db, retries, measured_at);
        meta.estimated_error_db = IdLines::parse_estimated_error(&function.header.id_lines[4]);
        shape.get_or_insert((converted.sample_rate_hz, converted.ir.len()));
        pending.push(IrRecord { meta, ir: converted.ir });
        if writer.is_none() {
            let description = DatasetDescription {
                ir_unit: ir_unit.clone().unwrap_or_default(),
                pre_samples: pre_samples.unwrap_or(0),
            };
            let config = json!({
                "files": files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
                "grid_from": grid_from,
                "source_recipe": source_recipe,
                "sample_rate_rule": "1/step rounded to the whole hertz within 1e-5 (metaplate_uff::sample_rate_from_step)",
                "frf_to_ir": "the FRF's own band, bins outside it zero, no taper; n = 2 x last bin index, causal",
            });
            let serde_json::Value::Object(config) = config else {
                refuse!("internal: configuration is not a JSON object")
            };
            let meta = DatasetMeta::new("import-uff", config, scene.clone(), env!("CARGO_PKG_VERSION"), seed, grid)
                .with_description(description);
            writer = Some(DatasetWriter::create(out, meta, IfExists::Refuse).map_err(|source| {
                InterchangeError::Dataset { what: format!("creating dataset {}", out.display()), source }
            })?);
        }
        if pending.len() >= BATCH_ROWS
            && let Some(w) = writer.as_mut()
        {
            w.commit_batch(&pending).map_err(InterchangeError::at(where_))?;
            pending.clear();
            progress(Progress { done: w.rows() as u64, total });
        }
        Ok(())
    })?;
    let Some(mut writer) = writer else { refuse!("no response was converted") };
    if !pending.is_empty() {
        writer.commit_batch(&pending)?;
    }
    let rows = writer.rows();
    progress(Progress { done: rows as u64, total });
    writer.finish()?;
    let (sample_rate_hz, ir_len) = shape.unwrap_or_default();
    Ok(ImportSummary { rows, from_frf, grid, sample_rate_hz, ir_len, skipped: survey.skipped })
}

/// The grid snapped from the response nodes, and each function's key (actuators: reference labels by rank).
fn keys_from_nodes(survey: &Survey, length_per_m: f64) -> Result<(GridSpec, Vec<(u32, u16)>), InterchangeError> {
    let responses: BTreeSet<u32> = survey.functions.iter().map(|s| s.response).collect();
    let references: BTreeSet<u32> = survey.functions.iter().map(|s| s.reference).collect();
    if references.len() > usize::from(u16::MAX) + 1 {
        refuse!("{} reference nodes: more actuators than a dataset numbers", references.len());
    }
    let mut labels = Vec::with_capacity(responses.len());
    let mut positions = Vec::with_capacity(responses.len());
    for &label in &responses {
        let Some(p) = survey.nodes.get(&label) else {
            refuse!("response node {label} has no coordinates (no dataset 2411 lists it): the grid cannot be placed")
        };
        labels.push(label);
        positions.push((p[0] / length_per_m, p[1] / length_per_m));
    }
    let (grid, indices) = snap_to_grid(&positions)
        .map_err(|source| InterchangeError::Grid { what: "placing the response nodes on a grid".into(), source })?;
    let point_of: HashMap<u32, u32> =
        labels.iter().zip(&indices).map(|(&label, &i)| (label, u32::try_from(i).unwrap_or(u32::MAX))).collect();
    let actuator_of: HashMap<u32, u16> =
        references.iter().enumerate().map(|(a, &label)| (label, u16::try_from(a).unwrap_or(u16::MAX))).collect();
    let keys = survey
        .functions
        .iter()
        .map(|s| (point_of.get(&s.response).copied().unwrap_or(0), actuator_of.get(&s.reference).copied().unwrap_or(0)))
        .collect();
    Ok((grid, keys))
}

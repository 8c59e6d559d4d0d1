//! A metaplate dataset from universal files (datasets 164, 2411, 58 and 58b), in two streaming passes over the
//! files (the first reads the headers, nodes and units; the second converts and commits, a batch at a time),
//! through the store's writer as the recipes write: manifest, journal, Parquet batches, checksums.
//!
//! - **What is read** (the survey, first pass): datasets 164, 2411, and the responses, datasets 58/58b of function
//!   type 1 or 4. Everything else, including datasets 58 of other function types (coherence, PSD, spectra), is
//!   stepped over unchecked ([`metaplate_uff::UffDecoder::only_functions`]) and listed ([`ImportSummary::skipped`]):
//!   it can neither fail the import nor number an actuator.
//! - **Grid and keys.** A file metaplate exported carries the grid and each response's (point, actuator) in its ID
//!   lines ([`IdLines`]): they are used as written. Otherwise (or with [`ImportOptions::grid_from_nodes`]) the grid
//!   comes from the response nodes' positions (dataset 2411, or [`ImportOptions::nodes`]): one point is a 1 x 1
//!   grid; points of constant z on an axis-aligned grid are snapped to it
//!   ([`metaplate_core::grid::snap_to_grid`]); else the lattice of their plane is fitted ([`crate::lattice`]);
//!   else they are kept as scattered points (`metaplate_store::ScatteredPoints`: each at its position in their
//!   plane, the grid only their index), which `analyze` and `focus` take as such. Nodes in 3-D are placed so even
//!   when the ID lines carry a grid (an import exported again). Each point's node (label, direction, position)
//!   and each reference's position are stored (`config.nodes`, `config.actuators`) for an export that keeps them. The actuators are the responses' (reference node, direction)
//!   pairs, numbered from 0 in ascending order ([`ImportSummary::actuators`], stored in the manifest's
//!   `config.actuators` with each reference's position in the grid's frame).
//! - **Sample rate:** from the abscissa step by [`metaplate_uff::sample_rate_from_step`] (the whole hertz within
//!   10⁻⁵ of `1 / step`).
//! - **Which function per (point, actuator):** the time response (function type 1) when the files hold one; else the
//!   frequency response function (type 4), turned into an impulse response: its bins placed on the grid of a real
//!   FFT of `n = 2 × (index of its last bin)` points at the file's frequency step (the band is the FRF's own,
//!   from its first to its last frequency, bins outside it zero, no taper; the last bin is taken as Nyquist), so the
//!   response is `n` samples long at `n × step` Hz, causal from time 0 (`pre_samples` 0).
//! - **Of several of one kind** for one (point, actuator): frequency responses by several estimators (ID line 2
//!   naming `H1`, `H2`, ... as Polytec PSV writes them) give the one [`ImportOptions::estimator`] names, else the
//!   first of [`crate::survey::ESTIMATORS`] present; responses in several directions at one point (a 3-D scan head's
//!   X, Y and Z) give the one along the axis nearest the points' plane normal, refused when that axis is more than
//!   [`crate::survey::MAX_AXIS_ANGLE_DEG`] from it. The others are listed as skipped; the choice is printed and
//!   stored (`config.estimator`, `config.response_direction`).
//! - **Units by quantity** (`crate::quantity`): velocity as it is, acceleration and displacement converted to
//!   velocity (÷ or × jω; time records through their FFT), in SI by dataset 164's factors or the units label; any
//!   other quantity refused by name unless [`ImportOptions::accept_unknown_quantity`]. Every imported response must
//!   have the first one's quantity and denominator. The `ir` unit is m/s/N over a force, m/s without a
//!   denominator, else "m/s per" its units label; the conversion is printed and stored (`config.ordinate`).
//! - **Metaplate's header** (dataset 151 of an export, `crate::header`): the `ir` unit in full where the responses
//!   say only "full scale" (a scan's), and the calibration a scan went through (`config.calibration`), so that an
//!   exported scan imported again plays through its calibration. Another tool's header is skipped.
//! - **Refusals** name the file, the record (ordinal, and the line of its opening delimiter), the line and field,
//!   and what would be accepted.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::SceneId;
use metaplate_store::{DatasetDescription, DatasetMeta, DatasetWriter, IfExists, IrMeta, IrRecord};
use metaplate_uff::UffRecord;
use serde_json::json;

use crate::convert::to_ir;
use crate::error::{InterchangeError, refuse};
use crate::quantity::{Denominator, OrdinateQuantity};
use crate::survey::{ActuatorRef, Plan, SkippedRecord, for_each_record, plan, read_nodes_csv, record_at, survey};
use crate::{IdLines, Progress};

/// Rows per committed batch file.
const BATCH_ROWS: usize = 256;

/// How to import.
#[derive(Debug, Clone, Default)]
pub struct ImportOptions {
    /// Take the grid from the nodes' positions even when the files carry metaplate's grid.
    pub grid_from_nodes: bool,
    /// Import an ordinate that is no motion (pressure, force, voltage, unknown) as it is, its unit declared unknown.
    pub accept_unknown_quantity: bool,
    /// A CSV file of node positions (`node,x_m,y_m[,z_m]`, metres), used in place of (and before) dataset 2411.
    pub nodes: Option<PathBuf>,
    /// Of frequency responses by several estimators for one pair, the one to import (one of
    /// [`crate::survey::ESTIMATORS`]); `None`: the first of them present.
    pub estimator: Option<String>,
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
    /// Where the grid came from: "metaplate ID lines", "nodes" (a regular grid), "one point", a lattice fitted in
    /// 3-D ("nodes on a lattice: ..."), or "scattered points: ..." (the grid is then their index).
    pub grid_from: String,
    /// The points lie on no lattice (`metaplate_store::ScatteredPoints`).
    pub scattered: bool,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Impulse response length, samples.
    pub ir_len: usize,
    /// The dataset's `ir` unit.
    pub ir_unit: String,
    /// What the ordinates were and how they became the `ir` (for example "acceleration (m/s²) from data type 12 ...,
    /// divided by jω").
    pub conversion: String,
    /// Which reference degree of freedom each actuator number stands for (also stored in the dataset).
    pub actuators: Vec<ActuatorRef>,
    /// Records stepped over: datasets not read (geometry, headers) and functions that are not responses
    /// (coherence, spectra, ...), in file order; then responses not chosen among several of one pair (another
    /// estimator, another direction).
    pub skipped: Vec<SkippedRecord>,
    /// The estimator imported where a pair had frequency responses by several.
    pub estimator: Option<&'static str>,
    /// The response direction imported where a point had responses in several (1 x, 2 y, 3 z).
    pub response_direction: Option<i8>,
    /// The content hash of the calibration a scan was measured through, restored from metaplate's header.
    pub calibration: Option<String>,
}

/// Builds the dataset `out` (which must not exist, or be empty) from the universal files `files`, read in order.
/// `progress` is told the responses committed, out of those the files hold.
///
/// # Errors
/// A file that cannot be read or is malformed (with the record and line), two response nodes at one position, a
/// response without its node, an ordinate that is no motion (unless [`ImportOptions::accept_unknown_quantity`]), responses
/// of different quantities, sample rates or lengths, a store error. Each names the file, the record and line, and
/// what would be accepted.
pub fn import(
    files: &[PathBuf],
    out: &Path,
    options: ImportOptions,
    mut progress: impl FnMut(Progress),
) -> Result<ImportSummary, InterchangeError> {
    let estimator = crate::survey::wanted_estimator(&options)?;
    let survey = survey(files, &options)?;
    let Some(first_ids) = survey.first_ids.clone() else {
        refuse!(
            "the files hold no response (a dataset 58 or 58b of function type 1, time response, or 4, frequency \
             response function){}",
            if survey.skipped.is_empty() {
                String::new()
            } else {
                format!("; skipped: {}", skipped_summary(&survey.skipped))
            }
        )
    };
    let length_per_m = survey.units.as_ref().map_or(1.0, |u| u.length_per_m);
    let force_per_n = survey.units.as_ref().map_or(1.0, |u| u.force_per_n);
    if !(length_per_m.is_finite() && length_per_m > 0.0 && force_per_n.is_finite() && force_per_n > 0.0) {
        refuse!(
            "dataset 164's length and force factors are {length_per_m} and {force_per_n}; finite positive factors are \
             accepted"
        );
    }
    // Positions in metres: the CSV's as given, else dataset 2411's in the file's length unit.
    let positions_m: HashMap<i64, [f64; 3]> = match &options.nodes {
        Some(csv) => read_nodes_csv(csv)?,
        None => survey.nodes.iter().map(|(&label, p)| (label, p.map(|v| v / length_per_m))).collect(),
    };
    let Plan { grid, by_at, grid_from, actuators, placed, frame, scattered, not_chosen, estimator, response_direction } =
        plan(files, &survey, &first_ids, &options, estimator, &positions_m)?;
    let skipped: Vec<SkippedRecord> = survey.skipped.iter().cloned().chain(not_chosen).collect();
    // The references' positions in the grid's frame, where a node gives them (for an export without a scene).
    let reference_at = |node: i64| -> Option<(f64, f64)> {
        let p = positions_m.get(&node)?;
        Some(match &frame {
            Some(frame) => frame.place(*p),
            None => (p[0], p[1]),
        })
    };
    let scene = IdLines::parse_scene(&first_ids[2])
        .unwrap_or_else(|| SceneId { name: "uff-import".into(), hash: "unknown".into() });
    let seed = IdLines::value(&first_ids[4], "seed").and_then(|v| v.parse().ok()).unwrap_or(0);
    let source_recipe = IdLines::value(&first_ids[4], "recipe").map(str::to_owned);
    let total = by_at.len() as u64;
    // The quantity of every imported response must be the first one's.
    let seen_at: HashMap<(usize, u64), usize> =
        survey.functions.iter().enumerate().map(|(i, seen)| (seen.at, i)).collect();
    let chosen = || by_at.keys().filter_map(|at| seen_at.get(at)).map(|&i| &survey.functions[i]);
    // Each point's original node (label, direction, position in the files' frame, m), for an export that keeps them.
    let mut point_nodes: Vec<(u32, i64, i8)> = by_at
        .iter()
        .filter_map(|(at, &(point, _))| seen_at.get(at).map(|&i| (point, &survey.functions[i])))
        .map(|(point, seen)| (point, seen.response, seen.response_direction))
        .collect();
    point_nodes.sort_unstable();
    point_nodes.dedup_by_key(|n| n.0);
    let Some(first) = chosen().min_by_key(|seen| seen.at) else { refuse!("no response was chosen") };
    let (motion, ordinate_to_si, conversion) = match &first.ordinate {
        OrdinateQuantity::Motion { motion, to_si, basis, .. } => {
            let how = match motion {
                crate::quantity::Motion::Velocity => "kept as velocity",
                crate::quantity::Motion::Acceleration => {
                    "converted to velocity: divided by jω (time responses through their FFT)"
                }
                crate::quantity::Motion::Displacement => {
                    "converted to velocity: multiplied by jω (time responses through their FFT)"
                }
            };
            (Some(*motion), *to_si, format!("{} from {basis}, {how}", motion.name()))
        }
        OrdinateQuantity::Other { name } => {
            (None, 1.0, format!("{name}, declared unknown (--accept-unknown-quantity): kept as it is"))
        }
    };
    if let Some(other) = chosen().find(|seen| seen.ordinate != first.ordinate || seen.denominator != first.denominator)
    {
        refuse!(
            "{}, lines {}-{}, records 9 and 10 (ordinate and denominator data characteristics): other quantities than              {}; one quantity over one denominator is accepted across the responses",
            record_at(files, other),
            other.line + 10,
            other.line + 11,
            record_at(files, first)
        );
    }
    // A metaplate export's header gives the unit in full where the responses' records say only "full scale".
    let over = match &first.denominator {
        Denominator::Other { label } => Some(label.as_str()),
        _ => None,
    };
    let restored_unit = survey
        .restored
        .as_ref()
        .and_then(|r| r.unit_over(over))
        .filter(|_| motion == Some(crate::quantity::Motion::Velocity));
    let ir_unit = match (motion, restored_unit) {
        (Some(_), Some(unit)) => unit.to_owned(),
        (Some(_), None) => first.denominator.ir_unit(),
        (None, _) => format!("declared unknown ({})", crate::quantity::describe_ordinate(&first.ordinate)),
    };
    let calibration = survey.restored.as_ref().and_then(|r| r.calibration.clone());
    let to_si = ordinate_to_si / first.denominator.to_si();
    progress(Progress { done: 0, total });

    // Second pass: convert and commit.
    let mut writer: Option<DatasetWriter> = None;
    let mut pending: Vec<IrRecord> = Vec::with_capacity(BATCH_ROWS);
    let mut from_frf = 0;
    let mut pre_samples = None;
    let mut spectrum = Vec::new();
    let mut shape = None;
    for_each_record(files, |f, ordinal, line, record| {
        let UffRecord::Function(function) = record else { return Ok(()) };
        let Some(&(point, actuator)) = by_at.get(&(f, ordinal)) else { return Ok(()) };
        let where_ = || format!("{} record {ordinal} (dataset 58 from line {line})", files[f].display());
        let converted = to_ir(&function, to_si, motion, &mut spectrum).map_err(InterchangeError::at(where_))?;
        from_frf += usize::from(converted.from_frf);
        match (pre_samples, shape) {
            (Some(p), Some((rate, len)))
                if p != converted.pre_samples || rate != converted.sample_rate_hz || len != converted.ir.len() =>
            {
                refuse!(
                    "{}, line {}, record 7 (data form): {} samples at {} Hz from {} samples before time 0; earlier \
             responses have {len} at {rate} Hz from {p}: one sample rate and length is accepted",
                    where_(),
                    line + 8,
                    converted.ir.len(),
                    converted.sample_rate_hz,
                    converted.pre_samples
                )
            }
            _ => {}
        }
        pre_samples.get_or_insert(converted.pre_samples);
        shape.get_or_insert((converted.sample_rate_hz, converted.ir.len()));
        let (ix, iy) = grid.indices(point as usize);
        let mut meta = IrMeta::at_grid(&grid, ix as u32, iy as u32, actuator, converted.sample_rate_hz)
            .map_err(InterchangeError::at(where_))?;
        if let Some(&(x_m, y_m)) = placed.get(&function.header.response.node) {
            (meta.x_m, meta.y_m) = (x_m, y_m);
        }
        let ids = &function.header.id_lines;
        let (status, snr_db, retries, measured_at) = IdLines::parse_quality(&ids[3]);
        (meta.status, meta.snr_db, meta.retries) = (status, snr_db, retries);
        meta.measured_at_unix_us = IdLines::parse_measured_at(&ids[0]).or(measured_at);
        meta.estimated_error_db = IdLines::parse_estimated_error(&ids[4]);
        pending.push(IrRecord { meta, ir: converted.ir });
        if writer.is_none() {
            let description = DatasetDescription { ir_unit: ir_unit.clone(), pre_samples: pre_samples.unwrap_or(0) };
            let config = json!({
                "files": files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
                "grid_from": grid_from,
                "nodes_csv": options.nodes.as_ref().map(|p| p.display().to_string()),
                "source_recipe": source_recipe,
                "sample_rate_rule": "1/step rounded to the whole hertz within 1e-5 (metaplate_uff::sample_rate_from_step)",
                "frf_to_ir": "the FRF's own band, bins outside it zero, no taper; n = 2 x last bin index, causal",
                "ordinate": conversion,
                "actuators": actuators.iter().map(|a| {
                    let at = reference_at(a.reference_node);
                    json!({
                        "actuator": a.actuator,
                        "reference_node": a.reference_node,
                        "direction": a.direction,
                        "x_m": at.map(|p| p.0),
                        "y_m": at.map(|p| p.1),
                        "position_m": positions_m.get(&a.reference_node),
                    })
                }).collect::<Vec<_>>(),
                "nodes": point_nodes.iter().map(|&(point, node, direction)| json!({
                    "point": point,
                    "node": node,
                    "direction": direction,
                    "position_m": positions_m.get(&node),
                })).collect::<Vec<_>>(),
                "skipped": skipped_summary(&skipped),
                "estimator": estimator,
                "response_direction": response_direction,
            });
            let serde_json::Value::Object(mut config) = config else {
                refuse!("internal: configuration is not a JSON object")
            };
            // The calibration a scan went through, as the scan's own configuration names it (`play` checks it).
            if let Some(hash) = &calibration {
                config.insert("calibration".into(), json!(hash));
            }
            let mut meta = DatasetMeta::new("import-uff", config, scene.clone(), env!("CARGO_PKG_VERSION"), seed, grid)
                .with_description(description);
            if let Some(scattered) = scattered.clone() {
                meta = meta.with_scattered(scattered);
            }
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
    Ok(ImportSummary {
        rows,
        from_frf,
        grid,
        grid_from,
        scattered: scattered.is_some(),
        sample_rate_hz,
        ir_len,
        ir_unit,
        conversion,
        actuators,
        skipped,
        estimator,
        response_direction,
        calibration,
    })
}

impl ImportSummary {
    /// Where the points are, for the import's report: `143 scattered points`, or `4 x 3 grid at 5 mm`.
    pub fn placement(&self) -> String {
        if self.scattered {
            format!("{} scattered points", self.grid.len())
        } else {
            format!("{} x {} grid at {} mm", self.grid.nx, self.grid.ny, self.grid.spacing_m * 1e3)
        }
    }
}

/// The skipped records counted by kind, each kind with its first place: `3 x dataset 58, function type 6
/// (coherence) (first: a.uff record 4, line 120)`.
pub fn skipped_summary(skipped: &[SkippedRecord]) -> String {
    let mut kinds: Vec<(&str, usize, &SkippedRecord)> = Vec::new();
    for record in skipped {
        match kinds.iter_mut().find(|(what, _, _)| *what == record.what) {
            Some((_, count, _)) => *count += 1,
            None => kinds.push((&record.what, 1, record)),
        }
    }
    let parts: Vec<String> = kinds
        .iter()
        .map(|(what, count, first)| {
            format!("{count} x {what} (first: {} record {}, line {})", first.file, first.record, first.line)
        })
        .collect();
    parts.join("; ")
}

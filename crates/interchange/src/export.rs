//! A dataset as a universal file (UFF datasets 164, 2411 and 58 or 58b), streamed.
//!
//! The file holds, in this order: dataset 151 (the header: the dataset's name, its `ir` unit in full, the calibration
//! a scan went through: `crate::header`); dataset 164 (SI units); dataset 2411 (one node per grid point the dataset
//! commits, labelled `point_index + 1`, at its nominal grid position, z = 0; then one reference node per actuator,
//! labelled `nx * ny + 1 + actuator`, at the actuator's magnet); then per committed (point, actuator) one dataset
//! 58/58b: the impulse response (function type 1, time from `-pre_samples / fs`), and with
//! [`ExportOptions::frequency`] also the frequency response (type 4: the FFT of the impulse response referred to time
//! 0, 0 Hz to Nyquist, complex). Ordinates are velocity (m/s) over force (N) for a dataset whose `ir` is in m/s/N, over
//! nothing for one in m/s (an imported operational record), a declared-unknown quantity as data type 0 "unknown";
//! otherwise velocity over "full-scale drive" (data type 0, unknown), as the dataset's description says.
//!
//! The ID lines carry what an import needs to rebuild the dataset's rows exactly ([`IdLines`](crate::IdLines)); the
//! header what belongs to the dataset as a whole. Other tools show both as text.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::fft;
use metaplate_store::{BatchRows, Dataset, DatasetMeta, IR_UNIT_M_S_PER_N, Manifest, ReadOptions};
use metaplate_uff::{
    AxisCharacteristics, Complex64, Dof, Format, FunctionHeader, FunctionType, Node, Nodes2411, OrdinateRef, Precision,
    UffEncoder, UffRecord, Units164,
};

use crate::Progress;
use crate::error::{InterchangeError, refuse};
use crate::id_lines::SharedIds;

/// How to export.
#[derive(Debug, Clone, Copy)]
pub struct ExportOptions {
    /// ASCII or binary (with its byte order).
    pub format: Format,
    /// Single or double precision.
    pub precision: Precision,
    /// Also write the frequency response functions.
    pub frequency: bool,
    /// Only these points of the grid (an evenly spread subset); all when `None`.
    pub points: Option<GridSubset>,
}

/// What an export wrote.
#[derive(Debug, Clone, Copy)]
pub struct ExportSummary {
    /// Datasets 58/58b written.
    pub records: u64,
    /// Bytes written.
    pub bytes: u64,
    /// Wall-clock seconds.
    pub elapsed_s: f64,
}

/// `DIR.uff` beside the dataset directory `DIR`.
///
/// # Errors
/// [`InterchangeError::Refused`] for a path without a directory name (`/`, `..`).
pub fn default_out(data: &Path) -> Result<PathBuf, InterchangeError> {
    let Some(name) = data.file_name() else { refuse!("--data {} has no directory name: give --out", data.display()) };
    let mut file = name.to_os_string();
    file.push(".uff");
    Ok(data.with_file_name(file))
}

/// The actuators' magnet positions (x, y), m, indexed by actuator number: from the scene file `scene_file`, else
/// from the reference nodes an import of universal files placed (so that an imported dataset exports as it came),
/// else from the built-in scene of the dataset in `data` when its id matches.
///
/// # Errors
/// An unreadable scene file or dataset; [`InterchangeError::Refused`] when the dataset's scene is not a built-in
/// one and no scene file is given.
pub fn actuator_sites(data: &Path, scene_file: Option<&Path>) -> Result<Vec<(f64, f64)>, InterchangeError> {
    let scene = match scene_file {
        Some(path) => Scene::load(path)
            .map_err(|source| InterchangeError::Scene { what: format!("reading scene {}", path.display()), source })?,
        None => {
            let manifest = Manifest::read(data).map_err(|source| InterchangeError::Dataset {
                what: format!("opening dataset {}", data.display()),
                source,
            })?;
            let id = &manifest.meta.scene;
            if let Some(sites) = imported_sites(&manifest.meta.config)? {
                return Ok(sites);
            }
            match Scene::builtin(&id.name).ok().filter(|s| s.id() == *id) {
                Some(scene) => scene,
                None => refuse!(
                    "the actuators' positions are unknown: the dataset's scene {:?} is not a built-in one; give the \
                     scene file with --scene",
                    id.name
                ),
            }
        }
    };
    Ok(scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect())
}

/// The actuators' positions an import stored (its `actuators` mapping, in the grid's frame), indexed by actuator
/// number; `None` for a dataset that is no import of universal files with references placed.
///
/// # Errors
/// [`InterchangeError::Refused`] naming an actuator whose reference node had no position in the imported files.
fn imported_sites(
    config: &serde_json::Map<String, serde_json::Value>,
) -> Result<Option<Vec<(f64, f64)>>, InterchangeError> {
    let Some(serde_json::Value::Array(actuators)) = config.get("actuators") else { return Ok(None) };
    let mut sites = vec![None; actuators.len()];
    for a in actuators {
        let number = a["actuator"].as_u64().and_then(|n| usize::try_from(n).ok());
        let Some(slot) = number.and_then(|n| sites.get_mut(n)) else { return Ok(None) };
        *slot = match (a["x_m"].as_f64(), a["y_m"].as_f64()) {
            (Some(x), Some(y)) => Some((x, y)),
            _ => refuse!(
                "actuator {} (reference node {}, direction {}) has no position: the imported files place no such node; \
                 give the actuators' positions with --scene FILE",
                a["actuator"],
                a["reference_node"],
                a["direction"]
            ),
        };
    }
    Ok(sites.into_iter().collect())
}

/// Writes the dataset in `data` to the universal file `out`, streaming (one batch file at a time);
/// `actuator_sites` are the reference nodes' positions, m, indexed by actuator number. `progress` is told each
/// response written, out of the committed responses of the selected points.
///
/// # Errors
/// An unreadable dataset, an actuator without a position, a value the format cannot hold, a failed write.
pub fn export(
    data: &Path,
    out: &Path,
    options: &ExportOptions,
    actuator_sites: &[(f64, f64)],
    mut progress: impl FnMut(Progress),
) -> Result<ExportSummary, InterchangeError> {
    let started = std::time::Instant::now();
    let manifest = Manifest::read(data)
        .map_err(|source| InterchangeError::Dataset { what: format!("opening dataset {}", data.display()), source })?;
    let meta = &manifest.meta;
    let grid = meta.grid;
    let selected: Option<Vec<bool>> = match options.points {
        Some(subset) => {
            let mut mask = vec![false; grid.len()];
            let indices = subset
                .indices(&grid)
                .map_err(|source| InterchangeError::Grid { what: format!("--points {subset}"), source })?;
            for i in indices {
                mask[i] = true;
            }
            Some(mask)
        }
        None => None,
    };
    let wanted = |point: u32| selected.as_ref().is_none_or(|m| m.get(point as usize).copied().unwrap_or(false));
    let keys = Dataset::committed_keys(data)?.unwrap_or_default();
    let mut points: Vec<u32> = keys.iter().map(|k| k.0).filter(|&p| wanted(p)).collect();
    points.dedup();
    let mut actuators: Vec<u16> = keys.iter().map(|k| k.1).collect();
    actuators.sort_unstable();
    actuators.dedup();
    let per_pair = if options.frequency { 2 } else { 1 };
    let total = keys.iter().filter(|k| wanted(k.0)).count() as u64;

    let file = File::create(out)
        .map_err(|source| InterchangeError::File { what: format!("creating {}", out.display()), source })?;
    let mut sink = BufWriter::with_capacity(1 << 20, file);
    let encoder = UffEncoder::new(options.format, options.precision);
    let mut buffer = Vec::with_capacity(1 << 20);
    encoder.encode(&UffRecord::Header(Box::new(crate::header::for_dataset(data, meta))), &mut buffer)?;
    encoder.encode(&UffRecord::Units(Units164::si()), &mut buffer)?;
    let labels = NodeLabels::of(meta);
    let mut nodes: Vec<Node> = Vec::with_capacity(points.len() + actuators.len());
    for &point in &points {
        let (dof, position_m) = labels.point(point);
        nodes.extend(node(dof.node, position_m));
    }
    for &actuator in &actuators {
        let Some(&(x_m, y_m)) = actuator_sites.get(usize::from(actuator)) else {
            refuse!("actuator {actuator} has no position in the scene ({} actuators)", actuator_sites.len());
        };
        let (dof, original_m) = labels.reference(actuator);
        nodes.extend(node(dof.node, original_m.unwrap_or([x_m, y_m, 0.0])));
    }
    // A reference at a response node (a lab's reference transducer on a scan point) is one node.
    let mut seen = std::collections::HashSet::new();
    nodes.retain(|n| seen.insert(n.label));
    encoder.encode(&UffRecord::Nodes(Nodes2411 { nodes }), &mut buffer)?;
    sink.write_all(&buffer)?;
    let mut bytes = buffer.len() as u64;
    buffer.clear();

    progress(Progress { done: 0, total });
    let shared = SharedIds::new(meta);
    let mut done = 0u64;
    let mut writer = RecordWriter {
        encoder,
        axes: axes(meta),
        pre_samples: meta.description.as_ref().map_or(0, |d| d.pre_samples),
        frequency: options.frequency,
        samples: Vec::new(),
        spectrum: Vec::new(),
    };
    Dataset::stream(data, ReadOptions::default(), |batch: BatchRows<'_>| -> Result<(), InterchangeError> {
        for (row, ir) in batch.iter() {
            if !wanted(row.point_index) {
                continue;
            }
            let dofs = (labels.point(row.point_index).0, labels.reference(row.actuator).0);
            writer.encode(&shared.for_row(row), dofs, row.sample_rate_hz, ir, &mut buffer)?;
            sink.write_all(&buffer)?;
            bytes += buffer.len() as u64;
            buffer.clear();
            done += 1;
            progress(Progress { done, total });
        }
        Ok(())
    })
    .map_err(InterchangeError::at(|| format!("exporting {} to {}", data.display(), out.display())))?;
    sink.flush()?;
    sink.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    Ok(ExportSummary { records: done * per_pair, bytes, elapsed_s: started.elapsed().as_secs_f64() })
}

/// The nodes an export writes: a dataset imported from universal files keeps its files' node labels, directions
/// and 3-D positions (the import's `nodes` and `actuators` mappings); any other numbers grid points from 1
/// (`point_index + 1`, at their position with z = 0, direction +Z) and actuators after them (`nx * ny + 1 +
/// actuator`, at their magnets).
struct NodeLabels {
    /// Point index -> its original node, direction and position, m.
    points: HashMap<u32, (Dof, [f64; 3])>,
    /// Actuator -> its original reference node, direction, and position where the files gave one, m.
    references: HashMap<u16, (Dof, Option<[f64; 3]>)>,
    /// Positions of points without an original node, m.
    meta: DatasetMeta,
}

impl NodeLabels {
    fn of(meta: &DatasetMeta) -> Self {
        let dof = |v: &serde_json::Value, node: &str, direction: &str| -> Option<Dof> {
            let direction = i8::try_from(v[direction].as_i64()?).ok()?;
            Some(Dof { entity: "NONE".to_owned(), node: v[node].as_i64()?, direction })
        };
        let position = |v: &serde_json::Value| -> Option<[f64; 3]> {
            let p = v["position_m"].as_array()?;
            match p.as_slice() {
                [x, y, z] => Some([x.as_f64()?, y.as_f64()?, z.as_f64()?]),
                _ => None,
            }
        };
        let list = |key: &str| meta.config.get(key).and_then(|v| v.as_array()).cloned().unwrap_or_default();
        let points: HashMap<u32, (Dof, [f64; 3])> = list("nodes")
            .iter()
            .filter_map(|v| {
                let point = u32::try_from(v["point"].as_u64()?).ok()?;
                Some((point, (dof(v, "node", "direction")?, position(v)?)))
            })
            .collect();
        // Only with the points' nodes: the references' labels alone could collide with the numbered points'.
        let references = if points.is_empty() {
            HashMap::new()
        } else {
            list("actuators")
                .iter()
                .filter_map(|v| {
                    let actuator = u16::try_from(v["actuator"].as_u64()?).ok()?;
                    Some((actuator, (dof(v, "reference_node", "direction")?, position(v))))
                })
                .collect()
        };
        Self { points, references, meta: meta.clone() }
    }

    /// The response degree of freedom of `point` and its node's position, m.
    fn point(&self, point: u32) -> (Dof, [f64; 3]) {
        if let Some((dof, p)) = self.points.get(&point) {
            return (dof.clone(), *p);
        }
        let (x_m, y_m) = self.meta.position_m(point as usize).unwrap_or_default();
        (Dof::z(point + 1), [x_m, y_m, 0.0])
    }

    /// The reference degree of freedom of `actuator`, and its original position, m, when the files gave one.
    fn reference(&self, actuator: u16) -> (Dof, Option<[f64; 3]>) {
        match self.references.get(&actuator) {
            Some((dof, p)) => (dof.clone(), *p),
            None => {
                let label = u32::try_from(self.meta.grid.len()).unwrap_or(u32::MAX - u32::from(u16::MAX) - 1);
                (Dof::z(label + 1 + u32::from(actuator)), None)
            }
        }
    }
}

/// A node of the default coordinate systems at `position_m`; none for a label no node can have (0 or negative:
/// "no node" to some writers, or beyond the format's).
fn node(label: i64, position_m: [f64; 3]) -> Option<Node> {
    let label = u32::try_from(label).ok().filter(|&l| l > 0)?;
    Some(Node { label, export_coordinate_system: 1, displacement_coordinate_system: 1, color: 11, position_m })
}

/// The ordinate and denominator characteristics of the dataset's `ir`: velocity per newton (the ground truth, or an
/// import of such); velocity alone (an import of operational records, `ir` in "m/s"); a quantity an import was told
/// to take as declared unknown (data type 0, no denominator: no unit it is not); else velocity per full-scale drive.
fn axes(meta: &DatasetMeta) -> (AxisCharacteristics, AxisCharacteristics) {
    let velocity = AxisCharacteristics::new(11, "Velocity", "m/s");
    let unit = match &meta.description {
        Some(description) => description.ir_unit.as_str(),
        // Written before datasets described themselves: only the simulation's ground truth was per newton.
        None if meta.recipe == "simulate-greens" => IR_UNIT_M_S_PER_N,
        None => "",
    };
    match unit {
        IR_UNIT_M_S_PER_N => (velocity, AxisCharacteristics::new(13, "Force", "N")),
        "m/s" => (velocity, AxisCharacteristics::unused()),
        u if u.starts_with("declared unknown") => {
            (AxisCharacteristics::new(0, "Declared unknown", "unknown"), AxisCharacteristics::unused())
        }
        _ => (velocity, AxisCharacteristics::new(0, "Drive", "full scale")),
    }
}

/// Encodes responses of one dataset, reusing its buffers.
struct RecordWriter {
    encoder: UffEncoder,
    /// The ordinate's and denominator's characteristics.
    axes: (AxisCharacteristics, AxisCharacteristics),
    /// Samples before time 0 of every response.
    pre_samples: u32,
    /// Also the frequency response.
    frequency: bool,
    samples: Vec<f64>,
    spectrum: Vec<Complex64>,
}

impl RecordWriter {
    /// Encodes the impulse response `ir` (and its FRF with `frequency`) of the (response, reference) degrees of
    /// freedom into `out`.
    fn encode(
        &mut self,
        ids: &[String; 5],
        (response, reference): (Dof, Dof),
        sample_rate_hz: f64,
        ir: &[f32],
        out: &mut Vec<u8>,
    ) -> Result<(), InterchangeError> {
        self.samples.clear();
        self.samples.extend(ir.iter().map(|&v| f64::from(v)));
        let dt_s = 1.0 / sample_rate_hz;
        let start_s = -f64::from(self.pre_samples) * dt_s;
        let mut header = FunctionHeader::velocity_over_force(FunctionType::TimeResponse, 0, 0, start_s, dt_s, "");
        (header.response, header.reference) = (response, reference);
        header.id_lines = ids.clone();
        (header.ordinate, header.denominator) = self.axes.clone();
        self.encoder.encode_function(&header, OrdinateRef::Real(&self.samples), out)?;
        if self.frequency {
            let n = self.samples.len();
            self.spectrum.resize(fft::bin_count(n), Complex64::new(0.0, 0.0));
            fft::forward_into(&self.samples, n, &mut self.spectrum)?;
            // Referred to time 0: the first sample is at -pre_samples / fs.
            for (k, bin) in self.spectrum.iter_mut().enumerate() {
                let phase = 2.0 * std::f64::consts::PI * (k as f64) * f64::from(self.pre_samples) / n as f64;
                *bin *= Complex64::from_polar(1.0, phase);
            }
            header.function_type = FunctionType::FrequencyResponse;
            header.abscissa = AxisCharacteristics::new(18, "Frequency", "Hz");
            header.abscissa_start = 0.0;
            header.abscissa_step = sample_rate_hz / n as f64;
            self.encoder.encode_function(&header, OrdinateRef::Complex(&self.spectrum), out)?;
        }
        Ok(())
    }
}

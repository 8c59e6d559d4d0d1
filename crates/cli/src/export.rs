//! `metaplate export`: a dataset as a universal file (UFF datasets 164, 2411 and 58 or 58b), streamed.
//!
//! The file holds, in this order: dataset 164 (SI units); dataset 2411 (one node per grid point the dataset
//! commits, labelled `point_index + 1`, at its nominal grid position, z = 0; then one reference node per actuator,
//! labelled `nx * ny + 1 + actuator`, at the actuator's magnet); then per committed (point, actuator) one dataset
//! 58/58b: the impulse response (function type 1, time from `-pre_samples / fs`), and with `--frequency` also the
//! frequency response (type 4: the FFT of the impulse response referred to time 0, 0 Hz to Nyquist, complex).
//! Ordinates are velocity (m/s) over force (N) for a dataset whose `ir` is in m/s/N; otherwise over "full-scale
//! drive" (data type 0, unknown), as the dataset's description says.
//!
//! The ID lines carry what a metaplate import needs to rebuild the dataset exactly ([`IdLines`]); other tools show
//! them as text.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, ValueEnum};
use metaplate_core::grid::{GridSpec, GridSubset};
use metaplate_core::scene::{Scene, SceneId};
use metaplate_dsp::fft;
use metaplate_store::{BatchRows, Dataset, DatasetMeta, IR_UNIT_M_S_PER_N, IrMeta, Manifest, ReadOptions, Status};
use metaplate_uff::{
    AxisCharacteristics, ByteOrder, Complex64, Format, FunctionHeader, FunctionType, Node, Nodes2411, OrdinateRef,
    Precision, UffEncoder, UffRecord, Units164,
};

use crate::progress;

/// Arguments of `metaplate export`.
#[derive(Args)]
pub struct ExportArgs {
    /// Dataset directory.
    #[arg(long)]
    data: PathBuf,
    /// `uff58` (ASCII) or `uff58b` (binary).
    #[arg(long, value_enum)]
    format: UffFormat,
    /// Output file (default: the dataset directory's name with `.uff`, beside it).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Only the points of an evenly spread NXxNY subset of the dataset's grid (for example 7x5).
    #[arg(long)]
    points: Option<GridSubset>,
    /// Also write each frequency response function (type 4, complex) after its impulse response.
    #[arg(long)]
    frequency: bool,
    /// Precision of the values: single (6 significant digits in ASCII, f32 in binary) or double.
    #[arg(long, value_enum, default_value_t = PrecisionArg::Single)]
    precision: PrecisionArg,
    /// Byte order of a binary (uff58b) file.
    #[arg(long, value_enum, default_value_t = ByteOrderArg::Little)]
    byte_order: ByteOrderArg,
    /// A scene file giving the actuators' positions (default: the dataset's built-in scene, when it is one).
    #[arg(long)]
    scene: Option<PathBuf>,
}

/// The file format.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UffFormat {
    /// Dataset 58, 80-column ASCII.
    Uff58,
    /// Dataset 58b, binary values.
    Uff58b,
}

/// Precision of the values.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PrecisionArg {
    /// Single.
    Single,
    /// Double.
    Double,
}

/// Byte order of binary values.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ByteOrderArg {
    /// Least significant byte first.
    Little,
    /// Most significant byte first.
    Big,
}

/// Runs `metaplate export`.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let out = match &args.out {
        Some(out) => out.clone(),
        None => default_out(&args.data)?,
    };
    let format = match args.format {
        UffFormat::Uff58 => Format::Ascii,
        UffFormat::Uff58b => Format::Binary {
            byte_order: match args.byte_order {
                ByteOrderArg::Little => ByteOrder::LittleEndian,
                ByteOrderArg::Big => ByteOrder::BigEndian,
            },
        },
    };
    let precision = match args.precision {
        PrecisionArg::Single => Precision::Single,
        PrecisionArg::Double => Precision::Double,
    };
    let options = ExportOptions { format, precision, frequency: args.frequency, points: args.points };
    let actuator_sites = actuator_sites(&args.data, args.scene.as_deref())?;
    let summary = export(&args.data, &out, &options, &actuator_sites)?;
    eprintln!(
        "wrote {} ({} records, {:.1} MB in {:.2} s: {:.1} MB/s, {:.0} records/s)",
        out.display(),
        summary.records,
        summary.bytes as f64 / 1e6,
        summary.elapsed_s,
        summary.bytes as f64 / 1e6 / summary.elapsed_s.max(1e-9),
        summary.records as f64 / summary.elapsed_s.max(1e-9),
    );
    Ok(())
}

/// `DIR.uff` beside the dataset directory `DIR`.
fn default_out(data: &Path) -> anyhow::Result<PathBuf> {
    let Some(name) = data.file_name() else { bail!("--data {} has no directory name: give --out", data.display()) };
    let mut file = name.to_os_string();
    file.push(".uff");
    Ok(data.with_file_name(file))
}

/// How to export.
#[derive(Debug, Clone, Copy)]
pub struct ExportOptions {
    /// ASCII or binary (with its byte order).
    pub format: Format,
    /// Single or double precision.
    pub precision: Precision,
    /// Also write the frequency response functions.
    pub frequency: bool,
    /// Only these points of the grid.
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

/// The actuators' magnet positions (x, y), m: from `scene_file`, else from the dataset's built-in scene when its id
/// matches.
fn actuator_sites(data: &Path, scene_file: Option<&Path>) -> anyhow::Result<Vec<(f64, f64)>> {
    let scene = match scene_file {
        Some(path) => Scene::load(path).with_context(|| format!("reading scene {}", path.display()))?,
        None => {
            let manifest = Manifest::read(data).with_context(|| format!("opening dataset {}", data.display()))?;
            let id = &manifest.meta.scene;
            match Scene::builtin(&id.name).ok().filter(|s| s.id() == *id) {
                Some(scene) => scene,
                None => bail!(
                    "the actuators' positions are unknown: the dataset's scene {:?} is not a built-in one; give the \
                     scene file with --scene",
                    id.name
                ),
            }
        }
    };
    Ok(scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect())
}

/// Writes the dataset in `data` to the universal file `out`, streaming (one batch file at a time), with a progress
/// bar; `actuator_sites` are the reference nodes' positions, m, indexed by actuator number.
///
/// # Errors
/// An unreadable dataset, an actuator without a position, a value the format cannot hold, a failed write.
pub fn export(
    data: &Path,
    out: &Path,
    options: &ExportOptions,
    actuator_sites: &[(f64, f64)],
) -> anyhow::Result<ExportSummary> {
    let started = std::time::Instant::now();
    let manifest = Manifest::read(data).with_context(|| format!("opening dataset {}", data.display()))?;
    let meta = &manifest.meta;
    let grid = meta.grid;
    let selected: Option<Vec<bool>> = match options.points {
        Some(subset) => {
            let mut mask = vec![false; grid.len()];
            for i in subset.indices(&grid).with_context(|| format!("--points {subset}"))? {
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

    let file = File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let mut sink = BufWriter::with_capacity(1 << 20, file);
    let encoder = UffEncoder::new(options.format, options.precision);
    let mut buffer = Vec::with_capacity(1 << 20);
    encoder.encode(&UffRecord::Units(Units164::si()), &mut buffer)?;
    let reference_label = |actuator: u16| grid_label_count(&grid) + 1 + u32::from(actuator);
    let mut nodes = Vec::with_capacity(points.len() + actuators.len());
    for &point in &points {
        let (x_m, y_m) = grid.position_m(point as usize);
        nodes.push(node(point + 1, x_m, y_m));
    }
    for &actuator in &actuators {
        let Some(&(x_m, y_m)) = actuator_sites.get(usize::from(actuator)) else {
            bail!("actuator {actuator} has no position in the scene ({} actuators)", actuator_sites.len());
        };
        nodes.push(node(reference_label(actuator), x_m, y_m));
    }
    encoder.encode(&UffRecord::Nodes(Nodes2411 { nodes }), &mut buffer)?;
    sink.write_all(&buffer)?;
    let mut bytes = buffer.len() as u64;
    buffer.clear();

    let bar = progress::bar(total, "exporting");
    let force_denominator = ir_is_per_newton(meta);
    let shared = SharedIds::new(meta);
    let mut records = 0u64;
    let mut writer = RecordWriter::default();
    Dataset::stream(data, ReadOptions::default(), |batch: BatchRows<'_>| -> anyhow::Result<()> {
        for (row, ir) in batch.iter() {
            if !wanted(row.point_index) {
                continue;
            }
            let ids = shared.for_row(row);
            let labels = (row.point_index + 1, reference_label(row.actuator));
            writer.encode(
                &encoder,
                &ids,
                labels,
                row.sample_rate_hz,
                ir,
                meta,
                force_denominator,
                options,
                &mut buffer,
            )?;
            sink.write_all(&buffer)?;
            bytes += buffer.len() as u64;
            buffer.clear();
            records += per_pair;
            bar.inc(1);
        }
        Ok(())
    })
    .with_context(|| format!("exporting {} to {}", data.display(), out.display()))?;
    sink.flush()?;
    sink.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    bar.finish_and_clear();
    Ok(ExportSummary { records, bytes, elapsed_s: started.elapsed().as_secs_f64() })
}

/// Node labels of the grid points (`1..=nx * ny`), so that actuators number after them.
fn grid_label_count(grid: &GridSpec) -> u32 {
    u32::try_from(grid.len()).unwrap_or(u32::MAX - u32::from(u16::MAX) - 1)
}

/// A node of the default coordinate systems at (x, y, 0).
fn node(label: u32, x_m: f64, y_m: f64) -> Node {
    Node {
        label,
        export_coordinate_system: 1,
        displacement_coordinate_system: 1,
        color: 11,
        position_m: [x_m, y_m, 0.0],
    }
}

/// Whether the dataset's `ir` is velocity per newton (the ground truth, or an import of such), rather than per
/// full-scale drive.
fn ir_is_per_newton(meta: &DatasetMeta) -> bool {
    match &meta.description {
        Some(description) => description.ir_unit == IR_UNIT_M_S_PER_N,
        // Written before datasets described themselves: only the simulation's ground truth was per newton.
        None => meta.recipe == "simulate-greens",
    }
}

/// Reusable buffers of one exported response.
#[derive(Default)]
struct RecordWriter {
    samples: Vec<f64>,
    spectrum: Vec<Complex64>,
}

impl RecordWriter {
    /// Encodes the impulse response `ir` (and its FRF with `options.frequency`) into `out`.
    #[allow(clippy::too_many_arguments)] // One call site; a struct would only rename them.
    fn encode(
        &mut self,
        encoder: &UffEncoder,
        ids: &[String; 5],
        (response, reference): (u32, u32),
        sample_rate_hz: f64,
        ir: &[f32],
        meta: &DatasetMeta,
        per_newton: bool,
        options: &ExportOptions,
        out: &mut Vec<u8>,
    ) -> anyhow::Result<()> {
        let pre_samples = meta.description.as_ref().map_or(0, |d| d.pre_samples);
        self.samples.clear();
        self.samples.extend(ir.iter().map(|&v| f64::from(v)));
        let dt_s = 1.0 / sample_rate_hz;
        let start_s = -f64::from(pre_samples) * dt_s;
        let mut header =
            FunctionHeader::velocity_over_force(FunctionType::TimeResponse, response, reference, start_s, dt_s, "");
        header.id_lines = ids.clone();
        if !per_newton {
            header.denominator = AxisCharacteristics::new(0, "Drive", "full scale");
        }
        encoder.encode_function(&header, OrdinateRef::Real(&self.samples), out)?;
        if options.frequency {
            let n = self.samples.len();
            self.spectrum.resize(fft::bin_count(n), Complex64::new(0.0, 0.0));
            fft::forward_into(&self.samples, n, &mut self.spectrum)?;
            // Referred to time 0: the first sample is at -pre_samples / fs.
            for (k, bin) in self.spectrum.iter_mut().enumerate() {
                let phase = 2.0 * std::f64::consts::PI * (k as f64) * f64::from(pre_samples) / n as f64;
                *bin *= Complex64::from_polar(1.0, phase);
            }
            header.function_type = FunctionType::FrequencyResponse;
            header.abscissa = AxisCharacteristics::new(18, "Frequency", "Hz");
            header.abscissa_start = 0.0;
            header.abscissa_step = sample_rate_hz / n as f64;
            encoder.encode_function(&header, OrdinateRef::Complex(&self.spectrum), out)?;
        }
        Ok(())
    }
}

/// The ID lines of metaplate's records: `metaplate KEY=VALUE ...`, values without spaces.
///
/// 1. `metaplate point=P actuator=A`: the dataset key;
/// 2. `metaplate grid=NXxNY spacing_m=H origin_m=X0,Y0`: the dataset's grid;
/// 3. `metaplate scene=NAME scene_hash=HASH`: the scene id;
/// 4. `metaplate status=S snr_db=X retries=R measured_at_us=T`: the row's quality (absent keys: not recorded);
/// 5. `metaplate recipe=R seed=S [estimated_error_db=E]`: where the dataset came from, and the row's estimated error
///    when it has one (line 4 is full).
///
/// Spaces inside a value are written `_`; a line is cut at 80 columns.
pub struct IdLines;

/// The parts of the ID lines shared by every row of a dataset.
struct SharedIds {
    grid: String,
    scene: String,
    source: String,
}

impl SharedIds {
    fn new(meta: &DatasetMeta) -> Self {
        let g = &meta.grid;
        Self {
            grid: IdLines::grid(g),
            scene: cut(format!("metaplate scene={} scene_hash={}", word(&meta.scene.name), word(&meta.scene.hash))),
            source: cut(format!("metaplate recipe={} seed={}", word(&meta.recipe), meta.seed)),
        }
    }

    fn for_row(&self, row: &IrMeta) -> [String; 5] {
        let mut quality = String::from("metaplate");
        if let Some(status) = row.status {
            quality.push_str(&format!(" status={}", status.as_str()));
        }
        if let Some(snr_db) = row.snr_db {
            quality.push_str(&format!(" snr_db={snr_db}"));
        }
        if let Some(retries) = row.retries {
            quality.push_str(&format!(" retries={retries}"));
        }
        if let Some(t) = row.measured_at_unix_us {
            quality.push_str(&format!(" measured_at_us={t}"));
        }
        let source = match row.estimated_error_db {
            Some(e) => cut(format!("{} estimated_error_db={e}", self.source)),
            None => self.source.clone(),
        };
        [
            format!("metaplate point={} actuator={}", row.point_index, row.actuator),
            self.grid.clone(),
            self.scene.clone(),
            cut(quality),
            source,
        ]
    }
}

impl IdLines {
    /// ID line 2 for `grid`.
    fn grid(g: &GridSpec) -> String {
        cut(format!(
            "metaplate grid={}x{} spacing_m={} origin_m={},{}",
            g.nx, g.ny, g.spacing_m, g.origin_x_m, g.origin_y_m
        ))
    }

    /// The `KEY=VALUE` pairs of a metaplate ID line, or `None` for a line metaplate did not write.
    pub fn pairs(line: &str) -> Option<Vec<(&str, &str)>> {
        let rest = line.trim().strip_prefix("metaplate ")?;
        Some(rest.split_whitespace().filter_map(|w| w.split_once('=')).collect())
    }

    /// The value of `key` in a metaplate ID line.
    pub fn value<'a>(line: &'a str, key: &str) -> Option<&'a str> {
        Self::pairs(line)?.into_iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// The grid of ID line 2, if it is a metaplate one.
    pub fn parse_grid(line: &str) -> Option<GridSpec> {
        let (nx, ny) = Self::value(line, "grid")?.split_once('x')?;
        let (x0, y0) = Self::value(line, "origin_m")?.split_once(',')?;
        let grid = GridSpec {
            nx: nx.parse().ok()?,
            ny: ny.parse().ok()?,
            spacing_m: Self::value(line, "spacing_m")?.parse().ok()?,
            origin_x_m: x0.parse().ok()?,
            origin_y_m: y0.parse().ok()?,
        };
        grid.validate().ok().map(|()| grid)
    }

    /// The (point, actuator) of ID line 1, if it is a metaplate one.
    pub fn parse_key(line: &str) -> Option<(u32, u16)> {
        Some((Self::value(line, "point")?.parse().ok()?, Self::value(line, "actuator")?.parse().ok()?))
    }

    /// The scene id of ID line 3, if it is a metaplate one.
    pub fn parse_scene(line: &str) -> Option<SceneId> {
        Some(SceneId {
            name: Self::value(line, "scene")?.to_owned(),
            hash: Self::value(line, "scene_hash")?.to_owned(),
        })
    }

    /// The row's estimated error of ID line 5, dB, if it has one.
    pub fn parse_estimated_error(line: &str) -> Option<f64> {
        Self::value(line, "estimated_error_db").and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite())
    }

    /// The row quality of ID line 4: status, SNR (dB), retries, measurement time (µs since the Unix epoch).
    pub fn parse_quality(line: &str) -> (Option<Status>, Option<f64>, Option<u32>, Option<i64>) {
        let status = Self::value(line, "status").and_then(Status::parse);
        let snr_db = Self::value(line, "snr_db").and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite());
        let retries = Self::value(line, "retries").and_then(|v| v.parse().ok());
        let measured_at = Self::value(line, "measured_at_us").and_then(|v| v.parse().ok());
        (status, snr_db, retries, measured_at)
    }
}

/// `text` with spaces as `_` (one word of an ID line).
fn word(text: &str) -> String {
    text.chars().map(|c| if c.is_ascii_graphic() { c } else { '_' }).collect()
}

/// `line` cut to the 80 columns of an ID line.
fn cut(mut line: String) -> String {
    line.truncate(80);
    line
}

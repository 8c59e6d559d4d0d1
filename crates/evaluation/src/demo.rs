//! The main job on the built-in simulated plates, with no hardware (`metaplate demo`).
//!
//! For each built-in plate (metamaterial, homogeneous), on the mock lab (the real drivers over mock devices, on a
//! virtual clock, so hours of measurement take minutes):
//! 1. dispersion of the plate model by the paper's k-space method, against the paper's measured wavelengths;
//! 2. calibrate: the calibration recipe on all 8 actuators (sweep on each magnet, Kirkeby inverse filter,
//!    verification through it), into `DIR/<plate>/calibration`;
//! 3. scan: the scan recipe with that calibration over a reduced grid by default (every other point, the quick
//!    protocol) or, when `full`, the paper's full grid and protocol, into `DIR/<plate>/scan`; the measured Green's
//!    functions are compared with the lab's ground truth (through the calibration's filters);
//! 4. the analyses of `metaplate analyze` on the scanned dataset, with their figures in `DIR/<plate>/figures`;
//! 5. a 5-pixel pattern (5 distinct targets, one of them a null), solved on the scanned dataset, compensated by the
//!    calibration's filters and peak-normalised, as `metaplate focus` renders it: `DIR/<plate>/pattern.wav`.
//!
//! It writes everything in `DIR/summary.json` ([`DemoSummary`]) and the same as one self-contained page in
//! `DIR/report.html` ([`crate::report`]); [`DemoSummary::table_text`] is the paper-against-suite table it prints.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use metaplate_analysis::dataset_figures::write_comparison_figures;
use metaplate_analysis::dataset_report::DatasetAnalysis;
use metaplate_analysis::paper_table::{
    DISPERSION_FREQS_HZ, ModelWavelength, PLATES, PlateResults, columns, paper_rows,
};
use metaplate_control::focus::{PixelSpec, RenderOptions, render};
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_plate::ModelOptions;
use metaplate_recipes::calibrate::ActuatorCalibration;
use metaplate_recipes::{Calibration, CalibrationConfig, Output, RunControl, ScanConfig, ScanPoints, calibrate, scan};
use metaplate_store::Dataset;
use serde::Serialize;

use crate::error::{EvaluationError, StepExt, io_error};
use crate::progress::Progress;
use crate::report::{ReportPlate, ScanMeasurement, analyse_with_figures, write_report};
use crate::simulated::{DispersionReport, model_dispersion};
use crate::truth::{GreensErrorSummary, greens_errors};

/// The default scan grid: every other point of the paper's 49 x 25 (1 cm spacing: 2 points per wavelength at
/// 400 Hz on the metamaterial, the lattice's limit; the 3.5 x 3.5 cm authority domain, centred on the lattice point
/// at the plate centre, holds 3 x 3 points).
const DEFAULT_GRID: (usize, usize) = (25, 13);

/// The pattern: positions as fractions of the measured area (-1..1 each way) and targets (`metaplate focus`
/// syntax; times in s from the start of the 1 s drive, whose focus time is 0.5 s).
const PATTERN: [((f64, f64), &str); 5] = [
    ((0.0, 0.0), "impulse"),
    ((-0.6, 0.5), "sine@200,0.4,0.2"),
    ((0.6, 0.5), "wavelets@250,3,0.42,0.5,0.58"),
    ((-0.6, -0.5), "noise@0.4,0.2,7"),
    ((0.6, -0.5), "null"),
];

/// What the demo runs.
#[derive(Debug, Clone)]
pub struct DemoRequest<'a> {
    /// Output directory (created; an earlier demo's results in it are replaced).
    pub out: &'a Path,
    /// The paper's full grid and protocol instead of a 25 x 13 grid and the quick protocol.
    pub full: bool,
    /// A scan grid of its own (at least 2 x 2), for tests.
    pub grid: Option<GridSubset>,
    /// Seed of the lab and the recipes.
    pub seed: u64,
    /// The Green's-function cache.
    pub cache_dir: Option<&'a Path>,
}

/// Everything the demo did, as `DIR/summary.json` holds it (fields in alphabetical order: the JSON's key order).
#[derive(Debug, Clone, Serialize)]
pub struct DemoSummary {
    /// Both plates' figures on shared axes.
    pub comparison_figures: Vec<String>,
    /// Per plate, by name.
    pub plates: BTreeMap<String, DemoPlate>,
    /// The scan protocol's name.
    pub protocol: String,
    /// `"full"` or `[nx, ny]`.
    pub scan_grid: ScanGrid,
    /// The seed.
    pub seed: u64,
    /// Wall time of the whole demo, s.
    pub wall_time_s: f64,
}

/// The scan grid: the full grid, or a subset.
#[derive(Debug, Clone, Copy, Serialize)]
#[serde(untagged)]
pub enum ScanGrid {
    /// `"full"`.
    Full(&'static str),
    /// `[nx, ny]`.
    Subset([usize; 2]),
}

/// What the demo did on one plate.
#[derive(Debug, Clone, Serialize)]
pub struct DemoPlate {
    /// The analysis of the scan, with its figures.
    pub analysis: DatasetAnalysis,
    /// The calibration.
    pub calibration: DemoCalibration,
    /// The plate model's dispersion.
    pub dispersion: DispersionReport,
    /// The 5-pixel pattern.
    pub pattern: Pattern,
    /// The scan.
    pub scan: DemoScan,
}

/// The calibration of one plate.
#[derive(Debug, Clone, Serialize)]
pub struct DemoCalibration {
    /// Per actuator.
    pub actuators: Vec<CalibratedActuator>,
    /// Its directory.
    pub dir: String,
}

/// One actuator's calibration.
#[derive(Debug, Clone, Serialize)]
pub struct CalibratedActuator {
    /// The actuator.
    pub actuator: usize,
    /// Attempts made.
    pub attempts: u32,
    /// Flatness deviation through its filter, dB.
    pub flatness_deviation_db: f64,
    /// The filter's largest boost, dB.
    pub max_boost_db: f64,
    /// Flatness deviation by the standard measure, dB.
    pub standard_flatness_deviation_db: f64,
    /// Its status.
    pub status: &'static str,
}

/// The scan of one plate.
#[derive(Debug, Clone, Serialize)]
pub struct DemoScan {
    /// Points deferred.
    pub deferred: usize,
    /// Its directory.
    pub dir: String,
    /// Its Green's functions against the truth.
    pub greens_error_db: GreensErrorSummary,
    /// Points committed.
    pub points: usize,
    /// Rig-clock time, hours.
    pub simulated_hours: f64,
    /// Rig-clock time over wall time.
    pub speed_up: f64,
    /// Rows by status.
    pub statuses: BTreeMap<&'static str, usize>,
    /// Points planned.
    pub total: usize,
    /// Wall time of the scan, s.
    pub wall_s: f64,
}

/// The rendered pattern of one plate.
#[derive(Debug, Clone, Serialize)]
pub struct Pattern {
    /// Channels (actuators).
    pub channels: usize,
    /// Focus time of the impulse, s.
    pub focus_s: f64,
    /// The normalisation factor applied.
    pub normalisation_factor: f64,
    /// Peak of the drives before normalisation.
    pub peak_drive: f64,
    /// Per pixel.
    pub pixels: Vec<PatternPixel>,
    /// Samples per channel.
    pub samples: usize,
    /// The WAV file.
    pub wav: String,
}

/// One pixel of the pattern.
#[derive(Debug, Clone, Serialize)]
pub struct PatternPixel {
    /// Predicted peak velocity there, m/s.
    pub peak_velocity_m_s: f64,
    /// The measured point it snapped to.
    pub point_index: u32,
    /// Its target.
    pub target: String,
    /// x, m.
    pub x_m: f64,
    /// y, m.
    pub y_m: f64,
}

/// Runs the demo: both plates, the comparison figures, `summary.json` and `report.html` in `request.out`.
///
/// # Errors
/// A directory that cannot be made or cleared, a recipe, analysis or figure that fails, a file that cannot be
/// written.
pub fn run_demo(request: &DemoRequest<'_>, progress: &mut dyn Progress) -> Result<DemoSummary, EvaluationError> {
    let out = request.out;
    fs::create_dir_all(out).map_err(io_error("creating", out))?;
    let started = std::time::Instant::now();
    let subset = match (request.grid, request.full) {
        // The wavelength estimate needs a two-dimensional field.
        (Some(grid), _) => Some(grid.at_least(2).step(|| "--grid".into())?.into()),
        (None, true) => None,
        (None, false) => Some(DEFAULT_GRID),
    };
    let protocol = ExcitationProtocol::by_name(if request.full { "paper" } else { "quick" })?;
    let mut plates = BTreeMap::new();
    for name in PLATES {
        let scene = Scene::builtin(name).step(|| format!("the built-in scene {name}"))?;
        let plate = run_plate(&scene, &out.join(name), subset, &protocol, request, progress)?;
        plates.insert(name.to_owned(), plate);
    }
    // Both plates on shared axes (wavelength with A0 and the paper's points; condition numbers with the paper's).
    let analyses: Vec<(&str, &DatasetAnalysis)> =
        PLATES.iter().filter_map(|name| Some((*name, &plates.get(*name)?.analysis))).collect();
    let comparison =
        write_comparison_figures(&out.join("figures"), &analyses).step(|| "drawing the comparison figures".into())?;
    let summary = DemoSummary {
        comparison_figures: comparison.iter().map(|p| p.display().to_string()).collect(),
        plates,
        protocol: protocol.name.clone(),
        scan_grid: subset.map_or(ScanGrid::Full("full"), |(nx, ny)| ScanGrid::Subset([nx, ny])),
        seed: request.seed,
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    let path = out.join("summary.json");
    let text = serde_json::to_string_pretty(&summary)
        .map_err(|e| EvaluationError::Invalid(format!("the summary as JSON: {e}")))?;
    fs::write(&path, text).map_err(io_error("writing", &path))?;
    summary.write_report(&out.join("report.html"))?;
    Ok(summary)
}

/// Everything the demo does on one plate.
fn run_plate(
    scene: &Scene,
    dir: &Path,
    subset: Option<(usize, usize)>,
    protocol: &ExcitationProtocol,
    request: &DemoRequest<'_>,
    progress: &mut dyn Progress,
) -> Result<DemoPlate, EvaluationError> {
    let name = scene.name.clone();
    progress.begin(&format!("[{name}] dispersion of the plate model"));
    let dispersion = model_dispersion(scene, &ModelOptions::default(), &DISPERSION_FREQS_HZ, &mut || {})?;
    progress.end();

    let plan = ScanPoints::new(scene.grid, &scene.grid_mask(), subset).step(|| "planning the scan".into())?;
    let n_act = scene.actuators.len();
    // The scanned points and the actuators' driving points (where calibration aims the beam).
    let mut points = plan.points.clone();
    points.extend((0..n_act).map(|k| scene.grid.len() + k));
    let options = LabOptions {
        seed: Some(request.seed),
        cache_dir: request.cache_dir.map(Path::to_path_buf),
        points: Some(points),
        ..LabOptions::default()
    };
    progress.begin(&format!(
        "[{name}] the mock lab: Green's functions of {} points x {n_act} actuators",
        plan.points.len() + n_act
    ));
    let lab = MockLab::new(scene, &options).step(|| format!("building the mock lab of {name}"))?;
    progress.end();
    let mut rig = lab.rig().step(|| "taking the lab's rig".into())?;
    let control = RunControl::new();

    let calibration_dir = fresh_dir(&dir.join("calibration"))?;
    let sites_m: Vec<(f64, f64)> = scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect();
    let cal_cfg = CalibrationConfig { seed: request.seed, ..CalibrationConfig::default() };
    progress.begin(&format!("[{name}] calibrate"));
    let calibrated = calibrate(&mut rig, &sites_m, &cal_cfg, &output(&calibration_dir, scene), &control, progress)
        .step(|| format!("calibrating {name}"))?;
    progress.end();
    let calibration = Calibration::load(&calibration_dir, n_act)
        .step(|| format!("loading the calibration {}", calibration_dir.display()))?;

    let scan_dir = fresh_dir(&dir.join("scan"))?;
    let scan_cfg = ScanConfig { protocol: protocol.clone(), seed: request.seed, ..ScanConfig::default() };
    progress.begin(&format!("[{name}] scan"));
    let scan_started = std::time::Instant::now();
    let summary = scan(&mut rig, &plan, Some(&calibration), &scan_cfg, &output(&scan_dir, scene), &control, progress)
        .step(|| format!("scanning {name}"))?;
    progress.end();
    let scan_wall_s = scan_started.elapsed().as_secs_f64();

    progress.begin(&format!("[{name}] measured against true Green's functions"));
    let dataset = Dataset::open(&scan_dir).step(|| format!("opening {}", scan_dir.display()))?;
    let errors = greens_errors(&lab, &dataset, Some(&calibration.filters))?;
    progress.end();

    progress.begin(&format!("[{name}] analyses and figures"));
    let analysis = analyse_with_figures(&scan_dir, &dir.join("figures"), &name)?;
    progress.end();

    let pattern = render_pattern(&dataset, &calibration, &dir.join("pattern.wav"))?;
    Ok(DemoPlate {
        analysis,
        calibration: calibration_summary(&calibration_dir, &calibrated),
        dispersion,
        pattern,
        scan: DemoScan {
            deferred: summary.deferred,
            dir: scan_dir.display().to_string(),
            greens_error_db: GreensErrorSummary::of(&errors),
            points: summary.committed,
            simulated_hours: summary.clock_s / 3600.0,
            speed_up: summary.clock_s / scan_wall_s,
            statuses: summary.statuses.clone(),
            total: summary.total,
            wall_s: scan_wall_s,
        },
    })
}

/// Removes an earlier demo's dataset in `dir` (only what the demo writes there) and returns the directory.
fn fresh_dir(dir: &Path) -> Result<PathBuf, EvaluationError> {
    if dir.exists() {
        fs::remove_dir_all(dir).map_err(io_error("removing the earlier", dir))?;
    }
    Ok(dir.to_path_buf())
}

fn output(dir: &Path, scene: &Scene) -> Output {
    Output {
        dir: dir.to_path_buf(),
        scene: scene.id(),
        software_version: env!("CARGO_PKG_VERSION").into(),
        resume: false,
        force: false,
        preflight: None,
    }
}

fn calibration_summary(dir: &Path, calibrated: &[ActuatorCalibration]) -> DemoCalibration {
    DemoCalibration {
        actuators: calibrated
            .iter()
            .map(|c| CalibratedActuator {
                actuator: c.actuator,
                attempts: c.attempts,
                flatness_deviation_db: c.flatness.deviation_db(),
                max_boost_db: c.filter.max_boost_db,
                standard_flatness_deviation_db: c.standard_flatness.deviation_db(),
                status: c.status.as_str(),
            })
            .collect(),
        dir: dir.display().to_string(),
    }
}

/// Renders the 5-pixel pattern on the scanned dataset through the calibration, writes it as a WAV file, and
/// returns what was played: the peak drive and the predicted peak velocity at each pixel.
fn render_pattern(dataset: &Dataset, calibration: &Calibration, wav_path: &Path) -> Result<Pattern, EvaluationError> {
    let grid = dataset.manifest().meta.grid;
    let positions: Vec<(f64, f64)> = dataset.points().iter().map(|&p| grid.position_m(p as usize)).collect();
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for &(x, y) in &positions {
        (lo, hi) = ((lo.0.min(x), lo.1.min(y)), (hi.0.max(x), hi.1.max(y)));
    }
    let rendering = || "rendering the pattern".to_owned();
    let mut specs: Vec<PixelSpec> = Vec::new();
    for ((fx, fy), target) in PATTERN {
        let want = ((lo.0 + hi.0) / 2.0 + fx * (hi.0 - lo.0) / 2.0, (lo.1 + hi.1) / 2.0 + fy * (hi.1 - lo.1) / 2.0);
        // The measured point nearest the wanted position, so that the pixel is never in a gap of the scan.
        let Some(&(x_m, y_m)) = positions.iter().min_by(|a, b| {
            let d = |p: &(f64, f64)| (p.0 - want.0).powi(2) + (p.1 - want.1).powi(2);
            d(a).total_cmp(&d(b))
        }) else {
            return Err(EvaluationError::Incomplete("the scanned dataset has no points".into()));
        };
        specs.push(PixelSpec::from_text(x_m, y_m, target).step(rendering)?);
    }
    let rendered = render(dataset, &specs, Some(&calibration.filters), &RenderOptions::default()).step(rendering)?;
    if let Some(parent) = wav_path.parent() {
        fs::create_dir_all(parent).map_err(io_error("creating", parent))?;
    }
    metaplate_store::write_wav_f32(wav_path, &rendered.signals, dataset.sample_rate_hz())
        .step(|| format!("writing {}", wav_path.display()))?;
    let fields = rendered.field_at_pixels().step(rendering)?;
    let peak = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let pixels = specs
        .iter()
        .zip(&rendered.points)
        .zip(&fields)
        .map(|((s, &point_index), v)| PatternPixel {
            peak_velocity_m_s: peak(v),
            point_index,
            target: s.label.clone(),
            x_m: s.x_m,
            y_m: s.y_m,
        })
        .collect();
    Ok(Pattern {
        channels: rendered.signals.len(),
        focus_s: rendered.focus_s,
        normalisation_factor: rendered.factor,
        peak_drive: rendered.peak,
        pixels,
        samples: rendered.signals.first().map_or(0, Vec::len),
        wav: wav_path.display().to_string(),
    })
}

impl Pattern {
    /// The largest predicted peak velocity at a pixel, m/s.
    pub fn peak_velocity_m_s(&self) -> f64 {
        self.pixels.iter().map(|p| p.peak_velocity_m_s).filter(|v| v.is_finite()).fold(0.0_f64, f64::max)
    }
}

impl DemoSummary {
    /// The paper-against-suite table and one line per plate on its measurement, as the demo prints them.
    pub fn table_text(&self) -> String {
        let wavelengths: BTreeMap<&str, Vec<ModelWavelength>> =
            self.plates.iter().map(|(name, p)| (name.as_str(), p.dispersion.model_wavelengths())).collect();
        let results: Vec<PlateResults<'_>> = self
            .plates
            .iter()
            .map(|(name, p)| PlateResults {
                name,
                analysis: Some(&p.analysis),
                model_wavelengths: wavelengths.get(name.as_str()).map(Vec::as_slice),
                pattern_peak_velocity_m_s: Some(p.pattern.peak_velocity_m_s()),
            })
            .collect();
        let mut out = format!("\n{:<46} {:>30}   metaplate ({})\n", "quantity", "paper", columns(&results));
        for r in paper_rows(&results) {
            out.push_str(&format!("{:<46} {:>30}   {}\n", r.quantity, r.paper, r.suite));
        }
        out.push_str(&format!("\nthe measurement (mock lab, {} protocol):\n", self.protocol));
        let num = |v: f64, digits: usize| if v.is_finite() { format!("{v:.digits$}") } else { "-".to_owned() };
        for name in PLATES {
            let Some(p) = self.plates.get(name) else { continue };
            let (s, e) = (&p.scan, &p.scan.greens_error_db);
            let statuses = s.statuses.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ");
            let calibrated = p.calibration.actuators.iter().filter(|c| c.status == "valid").count();
            out.push_str(&format!(
                "  {name}: {calibrated}/8 actuators calibrated; {} points ({statuses}), {} h simulated in {} s; \
                 Green's functions against the truth: median {} dB, p95 {} dB; pattern peak drive {}\n",
                s.points,
                num(s.simulated_hours, 2),
                num(s.wall_s, 0),
                num(e.median.unwrap_or(f64::NAN), 1),
                num(e.p95.unwrap_or(f64::NAN), 1),
                num(p.pattern.peak_drive, 3),
            ));
        }
        out
    }

    /// Writes the report page of the demo's plates to `path`.
    ///
    /// # Errors
    /// As [`write_report`].
    pub fn write_report(&self, path: &Path) -> Result<(), EvaluationError> {
        let wavelengths: BTreeMap<&str, Vec<ModelWavelength>> =
            self.plates.iter().map(|(name, p)| (name.as_str(), p.dispersion.model_wavelengths())).collect();
        let scans: BTreeMap<&str, ScanMeasurement> = self
            .plates
            .iter()
            .map(|(name, p)| {
                let s = &p.scan;
                let measurement = ScanMeasurement {
                    dir: s.dir.clone(),
                    points: s.points,
                    total: Some(s.total),
                    statuses: s.statuses.iter().map(|(k, v)| ((*k).to_owned(), *v)).collect(),
                    simulated_hours: Some(s.simulated_hours),
                    measured_span_hours: None,
                    greens_error: Ok(s.greens_error_db.clone()),
                };
                (name.as_str(), measurement)
            })
            .collect();
        let plates: Vec<ReportPlate<'_>> = self
            .plates
            .iter()
            .filter_map(|(name, p)| {
                Some(ReportPlate {
                    name,
                    analysis: &p.analysis,
                    scan: scans.get(name.as_str())?,
                    calibration_dir: Some(&p.calibration.dir),
                    model_wavelengths: wavelengths.get(name.as_str()).map(Vec::as_slice),
                    pattern_peak_velocity_m_s: Some(p.pattern.peak_velocity_m_s()),
                })
            })
            .collect();
        write_report(path, &plates, Some(&self.comparison_figures))
    }
}

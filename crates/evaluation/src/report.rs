//! One self-contained HTML page on analysed scan datasets (one plate, or the pair of built-in plates), as
//! `metaplate report` and the demo write it: the paper-against-suite table, the figures with captions, each
//! measurement's summary (protocol, points, statuses, status and SNR maps, the error against the truth on the mock
//! lab) and its provenance (scene, configuration hash, calibration, software version).
//!
//! Self-contained: figures are embedded as PNG data URIs, the grid maps as inline SVG, the style inline; there is
//! no script and nothing is fetched, so the file opens offline and can be mailed or archived as it is. The page
//! ([`page`]) is drawn from typed inputs ([`ReportPlate`]), so the demo's report and `metaplate report` on the
//! demo's datasets say the same.

mod page;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metaplate_analysis::dataset_figures::{write_comparison_figures, write_dataset_figures};
use metaplate_analysis::dataset_report::{DatasetAnalysis, analyse_dataset};
use metaplate_analysis::paper_table::{ModelWavelength, PLATES};
use metaplate_core::scene::Scene;
use metaplate_recipes::Calibration;
use metaplate_store::Dataset;
use serde_json::Value;

use crate::error::{EvaluationError, StepExt, io_error};
use crate::progress::Progress;
use crate::truth::{GreensErrorSummary, dataset_errors};

pub use page::write_report;

/// What the page says of one plate.
#[derive(Debug, Clone, Copy)]
pub struct ReportPlate<'a> {
    /// The plate's (scene's) name.
    pub name: &'a str,
    /// The analysis of its scanned dataset, with its figures written (their paths in `figures`).
    pub analysis: &'a DatasetAnalysis,
    /// The measurement.
    pub scan: &'a ScanMeasurement,
    /// The calibration directory the scan was compensated with, where known.
    pub calibration_dir: Option<&'a str>,
    /// The plate model's k-space wavelength per frequency, where computed (the demo).
    pub model_wavelengths: Option<&'a [ModelWavelength]>,
    /// The largest peak velocity at a pixel of a rendered pattern, m/s (the demo).
    pub pattern_peak_velocity_m_s: Option<f64>,
}

/// What the page says of a scan.
#[derive(Debug, Clone)]
pub struct ScanMeasurement {
    /// The dataset's directory.
    pub dir: String,
    /// Points committed.
    pub points: usize,
    /// Points planned, where known.
    pub total: Option<usize>,
    /// Rows by status.
    pub statuses: BTreeMap<String, usize>,
    /// Rig-clock time of the measurement, hours (the demo's: the scan's summary).
    pub simulated_hours: Option<f64>,
    /// Wall-clock span of the rows' timestamps, hours.
    pub measured_span_hours: Option<f64>,
    /// The error of its Green's functions against the truth, or why it is not compared.
    pub greens_error: Result<GreensErrorSummary, String>,
}

impl ScanMeasurement {
    /// What the page says of a scan, read back from the dataset: its directory, points committed and planned, row
    /// counts by status, and the span of the rows' timestamps (wall clock: on the mock lab, fast-forward, this is
    /// how long the simulation took, not the rig time it simulated). No rig time, no comparison yet.
    pub fn of_dataset(dir: &Path, dataset: &Dataset) -> Self {
        let mut statuses: BTreeMap<String, usize> = BTreeMap::new();
        let mut times_us = (i64::MAX, i64::MIN);
        for meta in dataset.rows() {
            if let Some(status) = meta.status {
                *statuses.entry(status.as_str().to_owned()).or_default() += 1;
            }
            if let Some(t) = meta.measured_at_unix_us {
                times_us = (times_us.0.min(t), times_us.1.max(t));
            }
        }
        let total = dataset.manifest().meta.config.get("points").and_then(Value::as_array).map(Vec::len);
        Self {
            dir: dir.display().to_string(),
            points: dataset.points().len(),
            total,
            statuses,
            simulated_hours: None,
            measured_span_hours: (times_us.1 >= times_us.0).then(|| (times_us.1 - times_us.0) as f64 / 3.6e9),
            greens_error: Err("-".to_owned()),
        }
    }
}

/// What `metaplate report` reports on.
#[derive(Debug, Clone)]
pub struct ReportRequest<'a> {
    /// Scan dataset directories, one per plate.
    pub datasets: &'a [PathBuf],
    /// Calibration directories the scans were compensated with (matched by content hash).
    pub calibrations: &'a [PathBuf],
    /// Scenes that are not built in (matched by hash).
    pub scenes: &'a [Scene],
    /// Skip the comparison with the truth.
    pub no_truth: bool,
    /// The Green's-function cache.
    pub cache_dir: Option<&'a Path>,
    /// The page to write.
    pub out: &'a Path,
}

/// Analyses each dataset (figures drawn into a scratch directory and embedded), compares it with the truth where
/// it can, and writes the page.
///
/// # Errors
/// Two datasets of one scene, a dataset or calibration that cannot be read, an analysis or figure that fails, a
/// comparison the lab refuses, the page that cannot be written.
pub fn report_on_datasets(request: &ReportRequest<'_>, progress: &mut dyn Progress) -> Result<(), EvaluationError> {
    // Figures are drawn into a scratch directory and embedded; it is removed when the report is written.
    let scratch = tempfile::tempdir().map_err(io_error("creating a scratch directory for", std::env::temp_dir()))?;
    let mut plates: BTreeMap<String, (DatasetAnalysis, ScanMeasurement)> = BTreeMap::new();
    for data in request.datasets {
        let dataset = Dataset::open(data).step(|| format!("opening dataset {}", data.display()))?;
        let name = dataset.manifest().meta.scene.name.clone();
        if plates.contains_key(&name) {
            return Err(EvaluationError::Invalid(format!(
                "two datasets of the scene `{name}`: a report holds one dataset per plate (write one report each)"
            )));
        }
        progress.begin(&format!("[{name}] analyses and figures"));
        let analysis = analyse_with_figures(data, &scratch.path().join(&name), &name)?;
        progress.end();
        let mut scan = ScanMeasurement::of_dataset(data, &dataset);
        scan.greens_error = if request.no_truth {
            Err("not compared (--no-truth)".to_owned())
        } else {
            progress.begin(&format!("[{name}] measured against the ground truth"));
            let scene = find_scene(&dataset, request.scenes);
            let errors = truth_errors(&dataset, scene.as_ref(), request.calibrations, request.cache_dir);
            progress.end();
            errors?.map(|e| GreensErrorSummary::of(&e))
        };
        plates.insert(name, (analysis, scan));
    }
    let pair: Vec<(&str, &DatasetAnalysis)> = PLATES.iter().filter_map(|p| Some((*p, &plates.get(*p)?.0))).collect();
    let comparison = if pair.len() == 2 {
        let dir = scratch.path().join("figures");
        let written = write_comparison_figures(&dir, &pair).step(|| "drawing the comparison figures".into())?;
        Some(written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>())
    } else {
        None
    };
    let inputs: Vec<ReportPlate<'_>> = plates
        .iter()
        .map(|(name, (analysis, scan))| ReportPlate {
            name,
            analysis,
            scan,
            calibration_dir: None,
            model_wavelengths: None,
            pattern_peak_velocity_m_s: None,
        })
        .collect();
    write_report(request.out, &inputs, comparison.as_deref())
}

/// The analysis of the dataset in `data` with its figures written into `figures` (`label`: the plate's name).
///
/// # Errors
/// As [`analyse_dataset`] and [`write_dataset_figures`].
pub fn analyse_with_figures(data: &Path, figures: &Path, label: &str) -> Result<DatasetAnalysis, EvaluationError> {
    let (mut analysis, parts) = analyse_dataset(data, None).step(|| format!("analysing dataset {}", data.display()))?;
    let written = write_dataset_figures(figures, label, &analysis, &parts)
        .step(|| format!("drawing the figures of {} in {}", data.display(), figures.display()))?;
    analysis.figures = Some(written.iter().map(|p| p.display().to_string()).collect());
    Ok(analysis)
}

/// The scene of a dataset when the suite can simulate it: a built-in one, or one of `scenes`, with the same hash.
fn find_scene(dataset: &Dataset, scenes: &[Scene]) -> Option<Scene> {
    let id = &dataset.manifest().meta.scene;
    let builtin = Scene::builtin(&id.name).ok().filter(|s| s.id().hash == id.hash);
    builtin.or_else(|| scenes.iter().find(|s| s.id().hash == id.hash).cloned())
}

/// The errors of the dataset's rows against the truth (`Ok(Ok)`), or why they are not compared (`Ok(Err)`): no
/// simulated scene, or a calibrated scan whose calibration is not among `calibrations`.
fn truth_errors(
    dataset: &Dataset,
    scene: Option<&Scene>,
    calibrations: &[PathBuf],
    cache_dir: Option<&Path>,
) -> Result<Result<Vec<f64>, String>, EvaluationError> {
    let Some(scene) = scene else {
        return Ok(Err("no ground truth: the scene is neither built in nor given with --scene".to_owned()));
    };
    let filters = match dataset.manifest().meta.config.get("calibration").and_then(Value::as_str) {
        None => None,
        Some(hash) => {
            let mut found = None;
            for dir in calibrations {
                let calibration = Calibration::load(dir, scene.actuators.len())
                    .step(|| format!("reading calibration {}", dir.display()))?;
                if calibration.content_hash == hash {
                    found = Some(calibration);
                    break;
                }
            }
            let Some(calibration) = found else {
                return Ok(Err(format!(
                    "calibrated scan ({hash}): pass its --calibration DIR to compare with the truth"
                )));
            };
            Some(calibration.filters)
        }
    };
    Ok(Ok(dataset_errors(scene, dataset, filters.as_deref(), cache_dir)?))
}

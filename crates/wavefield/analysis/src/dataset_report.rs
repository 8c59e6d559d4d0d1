//! The paper's Wave Field Analysis of one dataset, as `metaplate analyze` prints it: [`analyse_dataset`] opens the
//! dataset, builds its propagation matrices, runs [`crate::report::analyse`] and the pixel-area map, and returns a
//! [`DatasetAnalysis`] that serialises to the command's JSON object (fields in alphabetical order, the keys' order
//! in that JSON), with its figures written when asked ([`crate::dataset_figures`]).

use std::collections::BTreeMap;
use std::path::Path;

use metaplate_control::PropagationMatrices;
use metaplate_control::pixels::PointSelection;
use metaplate_core::error_chain;
use metaplate_core::scene::Scene;
use metaplate_store::Dataset;
use serde::Serialize;

use crate::error::AnalysisError;
use crate::pixel::{PixelAreaMap, PixelAreaOptions, pixel_area_map};
use crate::report::{PlateReport, ReportOptions, analyse};
use crate::scattered::{ScatteredSummary, analyse_scattered};

/// Band of the propagation matrices, Hz: the refresh pulse's skirts (50 Hz) up to the wavelength's 600 Hz.
pub const DATASET_G_BAND_HZ: (f64, f64) = (50.0, 625.0);

/// The domain edges the report keys its authority by, cm with one decimal, largest first.
pub const DOMAIN_EDGE_KEYS: [&str; 3] = ["9.5", "6.5", "3.5"];

/// Everything `metaplate analyze --json` prints on one dataset. An analysis that failed on this dataset is listed
/// under `errors` (its key, its message) and its value is `None` (null).
#[derive(Debug, Clone, Serialize)]
pub struct DatasetAnalysis {
    /// Actuators in the propagation matrices.
    pub actuators: usize,
    /// Mean condition number of G_D per domain edge (cm key, see [`DOMAIN_EDGE_KEYS`]).
    pub condition_number: BTreeMap<String, Option<f64>>,
    /// The dataset's directory as given.
    pub dataset: String,
    /// Mean driven response per frequency.
    pub driven_response: Option<Vec<DrivenResponseAt>>,
    /// Mean effective rank of G_D per domain edge (cm key).
    pub effective_rank: BTreeMap<String, Option<f64>>,
    /// Analyses that failed: name, message.
    pub errors: BTreeMap<String, String>,
    /// The points left out by `max_error_db`, when a limit was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excluded_points: Option<ExcludedPoints>,
    /// The figures written (PNG and SVG paths, the animation last), when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub figures: Option<Vec<String>>,
    /// The regular lattice the analyses work on.
    pub lattice: LatticeSummary,
    /// Median virtual-pixel area, cm^2 (`None` when no half-maximum contour closes).
    pub median_pixel_area_cm2: Option<f64>,
    /// Fraction of points whose pixel area is flagged.
    pub pixel_area_flagged_fraction: Option<f64>,
    /// POD components for 99 % of the energy.
    pub pod_components_99: Option<usize>,
    /// The POD's cumulative energy, its first 64 components.
    pub pod_energy: Option<Vec<f64>>,
    /// Measured points analysed.
    pub points: usize,
    /// Points per authority domain (cm key); domains that failed are absent.
    pub points_per_domain: BTreeMap<String, usize>,
    /// The refresh interval, ms.
    pub refresh_ms: Option<f64>,
    /// The dataset's scene name.
    pub scene: String,
    /// The k-space wavelength per frequency.
    pub wavelength: Vec<WavelengthRow>,
    /// The wavelengths the lattice resolves.
    pub wavelength_resolvable: ResolvableSummary,
    /// For scattered points (an imported scan mesh): which analyses ran on the points and which on a lattice
    /// interpolated within their hull (absent for a dataset on its grid).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scattered: Option<ScatteredSummary>,
}

/// The mean driven response at one frequency.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct DrivenResponseAt {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Mean magnitude over points and actuators, in the dataset's response unit.
    pub mean_abs: f64,
}

/// The points `--max-error-db` left out.
#[derive(Debug, Clone, Serialize)]
pub struct ExcludedPoints {
    /// Each point left out with its worst row's estimated error.
    pub excluded: Vec<ExcludedPoint>,
    /// Kept points with a row without an estimate.
    pub kept_without_estimate: usize,
    /// The limit, dB.
    pub max_error_db: f64,
}

/// One point left out.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ExcludedPoint {
    /// Its worst row's estimated error, dB.
    pub estimated_error_db: f64,
    /// Its grid index.
    pub point_index: u32,
}

/// The analysis lattice.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LatticeSummary {
    /// Fraction of the lattice measured.
    pub fill: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Spacing, m.
    pub spacing_m: f64,
    /// Grid points per lattice step.
    pub stride: usize,
}

/// The wavelengths the lattice resolves.
#[derive(Debug, Clone, Serialize)]
pub struct ResolvableSummary {
    /// The measured area's extent, m.
    pub aperture_m: f64,
    /// Longest resolvable wavelength, m.
    pub longest_m: f64,
    /// What `in_range` means.
    pub note: &'static str,
    /// The lattice's Nyquist wavenumber, rad/m.
    pub nyquist_k_rad_m: f64,
    /// Shortest resolvable wavelength, m.
    pub shortest_m: f64,
}

/// The k-space wavelength at one frequency: the estimate (`median_m`, `iqr_m`, `actuators_flagged`) or its
/// `error`.
#[derive(Debug, Clone, Serialize)]
pub struct WavelengthRow {
    /// The scene's analytic A0 wavelength, m, where the dataset's scene is a built-in one (absent otherwise; null
    /// when it cannot be computed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a0_wavelength_m: Option<Option<f64>>,
    /// Actuators whose estimate was flagged (absent when the estimate failed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub actuators_flagged: Option<usize>,
    /// Why there is no estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Inside the resolvable range on a lattice filled enough.
    pub in_range: bool,
    /// Interquartile range over the actuators, m.
    pub iqr_m: Option<[f64; 2]>,
    /// Median over the actuators, m.
    pub median_m: Option<f64>,
}

/// What the analysis of a dataset computed, beside its [`DatasetAnalysis`]: the figures are drawn from it.
pub struct DatasetAnalysisParts {
    /// The propagation matrices.
    pub g: PropagationMatrices,
    /// The analyses.
    pub report: PlateReport,
    /// The pixel-area map, or why not.
    pub pixels: Result<PixelAreaMap, AnalysisError>,
    /// The dataset's scene when it is a built-in one (same hash).
    pub scene: Option<Scene>,
}

/// The analysis of the dataset in `data` with every point, or only the points whose every row's estimated error
/// is at most `max_error_db`; figures are written by [`crate::dataset_figures::write_dataset_figures`] from the
/// parts returned beside it.
///
/// # Errors
/// An unreadable dataset, a selection or propagation matrices that cannot be built. An analysis that fails on this
/// dataset is not an error: it is listed under `errors`.
pub fn analyse_dataset(
    data: &Path,
    max_error_db: Option<f64>,
) -> Result<(DatasetAnalysis, DatasetAnalysisParts), AnalysisError> {
    let dataset = Dataset::open(data)
        .map_err(|e| AnalysisError::Dataset { path: data.to_path_buf(), reason: error_chain::message(&e) })?;
    let grid = dataset.manifest().meta.grid;
    if let [point] = dataset.points() {
        let (x, y) = dataset.manifest().meta.position_m(*point as usize).unwrap_or_default();
        return Err(AnalysisError::Step {
            step: "analysing the dataset",
            reason: format!(
                "it holds one point, at ({x}, {y}) m: every analysis of a wave field (wavelength, pixel area, POD, \
                 authority, refresh, driven response) compares points, so none runs on one; at least 2 points are \
                 needed (3 not on one line for the wavelength and the pixel area)"
            ),
        });
    }
    let selection =
        max_error_db.map(|db| PointSelection::by_estimated_error(&dataset, db)).transpose().map_err(|e| {
            AnalysisError::Step { step: "selecting points by estimated error", reason: error_chain::message(&e) }
        })?;
    let kept = selection.as_ref().map(|s| s.kept.as_slice());
    let g = PropagationMatrices::from_dataset(&dataset, DATASET_G_BAND_HZ, kept)
        .map_err(|e| AnalysisError::Step { step: "building G(omega)", reason: error_chain::message(&e) })?;
    let meta = &dataset.manifest().meta;
    let (report, pixels, scattered, g) = match &meta.scattered {
        Some(_) => {
            let positions: Vec<(f64, f64)> =
                g.points().iter().map(|&p| meta.position_m(p as usize).unwrap_or((f64::NAN, f64::NAN))).collect();
            let (report, pixels, summary, on_lattice) = analyse_scattered(&g, &positions, &ReportOptions::default())?;
            (report, pixels, Some(summary), on_lattice)
        }
        None => {
            let report = analyse(&g, &grid, &ReportOptions::default())?;
            let mut mask = vec![false; grid.len()];
            for &p in g.points() {
                if let Some(m) = mask.get_mut(p as usize) {
                    *m = true;
                }
            }
            let pixels = pixel_area_map(&g, &grid, &mask, &PixelAreaOptions::default());
            (report, pixels, None, g)
        }
    };
    let scene_id = &dataset.manifest().meta.scene;
    let scene = Scene::builtin(&scene_id.name).ok().filter(|s| s.id().hash == scene_id.hash);
    let mut analysis = summarise(&report, pixels.as_ref(), scene.as_ref());
    if let Some(summary) = &scattered
        && report.wavelength.is_empty()
    {
        analysis.errors.insert("wavelength".into(), summary.lattice_analyses.clone());
    }
    analysis.points = scattered.as_ref().map_or(g.n_points(), |s| s.points);
    analysis.scattered = scattered;
    analysis.dataset = data.display().to_string();
    analysis.scene.clone_from(&scene_id.name);
    analysis.actuators = g.n_actuators();
    analysis.excluded_points = selection.map(|s| ExcludedPoints {
        excluded: s
            .excluded
            .iter()
            .map(|&(point_index, estimated_error_db)| ExcludedPoint { estimated_error_db, point_index })
            .collect(),
        kept_without_estimate: s.without_estimate,
        max_error_db: s.max_error_db,
    });
    Ok((analysis, DatasetAnalysisParts { g, report, pixels, scene }))
}

/// Domain edge as the report's key, in cm with one decimal ("9.5").
pub fn edge_key(edge_m: f64) -> String {
    format!("{:.1}", edge_m * 100.0)
}

/// The report's figures as a [`DatasetAnalysis`] (dataset, scene, points and actuators left empty).
fn summarise(
    report: &PlateReport,
    pixels: Result<&PixelAreaMap, &AnalysisError>,
    scene: Option<&Scene>,
) -> DatasetAnalysis {
    let mut errors = BTreeMap::new();
    let mut keep = |key: String, e: &AnalysisError| {
        errors.insert(key, e.to_string());
    };
    let a0 = |f: f64| scene.map(|s| s.plate.a0_wavelength_m(f).ok());
    let wavelength = report
        .wavelength
        .iter()
        .map(|w| match &w.summary {
            Ok(s) => WavelengthRow {
                a0_wavelength_m: a0(w.freq_hz),
                actuators_flagged: Some(s.flagged),
                error: None,
                freq_hz: w.freq_hz,
                in_range: w.in_range,
                iqr_m: Some([s.iqr_m.0, s.iqr_m.1]),
                median_m: Some(s.median_m),
            },
            Err(e) => WavelengthRow {
                a0_wavelength_m: a0(w.freq_hz),
                actuators_flagged: None,
                error: Some(e.to_string()),
                freq_hz: w.freq_hz,
                in_range: false,
                iqr_m: None,
                median_m: None,
            },
        })
        .collect();
    let (mut rank, mut kappa, mut domain_points) = (BTreeMap::new(), BTreeMap::new(), BTreeMap::new());
    for (edge_m, a) in &report.authority {
        let key = edge_key(*edge_m);
        match a {
            Ok(a) => {
                domain_points.insert(key.clone(), a.points.len());
                rank.insert(key.clone(), Some(a.mean_effective_rank()));
                kappa.insert(key, Some(a.mean_condition_number()));
            }
            Err(e) => {
                keep(format!("authority {key} cm"), e);
                rank.insert(key.clone(), None);
                kappa.insert(key, None);
            }
        }
    }
    let pod = report.pod.as_ref().map_err(|e| keep("pod".into(), e)).ok();
    let refresh = report.refresh.as_ref().map_err(|e| keep("refresh".into(), e)).ok();
    let response = report.driven_response.as_ref().map_err(|e| keep("driven_response".into(), e)).ok();
    let pixels = pixels.map_err(|e| keep("pixel_area".into(), e)).ok();
    let (lattice, range) = (&report.lattice, &report.resolvable);
    DatasetAnalysis {
        actuators: 0,
        condition_number: kappa,
        dataset: String::new(),
        driven_response: response.map(|r| {
            r.freqs_hz
                .iter()
                .zip(&r.mean_magnitude)
                .map(|(&freq_hz, &mean_abs)| DrivenResponseAt { freq_hz, mean_abs })
                .collect()
        }),
        effective_rank: rank,
        errors,
        excluded_points: None,
        figures: None,
        lattice: LatticeSummary {
            fill: range.fill,
            nx: lattice.grid.nx,
            ny: lattice.grid.ny,
            spacing_m: range.spacing_m,
            stride: lattice.stride,
        },
        median_pixel_area_cm2: pixels.and_then(PixelAreaMap::median_area_cm2),
        pixel_area_flagged_fraction: pixels.map(PixelAreaMap::flagged_fraction),
        pod_components_99: pod.map(|p| p.components),
        pod_energy: pod.map(|p| p.energy.iter().take(64).copied().collect()),
        points: 0,
        points_per_domain: domain_points,
        refresh_ms: refresh.map(|r| r.refresh_s * 1e3),
        scene: String::new(),
        wavelength,
        wavelength_resolvable: ResolvableSummary {
            aperture_m: range.aperture_m,
            longest_m: range.longest_wavelength_m,
            note: "k-space estimates outside [shortest_m, longest_m], or on a lattice filled below 50 %, have \
                   in_range false: the lattice aliases shorter waves, the aperture biases longer ones short",
            nyquist_k_rad_m: range.nyquist_k_rad_m,
            shortest_m: range.shortest_wavelength_m,
        },
        scattered: None,
    }
}

impl DatasetAnalysis {
    /// "25 x 13 lattice at 1.0 cm".
    pub fn lattice_text(&self) -> String {
        format!("{} x {} lattice at {:.1} cm", self.lattice.nx, self.lattice.ny, self.lattice.spacing_m * 100.0)
    }

    /// "81 / 49 / 9 points" per domain, largest first.
    pub fn domain_points_text(&self) -> String {
        let n = |k: &str| self.points_per_domain.get(k).map_or_else(|| "-".to_owned(), ToString::to_string);
        format!("{} / {} / {} points", n("9.5"), n("6.5"), n("3.5"))
    }

    /// The analysis as the short table `metaplate analyze` prints without `--json`.
    pub fn table_text(&self) -> String {
        let show = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |x| format!("{x:.2}"));
        let cm = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |x| format!("{:.1}", x * 100.0));
        let finite = |v: f64| v.is_finite().then_some(v);
        let json_text = |v: Option<String>| v.unwrap_or_else(|| "null".to_owned());
        let mut out = String::new();
        let mut line = |s: String| {
            out.push_str(&s);
            out.push('\n');
        };
        line(format!(
            "dataset \"{}\" (\"{}\", {} points)",
            json_escape(&self.dataset),
            json_escape(&self.scene),
            self.points
        ));
        let (l, r) = (&self.lattice, &self.wavelength_resolvable);
        line(format!(
            "lattice {} x {} at {} cm (every {} grid point(s), {:.0} % filled): wavelengths {} to {} cm resolvable",
            l.nx,
            l.ny,
            cm(finite(l.spacing_m)),
            l.stride,
            l.fill * 100.0,
            cm(finite(r.shortest_m)),
            cm(finite(r.longest_m)),
        ));
        if let Some(s) = &self.scattered {
            line(format!("scattered points ({}): {}", s.points, s.on_points));
            line(format!("  {}", s.lattice_analyses));
        }
        line(format!("median pixel area (cm^2)   {}", show(self.median_pixel_area_cm2)));
        line(format!("POD components (99 %)      {}", json_text(self.pod_components_99.map(|n| n.to_string()))));
        for key in DOMAIN_EDGE_KEYS {
            line(format!(
                "d = {key} cm ({} points): effective rank {}, condition number {}",
                json_text(self.points_per_domain.get(key).map(ToString::to_string)),
                show(self.effective_rank.get(key).copied().flatten().and_then(finite)),
                show(self.condition_number.get(key).copied().flatten().and_then(finite))
            ));
        }
        line(format!("refresh (ms)               {}", show(self.refresh_ms.and_then(finite))));
        for w in &self.wavelength {
            let outside = if w.in_range { "" } else { "  (outside the resolvable range)" };
            line(format!(
                "wavelength at {} Hz: {} cm{outside}",
                number_text(w.freq_hz),
                cm(w.median_m.and_then(finite))
            ));
        }
        for (k, e) in &self.errors {
            line(format!("not computed: {k}: \"{}\"", json_escape(e)));
        }
        out
    }
}

/// A number as the JSON prints it (`75.0`), or `null` when not finite.
fn number_text(x: f64) -> String {
    if x.is_finite() { format!("{x:?}") } else { "null".to_owned() }
}

/// A string's body as JSON prints it between quotes.
fn json_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out
}

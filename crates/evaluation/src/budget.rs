//! The Green's-function error budget of a scene on the mock lab, per imperfection (`metaplate budget`).
//!
//! For each variant of the scene that [`Budget::variants`] lists (every imperfection off: the processing floor;
//! each imperfection alone; all on), the scan recipe runs one protocol over a subset of the grid (fast-forward, raw
//! drives, or through a calibration's filters), and every committed Green's function is compared with the lab's
//! ground truth over 80..600 Hz and its octave bands: the full truth, and the truth as the stored window keeps it
//! (the floor is judged by it; the truncation and, for two periods or more of a periodic sweep, the aliasing are
//! the truth's own, see `metaplate_lab::windowed_truth`). The variants share the plate's Green's functions (the
//! imperfections are not the plate's), so only the first lab computes them. `metaplate_lab::budget` does the
//! arithmetic; this module runs the scans and states the result ([`BudgetReport`]).

use std::fmt;
use std::path::Path;

use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use metaplate_lab::budget::{
    BUDGET_BANDS_HZ, Budget, BudgetPart, ERROR_BAND_HZ, ErrorSummary, PartErrors, Quantiles, RowError, splits,
};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPoints, scan};
use metaplate_recipes::{Calibration, RunControl, Silent};
use metaplate_store::Dataset;
use serde::Serialize;

use crate::error::{EvaluationError, StepExt};
use crate::scratch::{scratch_dir, scratch_output};

/// What a budget measures.
#[derive(Debug, Clone)]
pub struct BudgetRequest<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The scan's excitation protocol (its deconvolution as the caller wants it).
    pub protocol: ExcitationProtocol,
    /// The grid subset scanned.
    pub grid: GridSubset,
    /// A calibration directory of the same scene: scan through its filters and compare through them.
    pub calibration: Option<&'a Path>,
    /// Only these parts (`floor`, an imperfection's name, `all-on`); all when `None`.
    pub only: Option<&'a [String]>,
    /// Seed of the lab and the scan.
    pub seed: u64,
    /// The Green's-function cache (a temporary one shared by the variants when `None`).
    pub cache_dir: Option<&'a Path>,
}

/// One part measured, as the budget reports its progress.
#[derive(Debug, Clone)]
pub struct PartMeasured {
    /// 1-based.
    pub index: usize,
    /// Parts to measure.
    pub total: usize,
    /// The part's name.
    pub name: &'static str,
    /// Its errors.
    pub errors: PartErrors,
    /// Wall time of its scan and comparison, s.
    pub elapsed_s: f64,
}

impl fmt::Display for PartMeasured {
    /// The progress line: `budget [k/n] part  median .. dB  p95 .. dB (windowed truth .. / ..)  (.. s)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "budget [{}/{}] {:<16} median {:>7.1} dB  p95 {:>7.1} dB (windowed truth {:>7.1} / {:>7.1})  ({:.0} s)",
            self.index,
            self.total,
            self.name,
            self.errors.full.overall.median_db,
            self.errors.full.overall.p95_db,
            self.errors.windowed.overall.median_db,
            self.errors.windowed.overall.p95_db,
            self.elapsed_s
        )
    }
}

/// Measures the budget: every requested part scanned and compared, `on_part` told after each.
///
/// # Errors
/// A part that is not in the scene's budget, a grid or calibration that does not fit, a scan that fails or commits
/// fewer rows than planned, a comparison the lab refuses.
pub fn measure_budget(
    request: &BudgetRequest<'_>,
    on_part: &mut dyn FnMut(&PartMeasured),
) -> Result<BudgetReport, EvaluationError> {
    let scene = request.scene;
    let GridSubset { nx, ny } = request.grid;
    let plan = ScanPoints::new(scene.grid, &scene.grid_mask(), Some((nx, ny))).step(|| "planning the scan".into())?;
    let calibration = match request.calibration {
        Some(dir) => Some(
            Calibration::load(dir, scene.actuators.len())
                .step(|| format!("loading the calibration {}", dir.display()))?,
        ),
        None => None,
    };
    let mut variants = Budget::variants(scene);
    if let Some(wanted) = request.only {
        if let Some(unknown) = wanted.iter().find(|w| !variants.iter().any(|(p, _)| p.name() == w.as_str())) {
            let known: Vec<&str> = variants.iter().map(|(p, _)| p.name()).collect();
            return Err(EvaluationError::Invalid(format!(
                "--only: no part `{unknown}` in this scene's budget (it has {})",
                known.join(", ")
            )));
        }
        variants.retain(|(p, _)| wanted.iter().any(|w| w == p.name()));
    }
    // Each variant needs a lab of its own (a lab hands out one rig); a cache shares the plate's Green's functions.
    let scratch_cache = match request.cache_dir {
        Some(_) => None,
        None => Some(scratch_dir()?),
    };
    let options = LabOptions {
        seed: Some(request.seed),
        cache_dir: request.cache_dir.map(Path::to_path_buf).or_else(|| scratch_cache.clone()),
        points: Some(plan.points.clone()),
        ..LabOptions::default()
    };
    let mut parts = Vec::new();
    let total = variants.len();
    for (k, (part, variant)) in variants.into_iter().enumerate() {
        let started = std::time::Instant::now();
        let lab = MockLab::new(&variant, &options).step(|| "building the mock lab".into())?;
        let rows = measure(&lab, &variant, &plan, &request.protocol, request.seed, calibration.as_ref())?;
        let errors = PartErrors::of(&rows).step(|| format!("summarising {}", part.name()))?;
        on_part(&PartMeasured {
            index: k + 1,
            total,
            name: part.name(),
            errors,
            elapsed_s: started.elapsed().as_secs_f64(),
        });
        parts.push((part, rows));
    }
    if let Some(dir) = scratch_cache {
        let _ = std::fs::remove_dir_all(dir);
    }
    BudgetReport::of(&scene.name, &request.protocol.name, &plan, request.seed, calibration.is_some(), &parts)
}

/// Scans `plan` with `protocol` on `lab` into a temporary directory; each committed row's error against the truth.
fn measure(
    lab: &MockLab,
    scene: &Scene,
    plan: &ScanPoints,
    protocol: &ExcitationProtocol,
    seed: u64,
    calibration: Option<&Calibration>,
) -> Result<Vec<RowError>, EvaluationError> {
    let (dir, out) = scratch_output(scene)?;
    let cfg = ScanConfig { protocol: protocol.clone(), seed, ..ScanConfig::default() };
    let mut rig = lab.rig().step(|| "taking the lab's rig".into())?;
    scan(&mut rig, plan, calibration, &cfg, &out, &RunControl::new(), &mut Silent)
        .step(|| format!("scanning {} with {}", scene.name, protocol.name))?;
    let dataset = Dataset::open(&dir).step(|| format!("opening the scan {}", dir.display()))?;
    let filters: Option<&[metaplate_dsp::kirkeby::KirkebyFilter]> = calibration.map(|c| c.filters.as_slice());
    let fs = dataset.sample_rate_hz();
    let pre_samples = dataset.manifest().meta.description.as_ref().map_or(0, |d| d.pre_samples as usize);
    // The window the scan kept: the protocol's deconvolution (its band) at the recorder's rate, with the dataset's
    // own length and samples before time 0.
    let mut window = DeconvConfig { sample_rate_hz: fs, pre_samples, ..protocol.deconv };
    // Two periods or more are deconvolved periodically (every period a circular convolution: a response longer
    // than the period wraps its tail onto its start); one is deconvolved linearly over the whole recording, and
    // the interleaved scheme's one sweep too.
    let period_samples = match protocol.scheme {
        Scheme::Sequential | Scheme::Hadamard | Scheme::Staggered if protocol.repetitions() >= 2 => {
            Some((protocol.sweep.duration_s * fs).round() as usize)
        }
        _ => None,
    };
    let mut rows = Vec::with_capacity(dataset.len());
    for (row, meta) in dataset.rows().iter().enumerate() {
        let ir: Vec<f64> = dataset
            .row_ir(row)
            .ok_or_else(|| EvaluationError::Incomplete(format!("row {row} of the scan has no impulse response")))?
            .iter()
            .map(|v| f64::from(*v))
            .collect();
        window.ir_len = ir.len();
        let actuator = usize::from(meta.actuator);
        let filter = match filters {
            Some(f) => Some(
                f.get(actuator)
                    .ok_or_else(|| EvaluationError::Incomplete(format!("no filter for actuator {actuator}")))?,
            ),
            None => None,
        };
        let point = meta.point_index as usize;
        rows.push(
            lab.row_error(point, actuator, &ir, &window, period_samples, filter)
                .step(|| format!("comparing point {point}, actuator {actuator} with the truth"))?,
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    let expected = plan.points.len() * scene.actuators.len();
    if rows.len() != expected {
        return Err(EvaluationError::Incomplete(format!(
            "{}: {} of {expected} rows measured",
            protocol.name,
            rows.len()
        )));
    }
    Ok(rows)
}

/// The budget as `metaplate budget --json` prints it (fields in alphabetical order: the JSON's key order). A part
/// that was not measured is `None` (null).
#[derive(Debug, Clone, Serialize)]
pub struct BudgetReport {
    /// Whether the terms add up as powers, and the splits of the floor.
    pub additivity: Additivity,
    /// The truth wrapped by the period against the windowed truth (a periodic protocol's floor rows).
    pub aliasing: Option<SummaryJson>,
    /// The scene as it is, against the full truth.
    pub all_on: Option<SummaryJson>,
    /// Scanned through a calibration's filters.
    pub calibrated: bool,
    /// The band compared, Hz.
    pub error_band_hz: [f64; 2],
    /// Every imperfection off, against the windowed truth.
    pub floor: Option<SummaryJson>,
    /// Points scanned.
    pub grid_points: usize,
    /// The protocol's name.
    pub protocol: String,
    /// The scene's name.
    pub scene: String,
    /// The lab's and the scan's seed.
    pub seed: u64,
    /// Each imperfection alone, against the full truth.
    pub terms: Vec<SummaryJson>,
    /// The truth outside the window (from the floor's rows).
    pub truncation: Option<SummaryJson>,
    /// Which truth each part is judged against.
    pub truths: Truths,
}

/// An error summary: over the whole band and per octave band, with the other truths beside a part's.
#[derive(Debug, Clone, Serialize)]
pub struct SummaryJson {
    /// Per octave band.
    pub bands: Vec<BandQuantiles>,
    /// The part against the full truth (beside a floor judged against the windowed one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub full_truth: Option<Box<SummaryJson>>,
    /// Median, dB.
    pub median_db: f64,
    /// The term's name (an imperfection's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<&'static str>,
    /// 95th percentile, dB.
    pub p95_db: f64,
    /// Against the truth wrapped by the period (periodic protocols).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub periodic_truth: Option<Box<SummaryJson>>,
    /// Rows compared.
    pub rows: usize,
    /// Against the windowed truth (beside a part judged against the full one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub windowed_truth: Option<Box<SummaryJson>>,
}

/// One octave band's quantiles.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct BandQuantiles {
    /// The band, Hz.
    pub band_hz: [f64; 2],
    /// Median, dB.
    pub median_db: f64,
    /// 95th percentile, dB.
    pub p95_db: f64,
}

/// Median and 95th percentile, dB.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct QuantilesJson {
    /// Median, dB.
    pub median_db: f64,
    /// 95th percentile, dB.
    pub p95_db: f64,
}

/// Whether the terms add up, and the floor's splits row by row.
#[derive(Debug, Clone, Serialize)]
pub struct Additivity {
    /// Floor against the windowed truth = against the wrapped truth + aliasing (null for a linear protocol; absent
    /// without the floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aliasing_split_db: Option<Option<QuantilesJson>>,
    /// Measured all-on median against the predicted one, dB (with the floor and all on).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closure_db: Option<f64>,
    /// All on's median predicted by adding the terms as powers, dB.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub predicted_all_on_median_db: Option<f64>,
    /// Floor against the full truth = against the windowed truth + truncation (absent without the floor).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truncation_split_db: Option<QuantilesJson>,
}

/// Which truth each part is judged against.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Truths {
    /// All on's.
    pub all_on: &'static str,
    /// The floor's.
    pub floor: &'static str,
    /// The terms'.
    pub terms: &'static str,
}

fn quantiles(q: &Quantiles) -> QuantilesJson {
    QuantilesJson { median_db: q.median_db, p95_db: q.p95_db }
}

fn summary(s: &ErrorSummary) -> SummaryJson {
    SummaryJson {
        bands: BUDGET_BANDS_HZ
            .iter()
            .zip(&s.bands)
            .map(|(b, q)| BandQuantiles { band_hz: [b.0, b.1], median_db: q.median_db, p95_db: q.p95_db })
            .collect(),
        full_truth: None,
        median_db: s.overall.median_db,
        name: None,
        p95_db: s.overall.p95_db,
        periodic_truth: None,
        rows: s.rows,
        windowed_truth: None,
    }
}

/// A part's summary against the full truth (`main_is_full`) or the windowed one, with the other truths beside it.
fn part(errors: &PartErrors, main_is_full: bool) -> SummaryJson {
    let mut v = if main_is_full { summary(&errors.full) } else { summary(&errors.windowed) };
    if main_is_full {
        v.windowed_truth = Some(Box::new(summary(&errors.windowed)));
    } else {
        v.full_truth = Some(Box::new(summary(&errors.full)));
    }
    v.periodic_truth = errors.periodic.as_ref().map(|p| Box::new(summary(p)));
    v
}

impl BudgetReport {
    /// The report of the measured parts.
    ///
    /// # Errors
    /// A part whose rows cannot be summarised.
    fn of(
        scene: &str,
        protocol: &str,
        plan: &ScanPoints,
        seed: u64,
        calibrated: bool,
        parts: &[(BudgetPart, Vec<RowError>)],
    ) -> Result<Self, EvaluationError> {
        let summarise = |rows: &[RowError]| PartErrors::of(rows).step(|| "summarising a part".into());
        let of_part = |want: BudgetPart, main_is_full: bool| -> Result<Option<SummaryJson>, EvaluationError> {
            match parts.iter().find(|(p, _)| *p == want) {
                Some((_, rows)) => Ok(Some(part(&summarise(rows)?, main_is_full))),
                None => Ok(None),
            }
        };
        let floor_rows = parts.iter().find(|(p, _)| *p == BudgetPart::Floor).map(|(_, rows)| rows);
        let truncation = match floor_rows {
            Some(rows) => Some(summary(
                &ErrorSummary::of(rows.iter().map(|r| &r.truncation)).step(|| "summarising the truncation".into())?,
            )),
            None => None,
        };
        let aliasing = match floor_rows.map(|rows| rows.iter().map(|r| r.aliasing.as_ref()).collect::<Option<Vec<_>>>())
        {
            Some(Some(rows)) => Some(summary(&ErrorSummary::of(rows).step(|| "summarising the aliasing".into())?)),
            _ => None,
        };
        let mut terms = Vec::new();
        for (p, rows) in parts {
            if let BudgetPart::Alone(_) = p {
                let mut t = part(&summarise(rows)?, true);
                t.name = Some(p.name());
                terms.push(t);
            }
        }
        let mut additivity = match Budget::from_parts(parts) {
            Ok(b) => Additivity {
                aliasing_split_db: None,
                closure_db: Some(b.closure_db()),
                predicted_all_on_median_db: Some(b.predicted_all_on_median_db()),
                truncation_split_db: None,
            },
            Err(_) => Additivity {
                aliasing_split_db: None,
                closure_db: None,
                predicted_all_on_median_db: None,
                truncation_split_db: None,
            },
        };
        if let Some(rows) = floor_rows {
            let (truncation_split, aliasing_split) = splits(rows).step(|| "splitting the floor".into())?;
            additivity.truncation_split_db = Some(quantiles(&truncation_split));
            additivity.aliasing_split_db = Some(aliasing_split.as_ref().map(quantiles));
        }
        Ok(Self {
            additivity,
            aliasing,
            all_on: of_part(BudgetPart::AllOn, true)?,
            calibrated,
            error_band_hz: [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
            floor: of_part(BudgetPart::Floor, false)?,
            grid_points: plan.points.len(),
            protocol: protocol.to_owned(),
            scene: scene.to_owned(),
            seed,
            terms,
            truncation,
            truths: Truths { all_on: "full", floor: "windowed", terms: "full" },
        })
    }

    /// The budget as the table `metaplate budget` prints without `--json`.
    pub fn table_text(&self) -> String {
        let bands: Vec<String> = BUDGET_BANDS_HZ.iter().map(|b| format!("{:.0}-{:.0} Hz", b.0, b.1)).collect();
        let mut out = format!(
            "{} ({}, {} points, seed {}, {}): Green's-function error, dB (median / p95)\n",
            self.scene,
            self.protocol,
            self.grid_points,
            self.seed,
            if self.calibrated { "calibrated" } else { "uncalibrated" }
        );
        out.push_str(&format!("| part | 80-600 Hz | {} |\n", bands.join(" | ")));
        out.push_str(&format!("|---|---|{}\n", "---|".repeat(bands.len())));
        let mut row = |name: &str, v: Option<&SummaryJson>| {
            let Some(v) = v else { return };
            let q = |median: f64, p95: f64| format!("{median:.1} / {p95:.1}");
            let per_band: Vec<String> = v.bands.iter().map(|b| q(b.median_db, b.p95_db)).collect();
            out.push_str(&format!("| {name} | {} | {} |\n", q(v.median_db, v.p95_db), per_band.join(" | ")));
        };
        let floor = self.floor.as_ref();
        row("floor (all off; against the windowed truth)", floor);
        row("truncation (the truth outside the window)", self.truncation.as_ref());
        row("floor against the full truth", floor.and_then(|f| f.full_truth.as_deref()));
        row("aliasing (the truth wrapped by the period)", self.aliasing.as_ref());
        row("floor against the wrapped truth", floor.and_then(|f| f.periodic_truth.as_deref()));
        for t in &self.terms {
            row(t.name.unwrap_or("?"), Some(t));
        }
        row("all on", self.all_on.as_ref());
        row("all on against the windowed truth", self.all_on.as_ref().and_then(|a| a.windowed_truth.as_deref()));
        let a = &self.additivity;
        let finite = |v: Option<f64>| v.filter(|x| x.is_finite());
        if let (Some(p), Some(c)) = (finite(a.predicted_all_on_median_db), finite(a.closure_db)) {
            out.push_str(&format!(
                "terms added as powers predict {p:.1} dB median all on; measured {c:+.1} dB from that\n"
            ));
        }
        let mut split = |what: &str, v: Option<&QuantilesJson>| {
            if let Some(v) = v.filter(|v| v.median_db.is_finite() && v.p95_db.is_finite()) {
                out.push_str(&format!(
                    "{what}, row by row as powers: within {:.2} dB median, {:.2} dB p95\n",
                    v.median_db, v.p95_db
                ));
            }
        };
        split("floor against the full truth = against the windowed truth + truncation", a.truncation_split_db.as_ref());
        split(
            "floor against the windowed truth = against the wrapped truth + aliasing",
            a.aliasing_split_db.as_ref().and_then(Option::as_ref),
        );
        out
    }
}

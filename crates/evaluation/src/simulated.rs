//! The simulated plate's own answers (`metaplate simulate`): its dispersion measured by the paper's k-space method
//! on the plate model's field ([`model_dispersion`]), and its ground-truth Green's functions written as a dataset in
//! the format a scan produces ([`write_ground_truth`]). The analysis crate measures wavelengths from plain slices;
//! the plate model that produces them sits below this crate, so the two meet here.

use std::path::Path;

use metaplate_analysis::dispersion::{DispersionOptions, SceneLayout, wavelengths_at};
use metaplate_analysis::paper_table::ModelWavelength;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_plate::{GreensFunctions, GreensRequest, ModelOptions, PlateModel};
use metaplate_store::{
    DatasetDescription, DatasetMeta, DatasetWriter, IR_UNIT_M_S_PER_N, IfExists, IrMeta, IrRecord, Status,
};
use serde::Serialize;
use serde_json::{Map, Value};

use crate::error::{EvaluationError, StepExt};

/// Points per committed batch file: about 40 MB of f32 impulse responses at 0.5 s and 24 kHz.
const BATCH_POINTS: usize = 100;

/// The wavelengths of a scene's plate model per frequency, as `metaplate simulate dispersion --json` prints them
/// (fields in alphabetical order: the JSON's key order).
#[derive(Debug, Clone, Serialize)]
pub struct DispersionReport {
    /// How the wavelengths are measured.
    pub method: &'static str,
    /// Per frequency.
    pub points: Vec<DispersionPoint>,
    /// The scene's name.
    pub scene: String,
    /// The scene's content hash.
    pub scene_hash: String,
}

/// The wavelengths at one frequency.
#[derive(Debug, Clone, Serialize)]
pub struct DispersionPoint {
    /// The analytic A0 wavelength over the k-space one.
    pub a0_over_wavelength: f64,
    /// The analytic A0 wavelength of the (host) plate, m.
    pub a0_wavelength_m: f64,
    /// Actuators whose k-space estimate falls outside the method's resolved range.
    pub actuators_flagged: usize,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Interquartile range of the k-space estimates over the actuators, m.
    pub iqr_m: [f64; 2],
    /// The plate-equation estimate, m.
    pub local_wavelength_m: Option<f64>,
    /// Each actuator's k-space median, m.
    pub per_actuator_m: Vec<f64>,
    /// The k-space (paper's) wavelength, median over the actuators, m.
    pub wavelength_m: f64,
}

impl DispersionReport {
    /// The k-space wavelength per frequency, resolved where no actuator's estimate is flagged (the rule by which
    /// [`metaplate_analysis::report::wavelength_at`] judges a dataset's).
    pub fn model_wavelengths(&self) -> Vec<ModelWavelength> {
        self.points
            .iter()
            .map(|p| ModelWavelength {
                freq_hz: p.freq_hz,
                wavelength_m: p.wavelength_m,
                resolved: p.actuators_flagged == 0,
            })
            .collect()
    }

    /// The report as the table `metaplate simulate dispersion` prints without `--json`.
    pub fn table_text(&self) -> String {
        let mut out = format!(
            "{:>8}  {:>11}  {:>11}  {:>10}  {:>9}  k-space flagged\n",
            "f (Hz)", "k-space (cm)", "local (cm)", "A0 (cm)", "A0/k-space"
        );
        for p in &self.points {
            let cm = |v: f64| v * 100.0;
            out.push_str(&format!(
                "{:>8.1}  {:>11.2}  {:>11.2}  {:>10.2}  {:>9.2}  {}\n",
                p.freq_hz,
                cm(p.wavelength_m),
                cm(p.local_wavelength_m.unwrap_or(f64::NAN)),
                cm(p.a0_wavelength_m),
                p.a0_over_wavelength,
                p.actuators_flagged
            ));
        }
        out
    }
}

/// `from_hz` to `to_hz` by `step_hz`.
///
/// # Errors
/// Bounds out of order, non-positive or non-finite, or more than 10000 frequencies.
pub fn frequencies(from_hz: f64, to_hz: f64, step_hz: f64) -> Result<Vec<f64>, EvaluationError> {
    if !(from_hz.is_finite()
        && to_hz.is_finite()
        && step_hz.is_finite()
        && from_hz > 0.0
        && to_hz >= from_hz
        && step_hz > 0.0)
    {
        return Err(EvaluationError::Invalid(format!(
            "need 0 < --from-hz <= --to-hz and --step-hz > 0, got {from_hz}, {to_hz}, {step_hz}"
        )));
    }
    let n = ((to_hz - from_hz) / step_hz + 1e-9).floor() as usize + 1;
    if n > 10_000 {
        return Err(EvaluationError::Invalid(format!("{n} frequencies is more than 10000: use a larger --step-hz")));
    }
    Ok((0..n).map(|i| from_hz + i as f64 * step_hz).collect())
}

/// The scene's measured points, or the measured points of an evenly spread NX x NY subset of its grid.
///
/// # Errors
/// A subset that does not fit the grid, or one without a measured point.
pub fn select_points(scene: &Scene, grid: Option<GridSubset>) -> Result<Vec<usize>, EvaluationError> {
    let mask = scene.grid_mask();
    let candidates = match grid {
        None => (0..scene.grid.len()).collect(),
        Some(subset) => subset.indices(&scene.grid).step(|| format!("--grid {subset}"))?,
    };
    let points: Vec<usize> = candidates.into_iter().filter(|&p| mask.get(p).copied().unwrap_or(false)).collect();
    if points.is_empty() {
        return Err(EvaluationError::Invalid(
            "no measured point in the selected grid (every point is off the plate or under a support)".into(),
        ));
    }
    Ok(points)
}

/// Per-frequency wavelength report of a scene's plate model: the paper's k-space method (`wavelength_m`, median over
/// actuators, with its interquartile range and how many actuators' estimates fall outside the method's resolved
/// range), and the plate-equation estimate (`local_wavelength_m`), which resolves wavelengths as long as the plate
/// where the aperture-limited k-space method cannot. `on_frequency` is called after each frequency.
///
/// # Errors
/// A plate that cannot be discretised or solved, or a field the estimators refuse.
pub fn model_dispersion(
    scene: &Scene,
    options: &ModelOptions,
    freqs: &[f64],
    on_frequency: &mut dyn FnMut(),
) -> Result<DispersionReport, EvaluationError> {
    let model = PlateModel::from_scene(scene, options).step(|| "discretising the plate".into())?;
    let layout = SceneLayout::new(scene);
    let actuators: Vec<usize> = (0..scene.actuators.len()).collect();
    let mut points = Vec::with_capacity(freqs.len());
    for &f in freqs {
        let response = model
            .frequency_response(f, &actuators, &layout.points)
            .step(|| format!("the plate's response at {f} Hz"))?;
        let w = wavelengths_at(&response, actuators.len(), &layout.layout(), &DispersionOptions::default())
            .step(|| format!("the wavelength at {f} Hz"))?;
        let a0 = scene.plate.a0_wavelength_m(f).step(|| format!("the A0 wavelength at {f} Hz"))?;
        let summary = &w.k_space_summary;
        points.push(DispersionPoint {
            a0_over_wavelength: a0 / summary.median_m,
            a0_wavelength_m: a0,
            actuators_flagged: summary.flagged,
            freq_hz: f,
            iqr_m: [summary.iqr_m.0, summary.iqr_m.1],
            local_wavelength_m: w.local_summary.as_ref().map(|l| l.wavelength_m),
            per_actuator_m: w.k_space.iter().map(|e| e.median_m).collect(),
            wavelength_m: summary.median_m,
        });
        on_frequency();
    }
    Ok(DispersionReport {
        method: "k-space (the paper's): 2-D FFT of each actuator's field over the measured grid, half-maximum region \
                 around the peak, median over actuators; local: plate-equation (biharmonic Rayleigh quotient) estimate",
        points,
        scene: scene.name.clone(),
        scene_hash: scene.id().hash,
    })
}

/// What [`write_ground_truth`] wrote, as `metaplate simulate greens` prints it.
#[derive(Debug, Clone, Serialize)]
pub struct GroundTruthSummary {
    /// Actuators.
    pub actuators: usize,
    /// Batch files committed.
    pub batches: usize,
    /// Time to compute (or read from the cache) the Green's functions, s.
    pub compute_s: f64,
    /// The dataset's directory.
    pub dataset: String,
    /// Samples per impulse response.
    pub ir_len: usize,
    /// Points.
    pub points: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// The scene's name.
    pub scene: String,
    /// Wall time in all, s.
    pub total_s: f64,
}

/// Where [`write_ground_truth`] is.
#[derive(Debug, Clone, Copy)]
pub enum GroundTruthProgress {
    /// Computing (or reading from the cache) the Green's functions of so many points and actuators.
    Computing {
        /// Points.
        points: usize,
        /// Actuators.
        actuators: usize,
    },
    /// Written so many of the points.
    Writing {
        /// Points written.
        done: usize,
        /// Points in all.
        total: usize,
    },
}

/// Computes the Green's functions of `request` (through the cache `cache_dir` when given) and writes them as a
/// dataset in `out` (status "ground-truth"), replacing one there only when `force`.
///
/// # Errors
/// A plate that cannot be solved, a dataset that cannot be created (one already there without `force`) or written.
pub fn write_ground_truth(
    scene: &Scene,
    options: &ModelOptions,
    request: &GreensRequest,
    out: &Path,
    force: bool,
    cache_dir: Option<&Path>,
    progress: &mut dyn FnMut(GroundTruthProgress),
) -> Result<GroundTruthSummary, EvaluationError> {
    let started = std::time::Instant::now();
    progress(GroundTruthProgress::Computing { points: request.points.len(), actuators: request.actuators.len() });
    let greens = metaplate_plate::greens_functions(scene, options, request, cache_dir)
        .step(|| "computing the Green's functions".into())?;
    let compute_s = started.elapsed().as_secs_f64();
    let mut config = Map::new();
    let number = |x: f64| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number);
    config.insert("band_hz".into(), Value::Array(vec![number(request.band_hz.0), number(request.band_hz.1)]));
    config.insert("duration_s".into(), number(request.duration_s));
    config.insert("sample_rate_hz".into(), number(request.sample_rate_hz));
    config.insert("refinement".into(), Value::from(options.refinement));
    config.insert("points".into(), Value::from(request.points.len()));
    config.insert("actuators".into(), Value::from(request.actuators.clone()));
    config.insert(
        "units".into(),
        Value::from("plate normal velocity per unit actuator force, m/s/N, as a discrete-time filter"),
    );
    let meta =
        DatasetMeta::new("simulate-greens", config, scene.id(), env!("CARGO_PKG_VERSION"), scene.seed, scene.grid)
            .with_description(DatasetDescription { ir_unit: IR_UNIT_M_S_PER_N.into(), pre_samples: 0 });
    let if_exists = if force { IfExists::Replace } else { IfExists::Refuse };
    let mut writer = DatasetWriter::create(out, meta, if_exists)
        .step(|| format!("creating dataset {} (use --force to replace one)", out.display()))?;
    let total = greens.points.len();
    for (k, chunk) in (0..total).collect::<Vec<_>>().chunks(BATCH_POINTS).enumerate() {
        let records = records(scene, &greens, chunk)?;
        writer.commit_batch(&records).step(|| format!("writing dataset {}", out.display()))?;
        progress(GroundTruthProgress::Writing { done: (k * BATCH_POINTS + chunk.len()).min(total), total });
    }
    let manifest = writer.finish().step(|| format!("finishing dataset {}", out.display()))?;
    Ok(GroundTruthSummary {
        actuators: greens.actuators.len(),
        batches: manifest.batches.len(),
        compute_s,
        dataset: out.display().to_string(),
        ir_len: greens.ir_len,
        points: greens.points.len(),
        sample_rate_hz: greens.sample_rate_hz,
        scene: scene.name.clone(),
        total_s: started.elapsed().as_secs_f64(),
    })
}

fn records(scene: &Scene, greens: &GreensFunctions, point_ks: &[usize]) -> Result<Vec<IrRecord>, EvaluationError> {
    let mut out = Vec::with_capacity(point_ks.len() * greens.actuators.len());
    let index = |what: &str| EvaluationError::Invalid(format!("internal: {what} out of range"));
    for &pk in point_ks {
        let point = *greens.points.get(pk).ok_or_else(|| index("Green's function point"))?;
        let (ix, iy) = scene.grid.indices(point);
        for (ak, &actuator) in greens.actuators.iter().enumerate() {
            let ir = greens.ir(pk, ak).ok_or_else(|| index("Green's function index"))?;
            let (ix, iy, actuator) = (
                u32::try_from(ix).map_err(|_| index("grid column"))?,
                u32::try_from(iy).map_err(|_| index("grid row"))?,
                u16::try_from(actuator).map_err(|_| index("actuator"))?,
            );
            let mut meta = IrMeta::at_grid(&scene.grid, ix, iy, actuator, greens.sample_rate_hz)
                .step(|| format!("the record of point {point}"))?;
            meta.status = Some(Status::GroundTruth);
            out.push(IrRecord { meta, ir: ir.iter().map(|&v| v as f32).collect() });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frequency is resolved while no actuator's estimate is flagged.
    #[test]
    fn a_model_wavelength_is_resolved_while_no_actuator_is_flagged() {
        let point = |freq_hz: f64, actuators_flagged: usize| DispersionPoint {
            a0_over_wavelength: 2.0,
            a0_wavelength_m: 0.2,
            actuators_flagged,
            freq_hz,
            iqr_m: [0.09, 0.11],
            local_wavelength_m: Some(0.1),
            per_actuator_m: vec![0.1; 8],
            wavelength_m: 0.1,
        };
        let report = DispersionReport {
            method: "k-space",
            points: vec![point(75.0, 0), point(375.0, 1), point(600.0, 8)],
            scene: "s".into(),
            scene_hash: "h".into(),
        };
        let resolved: Vec<(f64, bool)> = report.model_wavelengths().iter().map(|w| (w.freq_hz, w.resolved)).collect();
        assert_eq!(resolved, [(75.0, true), (375.0, false), (600.0, false)]);
        assert!(report.model_wavelengths().iter().all(|w| w.wavelength_m == 0.1));
    }
}

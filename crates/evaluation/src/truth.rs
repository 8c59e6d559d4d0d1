//! A measured dataset against the mock lab's ground truth: the error of each measured Green's function, as the
//! demo, `tradeoff` and `report` state it.

use std::path::Path;

use metaplate_core::scene::Scene;
use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::quantile;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_store::Dataset;
use serde::Serialize;

use crate::error::{EvaluationError, StepExt};

/// Per measured row (point, actuator) of `dataset`: the error of the measured response against the lab's truth
/// ([`MockLab::response_error_db`] over [`ERROR_BAND_HZ`]), dB, through the actuator's inverse filter when the scan
/// was compensated (`filters`, indexed by actuator). Sorted ascending; non-finite errors are left out.
///
/// # Errors
/// A row without its impulse response, an actuator without a filter, or a response the lab cannot compare (a
/// point it has no Green's function for; see [`MockLab::response_error_db`]).
pub fn greens_errors(
    lab: &MockLab,
    dataset: &Dataset,
    filters: Option<&[KirkebyFilter]>,
) -> Result<Vec<f64>, EvaluationError> {
    let fs = dataset.sample_rate_hz();
    let pre_samples = dataset.manifest().meta.description.as_ref().map_or(0, |d| d.pre_samples as usize);
    let mut errors = Vec::with_capacity(dataset.len());
    for (row, meta) in dataset.rows().iter().enumerate() {
        let ir = dataset
            .row_ir(row)
            .ok_or_else(|| EvaluationError::Incomplete(format!("row {row} of the dataset has no impulse response")))?;
        let ir: Vec<f64> = ir.iter().map(|v| f64::from(*v)).collect();
        let ir = metaplate_lab::time_zero_first(&ir, pre_samples);
        let actuator = usize::from(meta.actuator);
        let filter = match filters {
            Some(filters) => Some(
                filters
                    .get(actuator)
                    .ok_or_else(|| EvaluationError::Incomplete(format!("no filter for actuator {actuator}")))?,
            ),
            None => None,
        };
        let point = meta.point_index as usize;
        errors.push(
            lab.response_error_db(point, actuator, &ir, fs, ERROR_BAND_HZ, filter)
                .step(|| format!("comparing point {point}, actuator {actuator} with the truth"))?,
        );
    }
    errors.retain(|e| e.is_finite());
    errors.sort_by(f64::total_cmp);
    Ok(errors)
}

/// [`greens_errors`] for a dataset measured on the mock lab of `scene`: builds that lab with the dataset's seed over
/// the points its scan planned, in the plan's order (so that the scan's entry in the Green's-function cache
/// `cache_dir` is found), or over its measured points when no plan is recorded.
///
/// # Errors
/// A lab that cannot be built, or as [`greens_errors`].
pub fn dataset_errors(
    scene: &Scene,
    dataset: &Dataset,
    filters: Option<&[KirkebyFilter]>,
    cache_dir: Option<&Path>,
) -> Result<Vec<f64>, EvaluationError> {
    let options = LabOptions {
        seed: Some(dataset.manifest().meta.seed),
        cache_dir: cache_dir.map(Path::to_path_buf),
        points: Some(planned_points(dataset)),
        ..LabOptions::default()
    };
    let lab = MockLab::new(scene, &options).step(|| "building the mock lab for the ground truth".into())?;
    greens_errors(&lab, dataset, filters)
}

/// The scan's planned points in its order (the configuration's `points`), else the dataset's measured points.
fn planned_points(dataset: &Dataset) -> Vec<usize> {
    let planned = metaplate_recipes::cells::planned_points(&dataset.manifest().meta.config);
    let points = if planned.is_empty() { dataset.points() } else { planned.as_slice() };
    points.iter().map(|&p| p as usize).collect()
}

/// The errors of a dataset's Green's functions against the truth, as the demo's summary and the report hold them.
/// Fields in alphabetical order: the JSON's key order.
#[derive(Debug, Clone, Serialize)]
pub struct GreensErrorSummary {
    /// The band compared, Hz.
    pub band_hz: [f64; 2],
    /// Median error, dB (`None` without a row).
    pub median: Option<f64>,
    /// 95th percentile, dB.
    pub p95: Option<f64>,
    /// Rows compared.
    pub rows: usize,
    /// The worst row's error, dB.
    pub worst: Option<f64>,
}

impl GreensErrorSummary {
    /// The summary of sorted errors (see [`greens_errors`]): band, row count, median, p95 and worst.
    pub fn of(sorted: &[f64]) -> Self {
        Self {
            band_hz: [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
            median: quantile(&mut sorted.to_vec(), 0.5),
            p95: quantile(&mut sorted.to_vec(), 0.95),
            rows: sorted.len(),
            worst: sorted.last().copied(),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use metaplate_dsp::deconv::DeconvConfig;
    use metaplate_lab::{LabOptions, MockLab};
    use metaplate_plate::ModelOptions;
    use metaplate_store::{
        Dataset, DatasetDescription, DatasetMeta, DatasetWriter, IR_UNIT_M_S_PER_N, IfExists, IrMeta, IrRecord,
    };

    use super::{GreensErrorSummary, greens_errors};

    /// A dataset of one point's rows (one per actuator), each the lab's windowed truth times `gain`.
    fn dataset_of_truth(lab: &MockLab, scene: &metaplate_core::scene::Scene, point: usize, gain: f64) -> Dataset {
        let fs = scene.daq.sample_rate_hz;
        // 0.5 s from time 0: the window holds the whole 0.25 s response.
        let window =
            DeconvConfig { ir_len: (0.5 * fs) as usize, pre_samples: 0, sample_rate_hz: fs, ..DeconvConfig::paper() };
        let meta = DatasetMeta::new("test", serde_json::Map::new(), scene.id(), "test", 1, scene.grid)
            .with_description(DatasetDescription { ir_unit: IR_UNIT_M_S_PER_N.into(), pre_samples: 0 });
        let dir = tempfile::tempdir().unwrap().keep();
        let mut writer = DatasetWriter::create(&dir, meta, IfExists::Refuse).unwrap();
        let (ix, iy) = scene.grid.indices(point);
        let records: Vec<IrRecord> = (0..scene.actuators.len())
            .map(|a| {
                let truth = lab.windowed_truth(point, a, &window, None, None).unwrap();
                let ir = truth.response()[..window.ir_len].iter().map(|v| (v * gain) as f32).collect();
                let meta = IrMeta::at_grid(&scene.grid, ix as u32, iy as u32, a as u16, fs).unwrap();
                IrRecord { meta, ir }
            })
            .collect();
        writer.commit_batch(&records).unwrap();
        writer.finish().unwrap();
        Dataset::open(&dir).unwrap()
    }

    #[test]
    fn a_perfect_measurement_compares_as_near_equal_and_a_scaled_one_by_its_scale() {
        // One point near the homogeneous plate's centre, a coarse lattice and a narrow band: seconds of plate model.
        let scene = metaplate_core::scene::Scene::builtin("homogeneous").unwrap();
        let measured = scene.measured_points();
        let point = measured[measured.len() / 2];
        // Kept between runs, under the target directory (`target/tmp`, where integration tests keep theirs: a unit
        // test has no CARGO_TARGET_TMPDIR); the test binary is target/PROFILE/deps/NAME.
        let exe = std::env::current_exe().unwrap();
        let target = exe.ancestors().nth(3).unwrap();
        let cache = target.join("tmp").join("metaplate-evaluation-tests-cache");
        std::fs::create_dir_all(&cache).unwrap();
        let options = LabOptions {
            seed: Some(1),
            cache_dir: Some(cache),
            points: Some(vec![point]),
            model: ModelOptions { refinement: 1, threads: 2 },
            band_hz: (100.0, 600.0),
            ir_duration_s: 0.25,
            ..LabOptions::default()
        };
        let lab = MockLab::new(&scene, &options).unwrap();
        let errors = greens_errors(&lab, &dataset_of_truth(&lab, &scene, point, 1.0), None).unwrap();
        assert_eq!(errors.len(), scene.actuators.len(), "one error per row");
        assert!(errors.windows(2).all(|w| w[0] <= w[1]), "sorted: {errors:?}");
        let summary = GreensErrorSummary::of(&errors);
        assert_eq!((summary.rows, summary.worst), (errors.len(), errors.last().copied()));
        assert!(summary.worst.unwrap() < -35.0, "the truth against itself (the band limit and f32 only): {errors:?}");
        // 10 % too loud: an error of 20 log10(0.1) = -20 dB on every row.
        let errors = greens_errors(&lab, &dataset_of_truth(&lab, &scene, point, 1.1), None).unwrap();
        assert!(errors.iter().all(|e| (e + 20.0).abs() < 1.0), "{errors:?}");
        // The summary as the demo's JSON holds it: keys in alphabetical order.
        let json = serde_json::to_string(&GreensErrorSummary::of(&[-40.0, -30.0])).unwrap();
        assert!(json.starts_with(r#"{"band_hz":[80.0,600.0],"median":"#), "{json}");
        assert!(json.ends_with(r#","rows":2,"worst":-30.0}"#), "{json}");
        assert_eq!(GreensErrorSummary::of(&[]).median, None);
    }
}

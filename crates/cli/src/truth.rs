//! A measured dataset against the mock lab's ground truth: the error of each measured Green's function, as the
//! demo, `tradeoff` and `report` state it.

use std::path::Path;

use anyhow::Context;
use metaplate_core::scene::Scene;
use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::quantile;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_store::Dataset;
use serde_json::{Value, json};

/// Per measured row (point, actuator) of `dataset`: the error of the measured response against the lab's truth
/// ([`MockLab::response_error_db`] over [`ERROR_BAND_HZ`]), dB, through the actuator's inverse filter when the scan
/// was compensated (`filters`, indexed by actuator). Sorted ascending; non-finite errors are left out.
///
/// # Errors
/// A row of a point the lab has no Green's function for, an actuator without a filter, or a response the lab
/// cannot compare (see [`MockLab::response_error_db`]).
pub fn greens_errors(lab: &MockLab, dataset: &Dataset, filters: Option<&[KirkebyFilter]>) -> anyhow::Result<Vec<f64>> {
    let fs = dataset.sample_rate_hz();
    let pre_samples = dataset.manifest().meta.description.as_ref().map_or(0, |d| d.pre_samples as usize);
    let mut errors = Vec::with_capacity(dataset.len());
    for (row, meta) in dataset.rows().iter().enumerate() {
        let ir = dataset.row_ir(row).context("a row without its impulse response")?;
        let ir: Vec<f64> = ir.iter().map(|v| f64::from(*v)).collect();
        let ir = metaplate_lab::time_zero_first(&ir, pre_samples);
        let filter = match filters {
            Some(filters) => Some(filters.get(usize::from(meta.actuator)).context("no filter for an actuator")?),
            None => None,
        };
        errors.push(lab.response_error_db(
            meta.point_index as usize,
            usize::from(meta.actuator),
            &ir,
            fs,
            ERROR_BAND_HZ,
            filter,
        )?);
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
) -> anyhow::Result<Vec<f64>> {
    let options = LabOptions {
        seed: Some(dataset.manifest().meta.seed),
        cache_dir: cache_dir.map(Path::to_path_buf),
        points: Some(planned_points(dataset)),
        ..LabOptions::default()
    };
    let lab = MockLab::new(scene, &options).context("building the mock lab for the ground truth")?;
    greens_errors(&lab, dataset, filters)
}

/// The scan's planned points in its order (the configuration's `points`), else the dataset's measured points.
fn planned_points(dataset: &Dataset) -> Vec<usize> {
    let planned = metaplate_monitor::cells::planned_points(&dataset.manifest().meta.config);
    let points = if planned.is_empty() { dataset.points() } else { planned.as_slice() };
    points.iter().map(|&p| p as usize).collect()
}

/// Sorted errors as the JSON the demo's summary and the report hold: band, row count, median, p95 and worst.
pub fn errors_json(sorted: &[f64]) -> Value {
    json!({
        "band_hz": [ERROR_BAND_HZ.0, ERROR_BAND_HZ.1],
        "rows": sorted.len(),
        "median": quantile(&mut sorted.to_vec(), 0.5),
        "p95": quantile(&mut sorted.to_vec(), 0.95),
        "worst": sorted.last(),
    })
}

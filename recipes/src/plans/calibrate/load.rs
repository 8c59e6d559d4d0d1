//! A calibration read back for a scan: the inverse filters, their statuses and the hash a scan stores.

use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::median;
use metaplate_store::{Dataset, RowKind, Status};
use serde_json::Value;

use crate::error::RecipeError;
use crate::plans::calibrate::processing::in_band_magnitudes;
use crate::plans::calibrate::{RECIPE, calibration_row};

/// A calibration read back for a scan: one inverse filter per actuator and a hash that identifies it.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Inverse filter of each actuator, indexed by actuator.
    pub filters: Vec<KirkebyFilter>,
    /// Status of each actuator's calibration.
    pub statuses: Vec<Status>,
    /// SHA-256 over the calibration's configuration hash and batch checksums, `"sha256:<hex>"`: a scan stores it,
    /// and a resumed scan refuses a different one.
    pub content_hash: String,
}

impl Calibration {
    /// Reads and verifies (checksums) the calibration dataset in `dir`, expecting `actuators` actuators.
    ///
    /// # Errors
    /// [`RecipeError::Store`] for an unreadable or corrupt dataset; [`RecipeError::Calibration`] for one that is not
    /// a calibration, lacks an actuator or has the wrong number of them.
    pub fn load(dir: &std::path::Path, actuators: usize) -> Result<Self, RecipeError> {
        let bad = |reason: String| RecipeError::Calibration { dir: dir.display().to_string(), reason };
        let dataset = Dataset::open(dir)?;
        let manifest = dataset.manifest();
        if manifest.meta.recipe != RECIPE {
            return Err(bad(format!("is a `{}` dataset, not a calibration", manifest.meta.recipe)));
        }
        let delay = manifest
            .meta
            .config
            .get("kirkeby")
            .and_then(|k| k.get("modelling_delay_samples"))
            .and_then(Value::as_u64)
            .ok_or_else(|| bad("its configuration lacks kirkeby.modelling_delay_samples".into()))?;
        let band = manifest
            .meta
            .config
            .get("check_band_hz")
            .and_then(Value::as_array)
            .and_then(|b| Some((b.first()?.as_f64()?, b.get(1)?.as_f64()?)))
            .ok_or_else(|| bad("its configuration lacks check_band_hz".into()))?;
        let fs = dataset.sample_rate_hz();
        let mut filters = Vec::with_capacity(actuators);
        let mut statuses = Vec::with_capacity(actuators);
        for a in 0..actuators {
            let key = a as u16;
            let filter_row = calibration_row(&dataset, RowKind::Filter, key);
            let (Some(taps), Some(meta)) =
                (filter_row.and_then(|r| dataset.row_ir(r)), filter_row.and_then(|r| dataset.rows().get(r)))
            else {
                return Err(bad(format!("actuator {a} is not calibrated (run calibrate again with --resume)")));
            };
            let taps: Vec<f64> = taps.iter().map(|v| f64::from(*v)).collect();
            let response = calibration_row(&dataset, RowKind::Response, key).and_then(|r| dataset.row_ir(r));
            let max_boost_db = match response {
                Some(response) => boost_db(&taps, response, fs, band)?,
                None => return Err(bad(format!("actuator {a}'s measured response is missing"))),
            };
            filters.push(KirkebyFilter {
                taps,
                sample_rate_hz: fs,
                modelling_delay_samples: delay as usize,
                max_boost_db,
            });
            statuses.push(meta.status.unwrap_or(Status::Failed));
        }
        if dataset.actuators().iter().any(|a| usize::from(*a) >= actuators) {
            return Err(bad(format!("holds more actuators than the {actuators} wired")));
        }
        let mut identity = manifest.config_hash.clone();
        for batch in &manifest.batches {
            identity.push('\n');
            identity.push_str(&batch.checksum);
        }
        Ok(Self { filters, statuses, content_hash: metaplate_store::sha256(identity.as_bytes()) })
    }
}

/// `20 log10(max |H| max |C_n|)`, dB, with `C_n` the response normalised by its median in-band gain as the design
/// saw it: the filter's boost, as [`KirkebyFilter::max_boost_db`] defines it.
fn boost_db(taps: &[f64], response: &[f32], fs: f64, band_hz: (f64, f64)) -> Result<f64, RecipeError> {
    let response: Vec<f64> = response.iter().map(|v| f64::from(*v)).collect();
    let reference_gain = median(&mut in_band_magnitudes(&response, fs, band_hz)?).unwrap_or(0.0);
    let n = metaplate_dsp::fft::fast_len(2 * taps.len().max(response.len()))?;
    let peak = |x: &[f64]| -> Result<f64, RecipeError> {
        Ok(metaplate_dsp::fft::forward(x, n)?.iter().map(|c| c.norm()).fold(0.0, f64::max))
    };
    let db = 20.0 * (peak(taps)? * peak(&response)? / reference_gain).log10();
    if db.is_finite() { Ok(db) } else { Err(RecipeError::Config("a calibration filter or response is zero".into())) }
}

//! A protocol's measured trade, per seed and over the seeds, and an estimate as the JSON holds it.

use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use serde::Serialize;

use super::fit::Estimate;

/// One protocol's measured trade with one seed (fields in the JSON's key order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeedTrade {
    /// Rows that failed.
    pub failed_rows: usize,
    /// Median Green's-function error, dB.
    pub median_error_db: f64,
    /// Median pixel area, cm^2 (`None` when no contour closes).
    pub median_pixel_area_cm2: Option<f64>,
    /// 95th percentile of the error, dB.
    pub p95_error_db: f64,
    /// The seed.
    pub seed: u64,
    /// Rig-clock time per point, s.
    pub time_per_point_s: f64,
}

/// One protocol's trade over every seed.
#[derive(Debug, Clone)]
pub struct ProtocolTrade {
    /// The protocol.
    pub protocol: ExcitationProtocol,
    /// Seconds of excitation per point and round (every shot's periods): what the noise averages over.
    pub excitation_s: f64,
    /// Seconds of excitation each actuator receives per point and round (the shots it plays in).
    pub excitation_per_actuator_s: f64,
    /// The protocol's nominal time per point, s.
    pub nominal_time_per_point_s: f64,
    /// Per seed, in the seeds' order.
    pub per_seed: Vec<SeedTrade>,
}

impl ProtocolTrade {
    /// The protocol's name.
    pub fn name(&self) -> &str {
        &self.protocol.name
    }

    pub(crate) fn estimate(&self, value: impl Fn(&SeedTrade) -> f64) -> Option<Estimate> {
        Estimate::of(&self.per_seed.iter().map(value).collect::<Vec<_>>())
    }

    /// The mean of a figure over the seeds (NaN only when there is no seed, which a trade never has).
    pub(crate) fn mean(&self, value: impl Fn(&SeedTrade) -> f64) -> f64 {
        self.estimate(value).map_or(f64::NAN, |e| e.mean)
    }

    pub(crate) fn failed_rows(&self) -> usize {
        self.per_seed.iter().map(|s| s.failed_rows).sum()
    }

    pub(crate) fn seed(&self, seed: u64) -> Option<&SeedTrade> {
        self.per_seed.iter().find(|s| s.seed == seed)
    }
}

/// An estimate as the JSON holds it: mean, interval, count.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EstimateJson {
    /// The 95 % interval (`None` from one value).
    pub ci95: Option<[f64; 2]>,
    /// The mean.
    pub mean: f64,
    /// How many values.
    pub n: usize,
}

/// An estimate as the JSON holds it (`None`: null).
pub(crate) fn estimate_json(e: Option<Estimate>) -> Option<EstimateJson> {
    e.map(|e| EstimateJson { ci95: e.ci95.map(|(lo, hi)| [lo, hi]), mean: e.mean, n: e.n })
}

/// The scheme's family name (`hadamard`, `interleaved`) of a non-adaptive simultaneous protocol; `None` for the
/// rest (sequential: not simultaneous; adaptive: its time is not fixed, so it counts alone).
pub(crate) fn simultaneous_family(protocol: &ExcitationProtocol) -> Option<&'static str> {
    if protocol.adaptive.is_some() {
        return None;
    }
    match protocol.scheme {
        Scheme::Sequential => None,
        Scheme::Hadamard => Some("hadamard"),
        Scheme::Staggered => Some("staggered"),
        Scheme::Interleaved { .. } => Some("interleaved"),
    }
}

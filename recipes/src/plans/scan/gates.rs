//! The scan's quality gates (SNR, clock drift) on a decoded response, and its conversion to m/s per full scale:
//! shared by the sequential processing and the simultaneous protocols.

use metaplate_dsp::pipeline::ChannelResult;

use crate::plans::scan::points::{Measured, Outcome, Problem};

/// The scan's quality gates, and the loopback's volts per full scale (to convert responses to m/s per full scale).
pub(crate) struct Gates {
    pub min_snr_db: f64,
    pub max_drift_ppm: f64,
    pub volts_per_fs: f64,
}

/// `r` with its response (and its noise) multiplied by `to_units`.
pub(crate) fn in_units(mut r: ChannelResult, to_units: f64) -> ChannelResult {
    r.ir.iter_mut().for_each(|v| *v *= to_units);
    r.noise_energy = r.noise_energy.map(|e| e * to_units * to_units);
    r
}

/// The outcome of `actuator`'s decoded response `r` (m/s per full scale, sampled at `sample_rate_hz`): the gates
/// (drift, then SNR) decide its problem, unless an acquisition `problem` (clipping, a gap) explains it better. The
/// response is kept even when a gate fails: it is committed if no later visit does better.
pub(crate) fn gated(
    actuator: usize,
    r: ChannelResult,
    problem: Option<Problem>,
    gates: &Gates,
    sample_rate_hz: f64,
) -> Outcome {
    let gate = if r.drift_ppm.abs() > gates.max_drift_ppm {
        Some(Problem::Drift(r.drift_ppm))
    } else {
        r.snr_db.filter(|s| *s < gates.min_snr_db).map(Problem::LowSnr)
    };
    let error_db = r.estimated_error_db(sample_rate_hz);
    (actuator, Some(Measured { ir: r.ir, snr_db: r.snr_db, error_db }), problem.or(gate))
}

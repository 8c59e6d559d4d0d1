//! How long a run has left, from how long its committed units took: what the progress display, the `--json` events
//! and the monitor state.

use metaplate_dsp::stats::quantile;

/// A duration longer than this many median unit times is downtime (a stop and resume, a pause), left out of the
/// 90th percentile.
pub const DOWNTIME_FACTOR: f64 = 20.0;

/// The remaining time of a run, s: the typical case and a conservative bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RemainingTime {
    /// Remaining units times the median unit time, s.
    pub median_s: f64,
    /// Remaining units times the 90th-percentile unit time, s: conservative, since it takes every remaining unit
    /// to be as slow as the slowest tenth so far (retries and re-measures included), where their sum would average
    /// out.
    pub p90_s: f64,
}

impl RemainingTime {
    /// The estimate for `remaining_units` from the durations of the units committed so far (`unit_durations_s`, s,
    /// on whichever clock the caller measures).
    ///
    /// Durations over [`DOWNTIME_FACTOR`] median unit times are left out of the 90th percentile.
    ///
    /// Valid range: finite, non-negative durations. `None` with no duration yet, or when one is negative or not
    /// finite (a clock that went back, or a corrupt timestamp); zero for no remaining unit.
    pub fn estimate(unit_durations_s: &[f64], remaining_units: usize) -> Option<Self> {
        if unit_durations_s.iter().any(|d| *d < 0.0) {
            return None;
        }
        let median = quantile(&mut unit_durations_s.to_vec(), 0.5)?;
        // A gap of many unit times is a stop and a resume (or a night's pause), not how long a unit takes.
        let mut durations: Vec<f64> =
            unit_durations_s.iter().copied().filter(|d| *d <= DOWNTIME_FACTOR * median).collect();
        let p90 = quantile(&mut durations, 0.9)?;
        let n = remaining_units as f64;
        Some(Self { median_s: n * median, p90_s: n * p90 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_p90_scale_with_the_units_left() {
        // Ten units: nine of 100 s and one retried of 300 s.
        let mut durations = vec![100.0; 9];
        durations.push(300.0);
        let r = RemainingTime::estimate(&durations, 50).unwrap();
        assert_eq!(r.median_s, 5000.0);
        // Rank round(0.9 x 9) = 8 of the sorted ten is still 100 s; with two slow units it is 300 s.
        assert_eq!(r.p90_s, 5000.0);
        durations[0] = 300.0;
        assert_eq!(RemainingTime::estimate(&durations, 50).unwrap().p90_s, 15_000.0);
        assert_eq!(RemainingTime::estimate(&durations, 0).unwrap(), RemainingTime { median_s: 0.0, p90_s: 0.0 });
    }

    #[test]
    fn a_stop_and_resume_is_not_a_unit_time() {
        // Nine units of 10 s and a night's stop of 10 h between two of them.
        let mut durations = vec![10.0; 9];
        durations.push(36_000.0);
        assert_eq!(RemainingTime::estimate(&durations, 10).unwrap(), RemainingTime { median_s: 100.0, p90_s: 100.0 });
    }

    #[test]
    fn no_estimate_without_a_valid_duration() {
        assert_eq!(RemainingTime::estimate(&[], 10), None);
        assert_eq!(RemainingTime::estimate(&[10.0, -1.0], 10), None);
        assert_eq!(RemainingTime::estimate(&[10.0, f64::NAN], 10), None);
        assert_eq!(RemainingTime::estimate(&[f64::INFINITY], 10), None);
    }
}

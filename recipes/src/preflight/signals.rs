//! Small signal helpers of the pre-flight checks: their test sweeps, peaks, energies and energy ratios.

use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use serde_json::Value;

/// Recording beyond the last signal, s (latency and ring-down).
pub(super) const TAIL_S: f64 = 0.3;
/// SNRs are reported up to this, dB (a noiseless simulated input would otherwise give infinity).
pub(super) const SNR_CAP_DB: f64 = 200.0;

/// A linear test sweep with 5 ms fades.
pub(super) fn sweep(f1_hz: f64, f2_hz: f64, duration_s: f64, amplitude: f64, sample_rate_hz: f64) -> SweepSpec {
    SweepSpec {
        kind: SweepKind::Linear,
        f1_hz,
        f2_hz,
        duration_s,
        sample_rate_hz,
        amplitude,
        fade_in_s: 0.005,
        fade_out_s: 0.005,
    }
}

/// Peak |x|.
pub(super) fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Mean square of `x` (0 when empty).
pub(super) fn mean_square(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64 }
}

/// `10 log10(a / b)` for energies, capped at [`SNR_CAP_DB`] (and at its negative) so it stays finite.
pub(super) fn db_ratio(a: f64, b: f64) -> f64 {
    if b <= 0.0 {
        return if a > 0.0 { SNR_CAP_DB } else { 0.0 };
    }
    if a <= 0.0 {
        return -SNR_CAP_DB;
    }
    (10.0 * (a / b).log10()).clamp(-SNR_CAP_DB, SNR_CAP_DB)
}

/// `a` with `b`'s keys added (both objects).
pub(super) fn merge(mut a: Value, b: Value) -> Value {
    if let (Some(a), Value::Object(b)) = (a.as_object_mut(), b) {
        a.extend(b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_ratios_stay_finite_at_the_extremes() {
        assert_eq!(db_ratio(1.0, 0.0), SNR_CAP_DB);
        assert_eq!(db_ratio(0.0, 0.0), 0.0);
        assert_eq!(db_ratio(0.0, 1.0), -SNR_CAP_DB);
        assert!((db_ratio(100.0, 1.0) - 20.0).abs() < 1e-12);
        assert_eq!(db_ratio(f64::MAX, f64::MIN_POSITIVE), SNR_CAP_DB);
    }
}

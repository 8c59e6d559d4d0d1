use metaplate_dsp::sweep::*;
use std::f64::consts::PI;

fn spec(kind: SweepKind) -> SweepSpec {
    SweepSpec { kind, fade_in_s: 0.0, fade_out_s: 0.0, ..SweepSpec::default() }
}

#[test]
fn paper_default() {
    let s = SweepSpec::default();
    assert_eq!(s.kind, SweepKind::Linear);
    assert_eq!(s.len_samples(), 72_000);
    let x = s.generate().unwrap();
    assert_eq!(x.len(), 72_000);
    assert!(x.iter().all(|v| v.abs() <= 1.0));
    assert_eq!(x[0], 0.0);
    assert_eq!(x[71_999], 0.0);
}

#[test]
fn instantaneous_frequency_is_phase_derivative() {
    for kind in [SweepKind::Linear, SweepKind::Exponential] {
        let s = spec(kind);
        for t in [0.0, 0.7, 1.5, 2.999] {
            let dt = 1e-6;
            let numeric = (s.phase_rad(t + dt) - s.phase_rad(t - dt)) / (2.0 * dt) / (2.0 * PI);
            let analytic = s.instantaneous_freq_hz(t);
            assert!((numeric - analytic).abs() < 1e-3, "{kind:?} t={t}: {numeric} vs {analytic}");
        }
        assert!((s.instantaneous_freq_hz(0.0) - 62.0).abs() < 1e-9);
        assert!((s.instantaneous_freq_hz(3.0) - 625.0).abs() < 1e-9);
    }
}

#[test]
fn exponential_harmonic_advance() {
    let s = spec(SweepKind::Exponential);
    let l = 3.0 / (625.0f64 / 62.0).ln();
    assert!((s.exp_rate_s().unwrap() - l).abs() < 1e-12);
    assert!((s.harmonic_advance_s(2).unwrap() - l * 2f64.ln()).abs() < 1e-12);
    assert_eq!(s.harmonic_advance_s(1), Some(0.0));
    assert_eq!(spec(SweepKind::Linear).harmonic_advance_s(2), None);
}

#[test]
fn fades_shape_the_ends() {
    let s = SweepSpec { fade_in_s: 0.01, fade_out_s: 0.01, ..spec(SweepKind::Linear) };
    let x = s.generate().unwrap();
    assert_eq!(x[0], 0.0);
    assert_eq!(*x.last().unwrap(), 0.0);
    // Past the fade the sweep is untouched.
    let plain = spec(SweepKind::Linear).generate().unwrap();
    assert_eq!(x[1000], plain[1000]);
}

#[test]
fn any_sample_rate_and_edges_at_zero_and_nyquist() {
    let s =
        SweepSpec { f1_hz: 0.0, f2_hz: 4000.0, sample_rate_hz: 8000.0, duration_s: 0.01, ..spec(SweepKind::Linear) };
    assert_eq!(s.generate().unwrap().len(), 80);
    let s = SweepSpec { f1_hz: 1.0, f2_hz: 22_050.0, sample_rate_hz: 44_100.0, ..spec(SweepKind::Exponential) };
    assert!(s.generate().is_ok());
}

#[test]
fn refuses_invalid_specs() {
    let base = spec(SweepKind::Exponential);
    for bad in [
        SweepSpec { f1_hz: 0.0, ..base },
        SweepSpec { f2_hz: 12_001.0, ..base },
        SweepSpec { f2_hz: 50.0, ..base },
        SweepSpec { duration_s: 0.0, ..base },
        SweepSpec { duration_s: f64::NAN, ..base },
        SweepSpec { sample_rate_hz: -1.0, ..base },
        SweepSpec { amplitude: f64::INFINITY, ..base },
        SweepSpec { fade_in_s: 2.0, fade_out_s: 2.0, ..base },
        SweepSpec { duration_s: 1e9, ..base },
        SweepSpec { duration_s: 1e-6, ..base },
    ] {
        assert!(bad.generate().is_err(), "{bad:?}");
    }
}

//! The galvo aimer over the mock lab's mirrors: aims through the fit, refuses what the outputs cannot reach before
//! anything moves, waits the settling time, writes the last voltages again after a reconnect.

use std::sync::Arc;

use metaplate_aim::galvo::{FitModel, GalvoAimer, GalvoFit, GalvoSettings, TaughtPoint};
use metaplate_core::aim::{Aim, AimError};
use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_lab::mirrors::{MirrorGeometry, MockMirrors};

/// A fit taught exactly (the true voltages of a 3 x 3 grid of marks, found by inverting the geometry).
fn exact_fit(geometry: &MirrorGeometry) -> GalvoFit {
    let marks = [-0.1, 0.0, 0.1].iter().flat_map(|&x| [-0.05, 0.0, 0.05].map(move |y| (x, y)));
    let points: Vec<TaughtPoint> = marks
        .map(|(x_m, y_m)| {
            let (x_v, y_v) = invert(geometry, (x_m, y_m));
            TaughtPoint { x_m, y_m, x_v, y_v }
        })
        .collect();
    GalvoFit::fit(FitModel::Projective, &points).expect("fits")
}

/// The voltages that land on `target`, by fixed-point iteration on the geometry (it is near linear).
fn invert(g: &MirrorGeometry, target: (f64, f64)) -> (f64, f64) {
    let mut v = (0.0, 0.0);
    for _ in 0..200 {
        let (lx, ly) = g.landing_m(v.0, v.1);
        let (ex, ey) = (target.0 - lx, target.1 - ly);
        let (sin, cos) = (-g.rotation_rad).sin_cos();
        v = (v.0 + (cos * ex - sin * ey) / g.scale_m_per_v, v.1 + (sin * ex + cos * ey) / (g.scale_m_per_v * g.aspect));
    }
    v
}

fn aimer(settle_s: f64) -> (GalvoAimer, MockMirrors, Arc<VirtualClock>) {
    let geometry = MirrorGeometry::seeded(7);
    let mirrors = MockMirrors::new(geometry);
    let clock = Arc::new(VirtualClock::new());
    let aimer =
        GalvoAimer::new(exact_fit(&geometry), Box::new(mirrors.clone()), clock.clone(), GalvoSettings { settle_s })
            .expect("valid settings");
    (aimer, mirrors, clock)
}

#[test]
fn a_point_beyond_the_outputs_is_refused_before_anything_moves() {
    let (mut aimer, mirrors, clock) = aimer(0.002);
    // ~20 mm per volt: 0.3 m from the centre needs ~15 V, beyond +/- 10 V.
    for (x_m, y_m) in [(0.3, 0.0), (0.0, -0.3), (0.25, 0.25)] {
        let err = aimer.check_reachable(x_m, y_m).unwrap_err();
        assert!(matches!(&err, AimError::Unreachable { detail, .. } if detail.contains("10 V")), "{err}");
        assert!(matches!(aimer.aim_at(x_m, y_m), Err(AimError::Unreachable { .. })));
    }
    assert!(matches!(aimer.check_reachable(f64::NAN, 0.0), Err(AimError::InvalidArgument { .. })));
    assert_eq!(mirrors.volts(), None, "nothing was written");
    assert_eq!(clock.now_s(), 0.0, "nothing waited");
    // The rig record names the fit and the outputs.
    let described = aimer.describe();
    assert!(described.starts_with("galvo mirrors (projective fit of 9 points, residual rms "), "{described}");
    assert!(described.ends_with(" mm) on the mock lab's galvo mirrors (+/- 10 V)"), "{described}");
    // The plate's corners are within reach.
    aimer.check_reachable(0.12, -0.06).expect("reachable");
}

#[test]
fn each_move_writes_the_volts_then_waits_the_settling_time() {
    let settle_s = 0.0035;
    let (mut aimer, mirrors, clock) = aimer(settle_s);
    aimer.aim_at(0.05, 0.02).expect("aims");
    assert_eq!(clock.now_s(), settle_s);
    aimer.aim_at(-0.05, 0.02).expect("aims");
    assert!((clock.now_s() - 2.0 * settle_s).abs() < 1e-15, "{}", clock.now_s());
    let (x, y) = mirrors.beam_m().expect("aimed");
    // An exact 3 x 3 teaching leaves the pincushion's few tenths of a mm minus what the projective map absorbs.
    assert!((x + 0.05).hypot(y - 0.02) < 0.1e-3, "landed at ({x}, {y})");
    assert!(
        GalvoAimer::new(
            exact_fit(&MirrorGeometry::seeded(7)),
            Box::new(mirrors),
            clock,
            GalvoSettings { settle_s: -1.0 }
        )
        .is_err()
    );
}

#[test]
fn reconnect_writes_the_last_volts_again() {
    let (mut aimer, mirrors, clock) = aimer(0.002);
    aimer.aim_at(0.03, -0.01).expect("aims");
    let held = mirrors.volts();
    mirrors.disconnect();
    let err = aimer.aim_at(0.04, -0.01).unwrap_err();
    assert!(err.suggests_reconnect(), "{err}");
    let before = clock.now_s();
    aimer.reconnect().expect("reopens");
    assert_eq!(mirrors.volts(), held, "the last successful voltages, written again");
    assert_eq!(clock.now_s() - before, 0.002, "and settled");
    aimer.aim_at(0.04, -0.01).expect("aims again");
}

//! Every imperfection switched off in the scene is gone from what the lab records (`Scene::without`).
#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_core::rig::Rig;
use metaplate_core::scene::{Imperfection, Scene};
use metaplate_lab::MockLab;
use metaplate_lab::session::{Recording, configure, play_and_record};
use metaplate_plate::actuator::VoiceCoil;

/// Velocity range `range_m_s`, beam on the test point.
fn ready(lab: &MockLab, rig: &mut Rig, range_m_s: f64) {
    let (x, y) = lab.scene().grid.position_m(common::point(lab.scene()));
    configure(rig, 2400).unwrap();
    rig.vibrometer.set_velocity_range(range_m_s).unwrap();
    rig.aim.aim_at(x, y).unwrap();
}

/// The same 0.5 s sweep recorded twice at the test point on one rig (the second a new measurement: new noise).
fn twice(scene: &Scene, range_m_s: f64) -> (Recording, Recording) {
    let lab = common::lab(scene, None);
    let mut rig = lab.rig().unwrap();
    ready(&lab, &mut rig, range_m_s);
    let sweep = common::sweep(0.5);
    let a = play_and_record(&mut rig, 2, &sweep, &sweep, 18_000).unwrap();
    let b = play_and_record(&mut rig, 2, &sweep, &sweep, 18_000).unwrap();
    (a, b)
}

fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |a, b| a.max(b.abs()))
}

#[test]
fn noise_off_makes_repetitions_identical() {
    let scene = common::scene(vec![], true);
    let (a, b) = twice(&scene, 0.02);
    assert_ne!(a.velocity_v, b.velocity_v, "with noise, two measurements differ");
    let (a, b) = twice(&scene.without(&[Imperfection::LdvNoise]), 0.02);
    assert_eq!(a.velocity_v, b.velocity_v, "without noise, they are the same bits");
}

#[test]
fn quantisation_off_leaves_the_16_bit_grid() {
    // 16-bit codes on +/-10 V: every recorded voltage is a whole number of 10 / 32768 V steps.
    let step_v = 10.0 / 32768.0;
    let on_grid = |x: &[f64]| x.iter().all(|v| (v / step_v - (v / step_v).round()).abs() < 1e-9);
    let scene = common::scene(vec![], true).without(&[Imperfection::LdvNoise]);
    let (quantised, _) = twice(&scene, 0.02);
    assert!(on_grid(&quantised.velocity_v) && on_grid(&quantised.loopback_v));
    let (ideal, _) = twice(&scene.without(&[Imperfection::Quantisation]), 0.02);
    assert!(!on_grid(&ideal.velocity_v) && !on_grid(&ideal.loopback_v));
    // The same signal otherwise: within half a step everywhere.
    let worst = quantised.velocity_v.iter().zip(&ideal.velocity_v).map(|(q, i)| (q - i).abs()).fold(0.0, f64::max);
    assert!(worst <= step_v / 2.0 + 1e-12, "{worst} V");
    // Another resolution is honoured (coarser steps).
    let mut coarse = scene.clone();
    coarse.daq.bits = 8;
    let (c, _) = twice(&coarse, 0.02);
    let step8 = 10.0 / 128.0;
    assert!(c.velocity_v.iter().all(|v| (v / step8 - (v / step8).round()).abs() < 1e-9));
}

#[test]
fn clipping_off_lets_the_signal_past_the_range() {
    // A range far below the plate's velocity: the vibrometer's output sits on its rails.
    let scene = common::scene(vec![], true).without(&[Imperfection::LdvNoise]);
    let (clipped, _) = twice(&scene, 0.0001);
    let full_v = peak(&clipped.velocity_v);
    assert!(full_v <= 10.0 && clipped.velocity_v.iter().filter(|v| v.abs() >= full_v).count() > 10);
    let (free, _) = twice(&scene.without(&[Imperfection::Clipping]), 0.0001);
    assert!(peak(&free.velocity_v) > 2.0 * full_v, "{} V against {full_v} V", peak(&free.velocity_v));
}

#[test]
fn clock_drift_and_latency_off_align_the_loopback_with_the_drive() {
    let scene = common::scene(vec![], true).without(&[Imperfection::ClockDrift, Imperfection::Latency]);
    let lab = common::lab(&scene, None);
    let c = lab.constants();
    assert_eq!((c.drift_ppm, c.audio_latency_s), (0.0, 0.0));
    assert_eq!((c.audio_rate_true_hz, c.daq_rate_true_hz), (48_000.0, 24_000.0));
    // A pulse at frame 4800 (0.1 s) shows at DAQ sample 2400 exactly.
    let mut rig = lab.rig().unwrap();
    ready(&lab, &mut rig, 0.02);
    let mut loopback = vec![0.0; 9_600];
    let width = 192;
    for i in 0..=width {
        loopback[4_800 - width / 2 + i] = 0.5 * (1.0 - (std::f64::consts::TAU * i as f64 / width as f64).cos());
    }
    let silent = vec![0.0; loopback.len()];
    let rec = play_and_record(&mut rig, 0, &silent, &loopback, 4_800).unwrap();
    let i = rec.loopback_v.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
    assert_eq!(i, 2_400);
    let (l, r) = (rec.loopback_v[i - 1], rec.loopback_v[i + 1]);
    assert!((l - r).abs() < 1e-3 * rec.loopback_v[i], "symmetric about sample 2400: {l} {r}");
}

#[test]
fn nonlinearity_and_spread_off_make_every_coil_the_nominal_linear_one() {
    let scene = Scene::builtin("metamaterial").unwrap();
    let coils = VoiceCoil::for_scene(&scene, 48_000.0).unwrap();
    assert!(coils.iter().all(|c| c.nonlinearity != 0.0 && c.spread_db != 0.0));
    let ideal = scene.without(&[Imperfection::Nonlinearity, Imperfection::ActuatorSpread]);
    let coils = VoiceCoil::for_scene(&ideal, 48_000.0).unwrap();
    let nominal = ideal.actuators[0].voice_coil.force_factor_n_per_v;
    assert!(coils.iter().all(|c| c.nonlinearity == 0.0 && c.spread_db == 0.0 && c.gain_n == nominal));
    // Linear: twice the drive, twice the force, to rounding.
    let drive: Vec<f64> = (0..480).map(|k| 0.9 * (k as f64 * 0.05).sin()).collect();
    let double: Vec<f64> = drive.iter().map(|u| 2.0 * u).collect();
    let (f1, f2) = (coils[0].drive_to_force(&drive).unwrap(), coils[0].drive_to_force(&double).unwrap());
    assert!(f1.iter().zip(&f2).all(|(a, b)| (2.0 * a - b).abs() <= 1e-12 * b.abs().max(1e-9)));
}

#[test]
fn dropouts_and_speckle_off() {
    let mut scene = common::scene(vec![], true);
    scene.ldv.dropout_probability = 1.0;
    let (a, _) = twice(&scene.without(&[Imperfection::LdvNoise]), 0.02);
    let (b, _) = twice(&scene.without(&[Imperfection::LdvNoise, Imperfection::Dropouts]), 0.02);
    assert_ne!(a.velocity_v, b.velocity_v, "a dropout garbles the recording");
    let lab = common::lab(&scene.without(&[Imperfection::Dropouts]), None);
    lab.rig().unwrap();
    assert_eq!(lab.stats().unwrap().random_dropouts, 0);
    // Speckle off: every spot returns full light (the noise is the floor's own, unscaled).
    let s = scene.without(&[Imperfection::Speckle]);
    assert_eq!((s.ldv.speckle_mean_level, s.ldv.speckle_spread), (1.0, 0.0));
    let model = metaplate_mock_ldv::SpeckleModel::new(&s.ldv, s.seed);
    assert!((-5..5).all(|k| model.level_percent(k * 5_000, k * 3_000) == 100));
}

#[test]
fn an_aiming_error_moves_the_spot_a_little_the_same_at_every_playback() {
    let exact = common::scene(vec![], true).without(&[Imperfection::LdvNoise]);
    let mut aimed = exact.clone();
    aimed.ldv.aim_error_rms_m = 0.0005;
    // The aimed lab prepares the test point's grid neighbours as well, for the response's slope.
    let point = common::point(&exact);
    let neighbours = {
        let (ix, iy) = exact.grid.indices(point);
        vec![
            point,
            exact.grid.index(ix - 1, iy),
            exact.grid.index(ix + 1, iy),
            exact.grid.index(ix, iy - 1),
            exact.grid.index(ix, iy + 1),
        ]
    };
    let record = |scene: &Scene| {
        let lab = common::lab_with_points(scene, None, neighbours.clone());
        let mut rig = lab.rig().unwrap();
        ready(&lab, &mut rig, 0.02);
        let sweep = common::sweep(0.5);
        let a = play_and_record(&mut rig, 2, &sweep, &sweep, 18_000).unwrap();
        let b = play_and_record(&mut rig, 2, &sweep, &sweep, 18_000).unwrap();
        (a, b)
    };
    let (e, _) = record(&exact);
    let (a, b) = record(&aimed);
    assert_eq!(a.velocity_v, b.velocity_v, "one offset per point, the same at every playback");
    let diff: f64 = a.velocity_v.iter().zip(&e.velocity_v).map(|(x, y)| (x - y).powi(2)).sum();
    let energy: f64 = e.velocity_v.iter().map(|x| x * x).sum();
    let rel_db = 10.0 * (diff / energy).log10();
    // 0.5 mm against wavelengths of 5 to 10 cm on this plate: a change of a few percent, no more.
    assert!((-60.0..-10.0).contains(&rel_db), "{rel_db} dB");
    // Switched off, the recording is the exact one again.
    let (off, _) = record(&aimed.without(&[Imperfection::AimError]));
    assert_eq!(off.velocity_v, e.velocity_v);
}

//! The signal chain through the real drivers: response, clocks, determinism, virtual time.
#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use std::time::Instant;

use metaplate_core::rig::Rig;
use metaplate_dsp::fft;
use metaplate_lab::MockLab;
use metaplate_lab::session::{Recording, configure, play_and_record};

/// A velocity range for about 20 mm/s, beam on the test point; returns the range's m/s per V.
fn ready(lab: &MockLab, rig: &mut Rig) -> f64 {
    let (x, y) = lab.scene().grid.position_m(common::point(lab.scene()));
    ready_at(rig, (x, y), 0.02)
}

/// As [`ready`], with the beam at `(x, y)`, m, and a velocity range of `range_m_s`.
fn ready_at(rig: &mut Rig, (x, y): (f64, f64), range_m_s: f64) -> f64 {
    configure(rig, 2400).unwrap();
    let scale = rig.vibrometer.set_velocity_range(range_m_s).unwrap();
    rig.aim.aim_at(x, y).unwrap();
    scale.m_s_per_v
}

fn sweep_recording(lab: &MockLab) -> (Recording, f64) {
    let (x, y) = lab.scene().grid.position_m(common::point(lab.scene()));
    sweep_recording_at(lab, (x, y), 0.02)
}

fn sweep_recording_at(lab: &MockLab, beam_m: (f64, f64), range_m_s: f64) -> (Recording, f64) {
    let mut rig = lab.rig().unwrap();
    let m_s_per_v = ready_at(&mut rig, beam_m, range_m_s);
    let sweep = common::sweep(1.0);
    (play_and_record(&mut rig, 2, &sweep, &sweep, 36_000).unwrap(), m_s_per_v)
}

#[test]
fn a_deconvolved_sweep_matches_the_true_response() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let (rec, m_s_per_v) = sweep_recording(&lab);
    let worst_db = worst_error_db(&lab, common::point(&scene), &rec, m_s_per_v);
    // Noise 1 um/s rms at full signal level (scene), scaled by 1 / level (level about 0.8): its in-band share per
    // bin against a response of ~1e-3 m/s per FS driven at 0.5 FS is below -60 dB, and 16-bit quantisation of a
    // +/-10 V range at 2 mm/s/V is below -70 dB at 30 dB under the peak; 0.2 dB (2.3 %) leaves room for the
    // interpolators' 2e-4 and the 30 dB excursion.
    assert!(worst_db < 0.2, "worst {worst_db} dB");
}

#[test]
fn a_the_beam_on_a_magnet_sees_the_driving_point() {
    // Calibration aims the beam at actuator 2's own position (not a grid point): the lab serves the plate's
    // driving-point response there (point index grid.len() + 2), under the same tolerance as on the grid.
    let scene = common::scene(vec![], true);
    let driving_point = scene.grid.len() + 2;
    let lab = common::lab_with_points(&scene, None, vec![driving_point]);
    let magnet = (scene.actuators[2].x_m, scene.actuators[2].y_m);
    // The magnet moves far more than the plate elsewhere: the widest velocity range keeps the DAQ from clipping.
    let (rec, m_s_per_v) = sweep_recording_at(&lab, magnet, 0.1);
    let peak_v = rec.velocity_v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(peak_v < 9.9, "the velocity clipped the DAQ: {peak_v} V");
    assert_eq!(lab.stats().unwrap().beam_off_prepared_points, 0);
    let worst_db = worst_error_db(&lab, driving_point, &rec, m_s_per_v);
    assert!(worst_db < 0.2, "worst {worst_db} dB");
}

/// Worst in-band magnitude error of velocity over loopback against the lab's truth at `point` for actuator 2, dB.
fn worst_error_db(lab: &MockLab, point: usize, rec: &Recording, m_s_per_v: f64) -> f64 {
    assert!(!rec.gap && rec.underruns == 0);
    println!(
        "max |v| {:.3} V, max |l| {:.3} V",
        rec.velocity_v.iter().fold(0.0f64, |a, b| a.max(b.abs())),
        rec.loopback_v.iter().fold(0.0f64, |a, b| a.max(b.abs()))
    );
    // Whole-recording spectral division: the sweep and its ring-down fit in the recording, so velocity over
    // loopback is the response (m/s per loopback volt); the DAQ-vs-audio clock offset acts on both channels alike.
    let n = fft::fast_len(2 * rec.velocity_v.len()).unwrap();
    let velocity: Vec<f64> = rec.velocity_v.iter().map(|v| v * m_s_per_v).collect();
    let v = fft::forward(&velocity, n).unwrap();
    let l = fft::forward(&rec.loopback_v, n).unwrap();
    let lv = lab.constants().loopback_volts_per_full_scale;
    let fs = lab.constants().daq_rate_true_hz;
    let bins: Vec<usize> = (0..v.len()).filter(|&k| (150.0..=520.0).contains(&(k as f64 * fs / n as f64))).collect();
    let freqs: Vec<f64> = bins.iter().map(|&k| k as f64 * fs / n as f64).collect();
    let truth = lab.true_response(point, 2, &freqs).unwrap();
    let peak = truth.iter().map(|t| t.norm()).fold(0.0, f64::max);
    let mut worst_db: f64 = 0.0;
    for ((&k, t), f) in bins.iter().zip(&truth).zip(&freqs) {
        // Anti-resonances more than 30 dB below the peak drown in noise and quantisation; skip them.
        if t.norm() < peak * 10f64.powf(-30.0 / 20.0) {
            continue;
        }
        let measured = v[k] / l[k] * lv;
        let err_db = 20.0 * (measured.norm() / t.norm()).log10();
        assert!(err_db.is_finite(), "{f} Hz");
        worst_db = worst_db.max(err_db.abs());
    }
    println!("worst in-band magnitude error {worst_db:.4} dB");
    worst_db
}

/// Sub-sample position of the largest sample (parabolic fit through it and its neighbours).
fn peak_position(x: &[f64]) -> f64 {
    let i = x.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
    let (a, b, c) = (x[i - 1], x[i], x[i + 1]);
    i as f64 + 0.5 * (a - c) / (a - 2.0 * b + c)
}

#[test]
fn b_the_loopback_shows_latency_and_clock_offset() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let mut rig = lab.rig().unwrap();
    ready(&lab, &mut rig);
    // Two 4 ms Hann pulses 3 s apart (frames at 48 kHz): smooth peaks, located to about 0.01 sample.
    let width = 192;
    let (k1, k2) = (4_800usize, 4_800 + 144_000);
    let mut loopback = vec![0.0; k2 + 2 * width];
    for k0 in [k1, k2] {
        for i in 0..=width {
            loopback[k0 + i] = 0.5 * (1.0 - (2.0 * std::f64::consts::PI * i as f64 / width as f64).cos());
        }
    }
    let silent = vec![0.0; loopback.len()];
    let rec = play_and_record(&mut rig, 0, &silent, &loopback, 76_800).unwrap();
    let half = rec.loopback_v.len() / 2;
    let p1 = peak_position(&rec.loopback_v[..half]);
    let p2 = half as f64 + peak_position(&rec.loopback_v[half..]);
    let c = lab.constants();
    let drift_ppm = ((p2 - p1) / (k2 - k1) as f64 * 2.0 - 1.0) * 1e6;
    // The pulse centre is frame k1 + width / 2; the DAQ and the playback started at the same virtual time.
    let latency_s = p1 / c.daq_rate_true_hz - (k1 + width / 2) as f64 / c.audio_rate_true_hz;
    println!("drift {drift_ppm:.3} ppm (scene {:.3}), latency {:.6} s", c.drift_ppm, latency_s);
    // 20 - (-30) ppm from the scene, as the lab computes it exactly; 0.5 ppm is 0.036 samples over 72 000, a few
    // times the peak fit's accuracy.
    assert!((c.drift_ppm - 50.0).abs() < 0.01);
    assert!((drift_ppm - c.drift_ppm).abs() < 0.5, "{drift_ppm} ppm");
    // 1 us is 0.024 DAQ samples.
    assert!((latency_s - scene.audio.latency_s).abs() < 1e-6, "{latency_s} s");
}

#[test]
fn d_the_same_seed_gives_bit_identical_recordings() {
    let scene = common::scene(vec![], false);
    let (a, _) = sweep_recording(&common::lab(&scene, Some(11)));
    let (b, _) = sweep_recording(&common::lab(&scene, Some(11)));
    assert_eq!(a, b);
    let (c, _) = sweep_recording(&common::lab(&scene, Some(12)));
    assert_ne!(a.velocity_v, c.velocity_v, "another seed, other noise");
    assert_eq!(a.loopback_v, c.loopback_v, "the loopback carries no noise");
}

#[test]
fn e_a_3_s_playback_takes_3_s_of_virtual_time_only() {
    let scene = common::scene(vec![], false);
    let lab = common::lab(&scene, None);
    let mut rig = lab.rig().unwrap();
    ready(&lab, &mut rig);
    let sweep = common::sweep(3.0);
    let t0 = rig.clock.now_s();
    let wall = Instant::now();
    let frames = sweep.len();
    let rec = play_and_record(&mut rig, 1, &sweep, &sweep, 72_000).unwrap();
    let elapsed_s = rig.clock.now_s() - t0;
    let wall_s = wall.elapsed().as_secs_f64();
    println!("virtual {elapsed_s:.4} s, wall {wall_s:.3} s");
    assert_eq!(rec.velocity_v.len(), 72_000);
    // The playback ends at latency + frames / true rate; 72 000 DAQ samples end at 3 s / (1 + 20 ppm): the later
    // of the two, plus the DAQ's stop exchange, which takes no virtual time.
    let end_s = scene.audio.latency_s + frames as f64 / lab.constants().audio_rate_true_hz;
    assert!((elapsed_s - end_s).abs() < 1e-9, "{elapsed_s} s vs {end_s} s");
    // A debug build on a loaded 2-core machine: far below the 3 s a real playback takes.
    assert!(wall_s < 2.0, "{wall_s} s of wall time");
}

#[test]
fn the_true_velocity_of_a_drive_is_its_convolution_with_the_true_response() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let point = common::point(&scene);
    let fs = scene.daq.sample_rate_hz;
    // An impulse on actuator 2: the velocity is actuator 2's true response, whose spectrum `true_response` gives
    // by another route (a direct DTFT of the impulse response, the coil's gain multiplied in). The velocity is cut
    // after the plate's impulse-response length, where the coil (an IIR filter) still rings a little: 1e-4
    // (-80 dB) of the response.
    let mut impulse = vec![0.0; 64];
    impulse[0] = 1.0;
    let v = lab.true_velocity(point, &[2], &[impulse.clone()], fs).unwrap();
    let freqs = [100.0, 250.0, 400.0];
    let truth = lab.true_response(point, 2, &freqs).unwrap();
    for (f, t) in freqs.iter().zip(&truth) {
        let dtft: num_complex::Complex64 = v
            .iter()
            .enumerate()
            .map(|(n, &x)| x * num_complex::Complex64::from_polar(1.0, -2.0 * std::f64::consts::PI * f * n as f64 / fs))
            .sum();
        assert!((dtft - t).norm() < 1e-4 * t.norm(), "{f} Hz: {dtft} against {t}");
    }
    // Linear: two actuators' drives give the sum of each alone.
    let burst: Vec<f64> = (0..64).map(|n| (n as f64 * 0.3).sin() * 0.5).collect();
    let both = lab.true_velocity(point, &[2, 5], &[impulse.clone(), burst.clone()], fs).unwrap();
    let alone = lab.true_velocity(point, &[5], &[burst], fs).unwrap();
    let worst = both.iter().zip(v.iter().zip(&alone)).map(|(b, (a, c))| (b - a - c).abs()).fold(0.0, f64::max);
    let peak = both.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(worst < 1e-12 * peak, "{worst} against {peak}");
    // Refused by name: another rate, an unprepared point, mismatched drives, a NaN.
    for (point, actuators, drives, rate, needle) in [
        (point, vec![2], vec![impulse.clone()], fs / 2.0, "Green's functions are at"),
        (scene.grid.len() - 1, vec![2], vec![impulse.clone()], fs, "grid point"),
        (point, vec![2, 5], vec![impulse.clone()], fs, "2 actuators"),
        (point, vec![2], vec![vec![f64::NAN]], fs, "non-finite"),
    ] {
        let err = lab.true_velocity(point, &actuators, &drives, rate).unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
    }
}

/// The galvo mirrors are hardware: their geometry is the scene's own seed's whatever seed the lab's draws take, so
/// a fit taught on the scene's mirrors (`metaplate aim teach --scene`) steers a lab run with `--seed` as well.
#[test]
fn the_mirrors_are_the_scenes_whatever_seed_the_draws_take() {
    let scene = common::scene(vec![], true);
    let reseeded = common::lab(&scene, Some(scene.seed ^ 0x5eed));
    let taught = metaplate_lab::mirrors::MirrorGeometry::seeded(scene.seed);
    assert_eq!(reseeded.mirrors().geometry(), Some(taught));
    assert_ne!(metaplate_lab::mirrors::MirrorGeometry::seeded(scene.seed ^ 0x5eed), taught, "the seeds draw apart");
}

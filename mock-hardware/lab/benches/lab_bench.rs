//! Wall time per (point, actuator) playback through the real drivers (run in release):
//!
//! `cargo bench -p metaplate-lab --bench lab_bench -- [points]`
//!
//! The paper's protocol per (point, actuator): 5 linear sweeps of 3 s from 62 to 625 Hz back to back (15 s at
//! 48 kHz), one actuator at a time, loopback on its channel, recorded at 24 kHz on 2 DAQ channels through the DAQ
//! protocol (2400-sample blocks), plus 0.5 s for the tail. Green's functions for `points` points (default 4) are
//! cached under `target/lab-cache`.

#![allow(clippy::expect_used, clippy::unwrap_used)] // A benchmark binary: a panic with its message is the report.

use std::time::Instant;

use metaplate_core::clock::Clock;
use metaplate_core::scene::Scene;
use metaplate_dsp::sweep::{SweepKind, SweepSpec};
use metaplate_lab::session::{configure, play_and_record};
use metaplate_lab::{LabOptions, MockLab};

fn main() {
    // `cargo bench` passes `--bench`: not one of ours.
    let n_points: usize = std::env::args().skip(1).find(|a| a != "--bench").and_then(|a| a.parse().ok()).unwrap_or(4);
    let scene = Scene::builtin("metamaterial").expect("scene");
    let measured = scene.measured_points();
    let points: Vec<usize> = (0..n_points).map(|i| measured[i * measured.len() / n_points]).collect();
    let cache = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/lab-cache");
    std::fs::create_dir_all(&cache).expect("cache dir");
    let t = Instant::now();
    let options = LabOptions { points: Some(points.clone()), cache_dir: Some(cache), ..LabOptions::default() };
    let lab = MockLab::new(&scene, &options).expect("lab");
    println!("lab built in {:.2} s ({} points)", t.elapsed().as_secs_f64(), points.len());
    let mut rig = lab.rig().expect("rig");
    configure(&mut rig, 2400).expect("configure");
    rig.vibrometer.set_velocity_range(0.1).expect("range");
    let spec = SweepSpec {
        kind: SweepKind::Linear,
        f1_hz: 62.0,
        f2_hz: 625.0,
        duration_s: 3.0,
        sample_rate_hz: 48_000.0,
        amplitude: 0.5,
        fade_in_s: 0.01,
        fade_out_s: 0.01,
    };
    let sweep = spec.generate().expect("sweep");
    let drive: Vec<f64> = sweep.iter().cycle().take(5 * sweep.len()).copied().collect();
    let record = (15.5 * 24_000.0) as usize;
    let mut times = Vec::new();
    for &p in &points {
        let (x, y) = scene.grid.position_m(p);
        rig.aim.aim_at(x, y).expect("move");
        for actuator in 0..scene.actuators.len() {
            let t = Instant::now();
            let rec = play_and_record(&mut rig, actuator, &drive, &drive, record).expect("playback");
            times.push(t.elapsed().as_secs_f64());
            assert_eq!(rec.velocity_v.len(), record);
        }
    }
    let first = times[0];
    // The first point's playbacks fill the drive cache (one buffer per actuator); later points all hit it.
    let rest = &times[scene.actuators.len().min(times.len() - 1)..];
    let mean = rest.iter().sum::<f64>() / rest.len().max(1) as f64;
    let max = rest.iter().copied().fold(0.0, f64::max);
    println!(
        "{} playbacks of 15 s: first {:.1} ms (drive cache miss); after the first point mean {:.1} ms, max {:.1} ms per (point, actuator)",
        times.len(),
        first * 1e3,
        mean * 1e3,
        max * 1e3
    );
    println!("virtual time {:.1} s; stats {:?}", lab.clock().now_s(), lab.stats().expect("stats"));
    println!(
        "full protocol estimate (1225 points x 8 actuators): {:.1} min of lab+driver time",
        1225.0 * 8.0 * mean / 60.0
    );
}

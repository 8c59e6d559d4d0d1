//! Benchmarks of the per-point processing.
//!
//! `point_deconvolution`: one grid point, 8 actuators, each a 5 x 3 s paper sweep at 24 kHz recorded as velocity and
//! loopback (with 30 ppm drift, a latency and noise), through `PreparedLayout::process_channel` with the layout
//! prepared once (as a scan does, for every point). Target: 50 ms on one core, under 1 % of the 120 s the
//! acquisition of a point takes. Single-threaded: the channels are processed one after the other on one thread.
//!
//! `point_deconvolution_unprepared`: the same through `process_channel`, which prepares the layout per channel.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use metaplate_dsp::conv::convolve;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::pipeline::{PreparedLayout, RepetitionLayout, process_channel};
use metaplate_dsp::sweep::SweepSpec;

const ACTUATORS: usize = 8;

/// A synthetic acquisition: the played signal sampled at the recorder's instants by linear interpolation (the sweep
/// is 40 times oversampled, so that is accurate enough for timing), through a decaying resonant response, plus a
/// small deterministic dither standing in for noise.
fn acquisition(layout: &RepetitionLayout, actuator: usize) -> (Vec<f64>, Vec<f64>) {
    let n = layout.excitation.len();
    let played: Vec<f64> = layout.excitation.iter().copied().cycle().take(n * layout.repetitions).collect();
    let latency = 1000.0 + 517.3 * actuator as f64;
    let ratio = 1.0 + 30e-6;
    let len = (latency + played.len() as f64 * ratio) as usize + 12_500;
    let loopback: Vec<f64> = (0..len)
        .map(|m| {
            let t = (m as f64 - latency) / ratio;
            if t < 0.0 || t >= (played.len() - 1) as f64 {
                0.0
            } else {
                let i = t as usize;
                let f = t - i as f64;
                played[i] * (1.0 - f) + played[i + 1] * f
            }
        })
        .collect();
    let f = 150.0 + 40.0 * actuator as f64;
    let ir: Vec<f64> = (0..9600)
        .map(|k| {
            let t = k as f64 / 24_000.0;
            (-t / 0.05).exp() * (2.0 * std::f64::consts::PI * f * t).sin()
        })
        .collect();
    let mut velocity = convolve(&loopback, &ir).unwrap_or_default();
    velocity.truncate(len);
    for (i, v) in velocity.iter_mut().enumerate() {
        *v += 1e-3 * (((i * 7919) % 1000) as f64 / 1000.0 - 0.5);
    }
    (velocity, loopback)
}

fn point_deconvolution(c: &mut Criterion) {
    let Ok(excitation) = SweepSpec::default().generate() else { return };
    let layout = RepetitionLayout { excitation, repetitions: 5 };
    let cfg = DeconvConfig::paper();
    let channels: Vec<(Vec<f64>, Vec<f64>)> = (0..ACTUATORS).map(|a| acquisition(&layout, a)).collect();
    let Ok(prepared) = PreparedLayout::new(&layout, &cfg) else { return };
    for (a, (velocity, loopback)) in channels.iter().enumerate() {
        // A failing channel would time an early return, not the work.
        let result = prepared.process_channel(velocity, loopback);
        assert!(result.is_ok(), "actuator {a}: {result:?}");
    }
    c.bench_function("point_deconvolution", |b| {
        b.iter(|| {
            for (velocity, loopback) in &channels {
                let out = prepared.process_channel(black_box(velocity), black_box(loopback));
                black_box(out.is_ok());
            }
        })
    });
    c.bench_function("point_deconvolution_unprepared", |b| {
        b.iter(|| {
            for (velocity, loopback) in &channels {
                let out = process_channel(black_box(velocity), black_box(loopback), &layout, &cfg);
                black_box(out.is_ok());
            }
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = point_deconvolution
}
criterion_main!(benches);

//! `metaplate sweep`: write an excitation sweep (optionally repeated) as a float WAV for an audio interface.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use metaplate_dsp::sweep::{SweepKind, SweepSpec};

use crate::wav;

/// Sweep shape on the command line.
#[derive(Clone, Copy, ValueEnum)]
pub enum Kind {
    /// Linear in frequency (the paper's protocol).
    Linear,
    /// Exponential in frequency (harmonic distortion separable after deconvolution).
    Exponential,
}

/// Arguments of `metaplate sweep`. Defaults are the paper's excitation: 3 s, 62 to 625 Hz, linear, 24 kHz.
#[derive(Args)]
pub struct SweepArgs {
    /// Sweep shape.
    #[arg(long, value_enum, default_value = "linear")]
    kind: Kind,
    /// Start frequency, Hz.
    #[arg(long, default_value_t = 62.0)]
    f1_hz: f64,
    /// End frequency, Hz.
    #[arg(long, default_value_t = 625.0)]
    f2_hz: f64,
    /// Duration of one sweep, s.
    #[arg(long, default_value_t = 3.0)]
    duration_s: f64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 24_000.0)]
    sample_rate_hz: f64,
    /// Peak amplitude, relative to full scale (0 < a <= 1).
    #[arg(long, default_value_t = 0.5)]
    amplitude: f64,
    /// Half-Hann fade at each end, s.
    #[arg(long, default_value_t = 0.005)]
    fade_s: f64,
    /// Repetitions played back to back.
    #[arg(long, default_value_t = 1)]
    repetitions: usize,
    /// Silence appended after the last repetition, s (room for the impulse response's tail).
    #[arg(long, default_value_t = 0.5)]
    tail_s: f64,
    /// Output WAV file (mono, 32-bit float).
    #[arg(long)]
    out: PathBuf,
}

/// Generates the sweep and writes it.
pub fn run(args: &SweepArgs) -> anyhow::Result<()> {
    if !(args.amplitude > 0.0 && args.amplitude <= 1.0) {
        anyhow::bail!("--amplitude must lie in (0, 1] of full scale, got {}", args.amplitude);
    }
    if !(args.tail_s.is_finite() && args.tail_s >= 0.0) {
        anyhow::bail!("--tail-s must be finite and >= 0, got {}", args.tail_s);
    }
    if args.repetitions == 0 || args.repetitions > 1000 {
        anyhow::bail!("--repetitions must lie in 1..=1000, got {}", args.repetitions);
    }
    let spec = SweepSpec {
        kind: match args.kind {
            Kind::Linear => SweepKind::Linear,
            Kind::Exponential => SweepKind::Exponential,
        },
        f1_hz: args.f1_hz,
        f2_hz: args.f2_hz,
        duration_s: args.duration_s,
        sample_rate_hz: args.sample_rate_hz,
        amplitude: args.amplitude,
        fade_in_s: args.fade_s,
        fade_out_s: args.fade_s,
    };
    let one = spec.generate()?;
    let tail = (args.tail_s * args.sample_rate_hz).round() as usize;
    let mut signal = Vec::with_capacity(one.len() * args.repetitions + tail);
    for _ in 0..args.repetitions {
        signal.extend_from_slice(&one);
    }
    signal.resize(signal.len() + tail, 0.0);
    wav::write_f32(&args.out, args.sample_rate_hz, &[signal])?;
    println!(
        "wrote {} ({} x {} s sweep, {} to {} Hz, {} Hz, {:.3} s in all)",
        args.out.display(),
        args.repetitions,
        args.duration_s,
        args.f1_hz,
        args.f2_hz,
        args.sample_rate_hz,
        (one.len() * args.repetitions + tail) as f64 / args.sample_rate_hz
    );
    Ok(())
}

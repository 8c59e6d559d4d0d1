//! Multichannel 32-bit float WAV files for the command line (hound).
//!
//! Samples are f64 in memory and f32 on disk: the 24-bit-equivalent resolution of f32 (about -150 dB re full scale)
//! is far below any DAC or DAQ noise floor in the lab.

use std::path::Path;

use anyhow::{Context, bail};

/// Writes `channels` (equal lengths) as an interleaved 32-bit float WAV at `sample_rate_hz`.
pub fn write_f32(path: &Path, sample_rate_hz: f64, channels: &[Vec<f64>]) -> anyhow::Result<()> {
    let Some(first) = channels.first() else { bail!("no channels to write to {}", path.display()) };
    if channels.iter().any(|c| c.len() != first.len()) {
        bail!("channels of different lengths cannot be written to one WAV file");
    }
    if sample_rate_hz.fract() != 0.0 || !(1.0..=f64::from(u32::MAX)).contains(&sample_rate_hz) {
        bail!("a WAV file needs a whole sample rate in Hz, got {sample_rate_hz}");
    }
    let spec = hound::WavSpec {
        channels: u16::try_from(channels.len()).context("too many channels for a WAV file")?,
        sample_rate: sample_rate_hz as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    let mut writer = hound::WavWriter::create(path, spec).with_context(|| format!("creating {}", path.display()))?;
    for i in 0..first.len() {
        for channel in channels {
            writer.write_sample(channel[i] as f32)?;
        }
    }
    writer.finalize().with_context(|| format!("finishing {}", path.display()))?;
    Ok(())
}

/// Reads a WAV file (integer or float samples) into one f64 vector per channel, scaled to +/-1 full scale, and its
/// sample rate in Hz.
pub fn read(path: &Path) -> anyhow::Result<(f64, Vec<Vec<f64>>)> {
    let mut reader = hound::WavReader::open(path).with_context(|| format!("opening {}", path.display()))?;
    let spec = reader.spec();
    let n_channels = usize::from(spec.channels);
    if n_channels == 0 {
        bail!("{} has no channels", path.display());
    }
    let interleaved: Vec<f64> = match spec.sample_format {
        hound::SampleFormat::Float => reader.samples::<f32>().map(|s| s.map(f64::from)).collect::<Result<_, _>>()?,
        hound::SampleFormat::Int => {
            let full_scale = f64::from(1u32 << (spec.bits_per_sample.clamp(1, 32) - 1));
            reader.samples::<i32>().map(|s| s.map(|v| f64::from(v) / full_scale)).collect::<Result<_, _>>()?
        }
    };
    let mut channels = vec![Vec::with_capacity(interleaved.len() / n_channels); n_channels];
    for (i, v) in interleaved.into_iter().enumerate() {
        channels[i % n_channels].push(v);
    }
    Ok((f64::from(spec.sample_rate), channels))
}

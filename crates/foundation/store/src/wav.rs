//! WAV export (32-bit float, multichannel, with hound): impulse responses for listening and for audio tools, and
//! drive signals for playback.
//!
//! Samples are f32 on disk: about 24 bits of resolution (-150 dB re full scale), far below any DAC or DAQ noise floor.

use std::path::Path;

use crate::error::StoreError;
use crate::reader::Dataset;

/// Writes `channels` (at least one, all of one length, at least one sample each) as an interleaved 32-bit float WAV
/// file at `sample_rate_hz`, replacing `path` if it exists. Samples may be f32 or f64 (converted to f32).
///
/// Valid range: `sample_rate_hz` a whole number in 1..=4294967295 Hz; every sample finite and within f32's range
/// (|x| <= 3.4e38); at most 65535 channels.
///
/// # Errors
/// [`StoreError::Wav`] for input outside that range (naming the channel and sample) or a failure of the WAV writer;
/// [`StoreError::Io`] / [`StoreError::DiskFull`] if the file cannot be created.
pub fn write_wav_f32<C, S>(path: impl AsRef<Path>, channels: &[C], sample_rate_hz: f64) -> Result<(), StoreError>
where
    C: AsRef<[S]>,
    S: Copy + Into<f64>,
{
    let path = path.as_ref();
    let bad = |reason: String| StoreError::Wav { path: path.to_path_buf(), reason };
    let len = channels.first().map(|c| c.as_ref().len()).ok_or_else(|| bad("no channels to write".into()))?;
    if len == 0 {
        return Err(bad("channels hold no samples".into()));
    }
    if let Some(c) = channels.iter().position(|c| c.as_ref().len() != len) {
        return Err(bad(format!("channel {c} has {} samples, channel 0 has {len}", channels[c].as_ref().len())));
    }
    if !(sample_rate_hz.fract() == 0.0 && (1.0..=f64::from(u32::MAX)).contains(&sample_rate_hz)) {
        return Err(bad(format!(
            "the sample rate must be a whole number of Hz in 1..=4294967295, got {sample_rate_hz}"
        )));
    }
    let spec = hound::WavSpec {
        channels: u16::try_from(channels.len()).map_err(|_| bad(format!("{} channels (max 65535)", channels.len())))?,
        sample_rate: sample_rate_hz as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    // Checked before the file is created, so that bad input leaves nothing behind.
    let mut interleaved = Vec::with_capacity(len * channels.len());
    for i in 0..len {
        for (c, channel) in channels.iter().enumerate() {
            let value: f64 = channel.as_ref()[i].into();
            let sample = value as f32;
            if !sample.is_finite() {
                return Err(bad(format!("channel {c} sample {i} is {value}: not finite as f32")));
            }
            interleaved.push(sample);
        }
    }
    let hound_error = |e: hound::Error| match e {
        hound::Error::IoError(source) => StoreError::from_io("write", path.to_path_buf(), source),
        other => bad(other.to_string()),
    };
    let mut writer = hound::WavWriter::create(path, spec).map_err(hound_error)?;
    for sample in interleaved {
        writer.write_sample(sample).map_err(hound_error)?;
    }
    writer.finalize().map_err(hound_error)
}

/// Reads a WAV file (integer or float samples) into one f64 vector per channel, scaled to +/-1 full scale (an
/// integer sample `v` of `b` bits is `v / 2^(b-1)`), and its sample rate in Hz.
///
/// # Errors
/// [`StoreError::Io`] if the file cannot be opened; [`StoreError::Wav`] if it is not a WAV file hound reads, has no
/// channels, or holds a non-finite float sample.
pub fn read_wav(path: impl AsRef<Path>) -> Result<(f64, Vec<Vec<f64>>), StoreError> {
    let path = path.as_ref();
    let bad = |reason: String| StoreError::Wav { path: path.to_path_buf(), reason };
    let hound_error = |e: hound::Error| match e {
        hound::Error::IoError(source) => StoreError::from_io("read", path.to_path_buf(), source),
        other => bad(other.to_string()),
    };
    let mut reader = hound::WavReader::open(path).map_err(hound_error)?;
    let spec = reader.spec();
    let n_channels = usize::from(spec.channels);
    if n_channels == 0 {
        return Err(bad("no channels".into()));
    }
    let interleaved: Vec<f64> = match spec.sample_format {
        hound::SampleFormat::Float => {
            reader.samples::<f32>().map(|s| s.map(f64::from)).collect::<Result<_, _>>().map_err(hound_error)?
        }
        hound::SampleFormat::Int => {
            let full_scale = f64::from(1u32 << (spec.bits_per_sample.clamp(1, 32) - 1));
            reader
                .samples::<i32>()
                .map(|s| s.map(|v| f64::from(v) / full_scale))
                .collect::<Result<_, _>>()
                .map_err(hound_error)?
        }
    };
    if let Some(i) = interleaved.iter().position(|v| !v.is_finite()) {
        return Err(bad(format!("channel {} sample {} is {}", i % n_channels, i / n_channels, interleaved[i])));
    }
    let mut channels = vec![Vec::with_capacity(interleaved.len() / n_channels); n_channels];
    for (i, v) in interleaved.into_iter().enumerate() {
        channels[i % n_channels].push(v);
    }
    Ok((f64::from(spec.sample_rate), channels))
}

/// Writes the impulse responses of grid point `point_index` as a WAV file with one channel per actuator of the
/// dataset (in [`Dataset::actuators`] order), at the dataset's sample rate. Returns the actuators, channel by
/// channel.
///
/// # Errors
/// [`StoreError::NotInDataset`] if the point lacks a response for one of the actuators; [`StoreError::Wav`] if the
/// sample rate is not a whole number of Hz; as [`write_wav_f32`].
pub fn export_wav(dataset: &Dataset, point_index: u32, path: impl AsRef<Path>) -> Result<Vec<u16>, StoreError> {
    let actuators = dataset.actuators().to_vec();
    let channels = actuators
        .iter()
        .map(|&actuator| dataset.ir(point_index, actuator).ok_or(StoreError::NotInDataset { point_index, actuator }))
        .collect::<Result<Vec<_>, _>>()?;
    write_wav_f32(path, &channels, dataset.sample_rate_hz())?;
    Ok(actuators)
}

//! A playback-and-recording session through a [`Rig`]'s capabilities: what every recipe does per actuator and
//! point, offered here for the lab's tests and benchmark (recipes have their own, with retries and checks).

use metaplate_core::audio::AudioConfig;
use metaplate_core::daq::{DaqChannel, DaqConfig};
use metaplate_core::rig::Rig;

/// One recording: velocity (V at the LDV output) and loopback (V), from the DAQ's start, and the playback report.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// DAQ input `wiring.velocity_input`, V.
    pub velocity_v: Vec<f64>,
    /// DAQ input `wiring.loopback_input`, V.
    pub loopback_v: Vec<f64>,
    /// Underruns reported by the audio interface.
    pub underruns: u32,
    /// Whether every block continued the previous one.
    pub contiguous: bool,
}

/// Configures the audio interface (every wired channel at the wiring's rate) and the DAQ (velocity and loopback
/// at the wiring's range and rate, `block_len_samples` per block).
///
/// # Errors
/// The drivers' errors, as text.
pub fn configure(rig: &mut Rig, block_len_samples: u32) -> Result<(), String> {
    let w = rig.wiring.clone();
    rig.audio
        .configure(&AudioConfig { sample_rate_hz: w.audio_sample_rate_hz, channels: w.audio_channels })
        .map_err(|e| e.to_string())?;
    let channels = vec![
        DaqChannel { input: w.velocity_input, range_v: w.daq_range_v },
        DaqChannel { input: w.loopback_input, range_v: w.daq_range_v },
    ];
    rig.daq
        .configure(&DaqConfig { channels, sample_rate_hz: w.daq_sample_rate_hz, block_len_samples })
        .map_err(|e| e.to_string())
}

/// Plays `drive` on `actuator` with `loopback` on the loopback channel (both at the audio rate, same length) and
/// records `record_samples` DAQ samples per channel, starting the DAQ first.
///
/// # Errors
/// The drivers' errors, as text.
pub fn play_and_record(
    rig: &mut Rig,
    actuator: usize,
    drive: &[f64],
    loopback: &[f64],
    record_samples: usize,
) -> Result<Recording, String> {
    let w = rig.wiring.clone();
    let mut channels = vec![vec![0.0; drive.len()]; w.audio_channels as usize];
    let channel = *w.actuator_channels.get(actuator).ok_or("no such actuator")? as usize;
    channels[channel].copy_from_slice(drive);
    channels[w.loopback_channel as usize].copy_from_slice(loopback);
    rig.daq.start().map_err(|e| e.to_string())?;
    rig.audio.start(&channels).map_err(|e| e.to_string())?;
    let mut rec = Recording { velocity_v: Vec::new(), loopback_v: Vec::new(), underruns: 0, contiguous: true };
    while rec.velocity_v.len() < record_samples {
        let block = rig.daq.read_block().map_err(|e| e.to_string())?;
        rec.contiguous &= block.integrity.is_contiguous();
        rec.velocity_v.extend_from_slice(&block.volts[0]);
        rec.loopback_v.extend_from_slice(&block.volts[1]);
    }
    rec.velocity_v.truncate(record_samples);
    rec.loopback_v.truncate(record_samples);
    rec.underruns = rig.audio.finish().map_err(|e| e.to_string())?.underruns;
    rig.daq.stop().map_err(|e| e.to_string())?;
    Ok(rec)
}

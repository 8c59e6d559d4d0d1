//! A rig: the instruments a recipe drives, behind their capability traits, and how they are wired together.
//!
//! Recipes receive a [`Rig`] and never know whether it is the real lab (drivers on serial, USB and ALSA) or the
//! mock lab (the same drivers on in-process transports, on a virtual clock).

use std::sync::Arc;

use crate::aim::Aim;
use crate::audio::{AudioConfig, AudioError, AudioOut};
use crate::clock::Clock;
use crate::daq::{Daq, DaqChannel, DaqConfig, DaqError};
use crate::vibrometer::Vibrometer;

/// How the instruments are cabled, and the rates they run at.
///
/// Valid range (checked by [`Wiring::validate`]): one audio channel per actuator, all distinct and different from
/// the loopback channel; distinct DAQ inputs; finite positive rates and scales.
#[derive(Debug, Clone, PartialEq)]
pub struct Wiring {
    /// Audio output channel (from 0) that drives each actuator, indexed by actuator.
    pub actuator_channels: Vec<u32>,
    /// Audio output channel looped back into the DAQ as the timing reference.
    pub loopback_channel: u32,
    /// Output channels to open on the audio interface (at least every channel above + 1).
    pub audio_channels: u32,
    /// The audio interface's frame rate, Hz.
    pub audio_sample_rate_hz: f64,
    /// DAQ analog input that records the LDV's velocity output.
    pub velocity_input: u8,
    /// DAQ analog input that records the loopback channel.
    pub loopback_input: u8,
    /// DAQ input range for both inputs, +/- V.
    pub daq_range_v: f64,
    /// DAQ per-channel sample rate, Hz.
    pub daq_sample_rate_hz: f64,
    /// Volts at the DAQ's loopback input for a full-scale (1.0) audio sample, V.
    pub loopback_volts_per_full_scale: f64,
}

impl Wiring {
    /// Checks the wiring.
    ///
    /// # Errors
    /// A sentence saying what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = std::collections::BTreeSet::new();
        for (actuator, &channel) in self.actuator_channels.iter().enumerate() {
            if channel == self.loopback_channel || !seen.insert(channel) {
                return Err(format!("actuator {actuator}'s audio channel {channel} is used twice"));
            }
        }
        let highest = self.actuator_channels.iter().copied().chain([self.loopback_channel]).max().unwrap_or(0);
        if highest >= self.audio_channels {
            return Err(format!("audio channel {highest} is beyond the {} opened channels", self.audio_channels));
        }
        if self.velocity_input == self.loopback_input {
            return Err(format!("velocity and loopback share DAQ input {}", self.velocity_input));
        }
        for (name, value) in [
            ("audio_sample_rate_hz", self.audio_sample_rate_hz),
            ("daq_sample_rate_hz", self.daq_sample_rate_hz),
            ("daq_range_v", self.daq_range_v),
            ("loopback_volts_per_full_scale", self.loopback_volts_per_full_scale),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(format!("{name} = {value} must be finite and > 0"));
            }
        }
        Ok(())
    }

    /// The DAQ configuration for play-and-record: the velocity input first, the loopback second (the order
    /// [`Rig::play_and_record`] reads them in), both at the wiring's range and rate, `block_len_samples` per block.
    pub fn daq_config(&self, block_len_samples: u32) -> DaqConfig {
        DaqConfig {
            channels: vec![
                DaqChannel { input: self.velocity_input, range_v: self.daq_range_v },
                DaqChannel { input: self.loopback_input, range_v: self.daq_range_v },
            ],
            sample_rate_hz: self.daq_sample_rate_hz,
            block_len_samples,
        }
    }

    /// The audio configuration: every opened channel at the wiring's rate.
    pub fn audio_config(&self) -> AudioConfig {
        AudioConfig { sample_rate_hz: self.audio_sample_rate_hz, channels: self.audio_channels }
    }
}

/// What the DAQ recorded while the audio interface played, in volts at the DAQ rate, and what went wrong in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The velocity input, V.
    pub velocity_v: Vec<f64>,
    /// The loopback input, V.
    pub loopback_v: Vec<f64>,
    /// Some sample sat on a rail.
    pub clipped: bool,
    /// Samples were lost (packets lost, samples missing, overrun): the recording has a gap.
    pub gap: bool,
    /// The DAQ reported that its buffer overflowed (samples dropped at the source, before the host read them): one
    /// cause of a [`Recording::gap`], named apart because its remedy differs (a host or bus too busy to read in
    /// time, not a lost packet).
    pub daq_overrun: bool,
    /// Audio underruns during the playback.
    pub underruns: u32,
}

/// Why a play-and-record failed.
#[derive(Debug, thiserror::Error)]
pub enum PlayRecordError {
    /// The DAQ failed.
    #[error(transparent)]
    Daq(#[from] DaqError),
    /// The audio interface failed.
    #[error(transparent)]
    Audio(#[from] AudioError),
    /// A DAQ block lacked the velocity or the loopback input (the DAQ is not configured as
    /// [`Wiring::daq_config`] says).
    #[error("DAQ block with {channels} channels, expected 2")]
    Channels {
        /// Channels in the block.
        channels: usize,
    },
}

/// The instruments of one lab, as capabilities, with their wiring and the clock they share.
pub struct Rig {
    /// The vibrometer.
    pub vibrometer: Box<dyn Vibrometer + Send>,
    /// What puts the vibrometer's beam on a point of the plate.
    pub aim: Box<dyn Aim + Send>,
    /// The DAQ recording velocity and loopback.
    pub daq: Box<dyn Daq + Send>,
    /// The audio interface driving the actuators.
    pub audio: Box<dyn AudioOut + Send>,
    /// The clock the recipe waits on (real, or the mock lab's virtual clock).
    pub clock: Arc<dyn Clock>,
    /// How it is cabled.
    pub wiring: Wiring,
}

impl Rig {
    /// Plays `buffers` (one per audio channel, at the audio rate) while recording `record_samples` samples per
    /// channel: starts the DAQ, then the audio, reads blocks to the length, finishes the audio and stops the DAQ.
    /// No retries and no recovery: that is the caller's policy. The DAQ must be configured as
    /// [`Wiring::daq_config`] says (velocity first, loopback second).
    ///
    /// # Errors
    /// The device's error as [`PlayRecordError`] says; after one the devices may still be running (the caller stops
    /// them), except that a refused audio start stops the DAQ.
    pub fn play_and_record(
        &mut self,
        buffers: &[Vec<f64>],
        record_samples: usize,
    ) -> Result<Recording, PlayRecordError> {
        self.daq.start()?;
        if let Err(e) = self.audio.start(buffers) {
            let _ = self.daq.stop();
            return Err(e.into());
        }
        let mut velocity_v = Vec::with_capacity(record_samples);
        let mut loopback_v = Vec::with_capacity(record_samples);
        let (mut clipped, mut gap, mut daq_overrun) = (false, false, false);
        while velocity_v.len() < record_samples {
            let block = self.daq.read_block()?;
            let [velocity, loopback, ..] = block.volts.as_slice() else {
                return Err(PlayRecordError::Channels { channels: block.volts.len() });
            };
            clipped |= block.integrity.clipped;
            gap |= !block.integrity.is_contiguous();
            daq_overrun |= block.integrity.overrun;
            velocity_v.extend_from_slice(velocity);
            loopback_v.extend_from_slice(loopback);
        }
        velocity_v.truncate(record_samples);
        loopback_v.truncate(record_samples);
        let report = self.audio.finish()?;
        self.daq.stop()?;
        Ok(Recording { velocity_v, loopback_v, clipped, gap, daq_overrun, underruns: report.underruns })
    }
}

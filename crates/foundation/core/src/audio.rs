//! The `AudioOut` capability: a multichannel audio interface that plays drive signals, as recipes see it.
//!
//! A recipe configures the interface (sample rate and channel count), starts playing a buffer (one signal per
//! output channel, equal lengths, full scale = 1.0), does other work (reads the DAQ) while it plays, and then waits
//! for the end of playback, which reports what went wrong on the way (underruns). Playback start is *not*
//! sample-accurate with anything else: the loopback reference channel, recorded by the DAQ, is how a recipe finds
//! where the playback really started and how fast the interface's clock ran.

/// Who the device is, as it reports itself (for ALSA: card and PCM names).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct AudioIdentity {
    /// Manufacturer (empty when the backend cannot tell).
    pub vendor: String,
    /// Model or card name.
    pub model: String,
    /// What a reopen looks the device up by (an ALSA PCM name such as `hw:CARD=24Ao,DEV=0`, a serial number).
    pub serial: String,
    /// Firmware or driver version (empty when unknown).
    pub firmware: String,
}

/// A playback configuration.
///
/// Valid range (checked by the driver, which answers [`AudioError::Config`] otherwise): a finite
/// `sample_rate_hz > 0` the device runs at exactly (no resampling behind our back), `1 <= channels` up to the
/// device's output count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AudioConfig {
    /// Frames per second, Hz.
    pub sample_rate_hz: f64,
    /// Output channels used, from channel 0.
    pub channels: u32,
}

/// What happened during one playback.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PlaybackReport {
    /// Frames handed to the device.
    pub frames_played: u64,
    /// Underruns (the device ran dry and played silence or repeated data): a recording made during this playback
    /// is suspect and should be repeated.
    pub underruns: u32,
}

/// Why the audio interface failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AudioError {
    /// The device did not accept data in time.
    #[error("audio interface timed out: {detail}")]
    Timeout {
        /// What was waited for.
        detail: String,
    },
    /// The device went away; [`AudioOut::reopen`] may bring it back.
    #[error("audio interface disconnected: {detail}")]
    Disconnected {
        /// What the backend said.
        detail: String,
    },
    /// The configuration or buffer is not one this device can play (rate, channel count, sample format, unequal
    /// channel lengths, non-finite samples).
    #[error("invalid audio configuration: {detail}")]
    Config {
        /// What is wrong.
        detail: String,
    },
    /// A call out of order (start before configure, start while playing, finish with nothing playing).
    #[error("audio interface misuse: {detail}")]
    State {
        /// What was called when.
        detail: String,
    },
    /// The backend reported an error it could not recover from.
    #[error("audio device error: {detail}")]
    Device {
        /// What the backend said.
        detail: String,
    },
    /// The backend is not available on this machine (no sound card, no ALSA library).
    #[error("audio interface unavailable: {detail}")]
    Unavailable {
        /// Why.
        detail: String,
    },
}

impl AudioError {
    /// Whether a recipe should try [`AudioOut::reopen`] and repeat the measurement.
    pub fn suggests_reopen(&self) -> bool {
        matches!(self, AudioError::Disconnected { .. } | AudioError::Timeout { .. })
    }
}

/// A multichannel audio output, real (ALSA) or simulated.
pub trait AudioOut {
    /// The device's identity.
    fn identity(&self) -> &AudioIdentity;

    /// Opens the stream at this rate and channel count, checking that the device runs at them exactly.
    ///
    /// # Errors
    /// [`AudioError::Config`] for a rate, channel count or sample format the device does not offer.
    fn configure(&mut self, config: &AudioConfig) -> Result<(), AudioError>;

    /// Starts playing `channels` (one signal per configured output channel, all the same length, samples in
    /// full-scale units: |x| <= 1, beyond which the device clips) and returns as soon as playback has started.
    ///
    /// # Errors
    /// [`AudioError::Config`] for a wrong channel count, unequal lengths or non-finite samples (nothing is
    /// played); [`AudioError::State`] when not configured or already playing; link errors as for the device.
    fn start(&mut self, channels: &[Vec<f64>]) -> Result<(), AudioError>;

    /// Waits for the playback started by [`AudioOut::start`] to end, and reports it.
    ///
    /// # Errors
    /// [`AudioError::State`] when nothing is playing; link errors as for the device.
    fn finish(&mut self) -> Result<PlaybackReport, AudioError>;

    /// Closes and reopens the device by its identity, re-applying the last configuration.
    ///
    /// # Errors
    /// [`AudioError::Disconnected`] while the device is still absent.
    fn reopen(&mut self) -> Result<(), AudioError>;
}

/// Checks a playback buffer against a configuration: `channels` signals of equal, nonzero length, finite samples.
///
/// # Errors
/// [`AudioError::Config`] saying what is wrong.
pub fn check_playback(config: &AudioConfig, channels: &[Vec<f64>]) -> Result<usize, AudioError> {
    if channels.len() != config.channels as usize {
        return Err(AudioError::Config {
            detail: format!("{} signals for {} configured channels", channels.len(), config.channels),
        });
    }
    let frames = channels.first().map_or(0, Vec::len);
    if frames == 0 {
        return Err(AudioError::Config { detail: "empty playback buffer".into() });
    }
    for (index, signal) in channels.iter().enumerate() {
        if signal.len() != frames {
            return Err(AudioError::Config {
                detail: format!("channel {index} has {} frames, channel 0 has {frames}", signal.len()),
            });
        }
        if let Some(at) = signal.iter().position(|x| !x.is_finite()) {
            return Err(AudioError::Config { detail: format!("channel {index} frame {at} is not finite") });
        }
    }
    Ok(frames)
}

//! `AudioOut` over any [`PcmSink`].

use metaplate_core::audio::{AudioConfig, AudioError, AudioIdentity, AudioOut, PlaybackReport, check_playback};

use crate::sink::{PcmError, PcmParams, PcmSink};

/// The audio interface driver: the [`AudioOut`] capability over a [`PcmSink`].
///
/// It refuses a device that opens at another rate or channel count than asked (a resampling sound server would
/// silently change the sweep), converts buffers to interleaved `f32`, and maps sink errors to [`AudioError`].
pub struct AudioDriver<S: PcmSink> {
    sink: S,
    identity: AudioIdentity,
    config: Option<AudioConfig>,
    playing: bool,
}

impl<S: PcmSink> AudioDriver<S> {
    /// A driver over `sink`; nothing is opened until [`AudioOut::configure`].
    pub fn new(sink: S) -> Self {
        let (vendor, model, serial) = sink.describe();
        Self {
            sink,
            identity: AudioIdentity { vendor, model, serial, firmware: String::new() },
            config: None,
            playing: false,
        }
    }

    /// The sink, for tests and for the mock lab's bookkeeping.
    pub fn sink(&self) -> &S {
        &self.sink
    }

    /// The sink, mutably.
    pub fn sink_mut(&mut self) -> &mut S {
        &mut self.sink
    }

    fn open(&mut self, config: &AudioConfig) -> Result<(), AudioError> {
        let wanted = PcmParams { sample_rate_hz: config.sample_rate_hz, channels: config.channels };
        let got = self.sink.open(wanted).map_err(to_audio_error)?;
        // Exact rate: an interface that plays at another rate (or a sound server that resamples) changes every
        // frequency the recipes rely on.
        if got.channels != wanted.channels
            || (got.sample_rate_hz - wanted.sample_rate_hz).abs() > 1e-9 * wanted.sample_rate_hz
        {
            self.sink.close();
            return Err(AudioError::Config {
                detail: format!(
                    "asked for {} channels at {} Hz, the device opened {} channels at {} Hz",
                    wanted.channels, wanted.sample_rate_hz, got.channels, got.sample_rate_hz
                ),
            });
        }
        Ok(())
    }
}

/// Maps a sink error to the capability's error.
fn to_audio_error(error: PcmError) -> AudioError {
    match error {
        PcmError::Params(detail) => AudioError::Config { detail },
        PcmError::Timeout(detail) => AudioError::Timeout { detail },
        PcmError::Disconnected(detail) => AudioError::Disconnected { detail },
        PcmError::State(detail) => AudioError::State { detail },
        PcmError::Unavailable(detail) => AudioError::Unavailable { detail },
        PcmError::Other(detail) => AudioError::Device { detail },
    }
}

impl<S: PcmSink> AudioOut for AudioDriver<S> {
    fn identity(&self) -> &AudioIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &AudioConfig) -> Result<(), AudioError> {
        if !(config.sample_rate_hz.is_finite() && config.sample_rate_hz > 0.0) || config.channels == 0 {
            return Err(AudioError::Config {
                detail: format!("{} channels at {} Hz", config.channels, config.sample_rate_hz),
            });
        }
        if self.playing {
            return Err(AudioError::State { detail: "configure while playing".into() });
        }
        self.open(config)?;
        self.config = Some(*config);
        Ok(())
    }

    fn start(&mut self, channels: &[Vec<f64>]) -> Result<(), AudioError> {
        let config = self.config.ok_or_else(|| AudioError::State { detail: "start before configure".into() })?;
        if self.playing {
            return Err(AudioError::State { detail: "start while a playback is running".into() });
        }
        let frames = check_playback(&config, channels)?;
        let mut interleaved = Vec::with_capacity(frames * channels.len());
        for frame in 0..frames {
            // Full scale is 1.0; the device would clip beyond it, so clip here, visibly the same.
            interleaved.extend(channels.iter().map(|signal| signal[frame].clamp(-1.0, 1.0) as f32));
        }
        self.sink.submit(interleaved).map_err(to_audio_error)?;
        self.playing = true;
        Ok(())
    }

    fn finish(&mut self) -> Result<PlaybackReport, AudioError> {
        if !self.playing {
            return Err(AudioError::State { detail: "finish with nothing playing".into() });
        }
        self.playing = false;
        let status = self.sink.wait().map_err(to_audio_error)?;
        Ok(PlaybackReport { frames_played: status.frames_played, underruns: status.underruns })
    }

    fn reopen(&mut self) -> Result<(), AudioError> {
        self.playing = false;
        self.sink.close();
        match self.config {
            Some(config) => self.open(&config),
            None => Ok(()),
        }
    }
}

//! The narrow transport of an audio driver: a PCM playback stream.

/// What the device actually opened (it may differ from what was asked; the driver refuses a mismatch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcmParams {
    /// Frames per second the device runs at, Hz.
    pub sample_rate_hz: f64,
    /// Interleaved channels per frame.
    pub channels: u32,
}

/// How one submitted buffer played.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PcmStatus {
    /// Frames the device consumed.
    pub frames_played: u64,
    /// Underruns (xruns) the stream recovered from while playing.
    pub underruns: u32,
}

/// Why a PCM operation failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PcmError {
    /// The device refused the parameters (rate, channels, sample format).
    #[error("PCM parameters refused: {0}")]
    Params(String),
    /// The stream did not progress within its timeout.
    #[error("PCM timed out: {0}")]
    Timeout(String),
    /// The device is gone (unplugged); only reopening can help.
    #[error("PCM device disconnected: {0}")]
    Disconnected(String),
    /// Called out of order (submit before open, wait with nothing submitted, submit while playing).
    #[error("PCM misuse: {0}")]
    State(String),
    /// The backend is not available here.
    #[error("PCM backend unavailable: {0}")]
    Unavailable(String),
    /// Any other backend failure.
    #[error("PCM failure: {0}")]
    Other(String),
}

/// One playback stream of a multichannel audio device.
///
/// A sink plays one buffer at a time, in the background: [`submit`](Self::submit) returns once playback has
/// started, [`wait`](Self::wait) returns when it has ended. Samples are interleaved `f32` in full-scale units
/// (|x| <= 1); a backend whose device wants integers converts.
pub trait PcmSink: Send {
    /// Short names of the device for [`metaplate_core::audio::AudioIdentity`]: (vendor, model, lookup name).
    fn describe(&self) -> (String, String, String);

    /// Opens (or re-opens) the stream asking for exactly these parameters, and returns what the device opened.
    ///
    /// # Errors
    /// [`PcmError::Params`] when the device cannot run at them; `Disconnected`, `Unavailable`, `Other`.
    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError>;

    /// Starts playing `interleaved` (`frames * channels` samples) and returns without waiting for the end.
    ///
    /// # Errors
    /// `State` when not open or still playing; link errors.
    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError>;

    /// Waits for the submitted buffer to finish playing.
    ///
    /// # Errors
    /// `State` when nothing was submitted; `Timeout`, `Disconnected`, `Other`.
    fn wait(&mut self) -> Result<PcmStatus, PcmError>;

    /// Closes the stream (idempotent).
    fn close(&mut self);
}

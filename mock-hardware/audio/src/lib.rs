//! The mock audio interface: a PCM sink on the virtual clock with output latency, clock offset and underruns.
//!
//! [`MockPcm`] implements the audio driver's transport ([`metaplate_audio::PcmSink`]), so the real
//! [`metaplate_audio::AudioDriver`] runs on it. Nothing plays in wall time and there are no threads:
//! - `submit` at virtual time `t` schedules the buffer to sound from `t + latency_s`, at the interface's true
//!   frame rate `sample_rate_hz * (1 + clock_offset_ppm * 1e-6)` (the device believes it runs at the nominal rate,
//!   and says so to the driver);
//! - an `audio_underrun` fault whose window meets the playback inserts silence into what is physically played (at
//!   the window's start, lasting the window, at least [`MIN_UNDERRUN_S`]) and is counted in `PcmStatus::underruns`;
//! - `wait` advances the clock to the end of the physical playback (if it is not already past it);
//! - a `disconnect` fault takes the interface off its bus on its next use (see [`DisconnectTracker`]).
//!
//! What was physically played ([`Playback`]: true start time, true frame rate, samples with the gaps) is handed to
//! a [`PlaybackObserver`] at `submit`: the mock lab turns it into actuator forces and loopback voltage.
//!
//! [`FaultWindows`] and [`DisconnectTracker`] are the scene's time-keyed faults as the mock lab consults them (is a
//! fault of this kind active now; has a disconnect taken a device off its bus), for the audio interface and for the
//! rest of its chain alike.

mod windows;

use std::sync::Arc;

use metaplate_audio::{PcmError, PcmParams, PcmSink, PcmStatus};
use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::scene::{AudioSpec, FaultKind, FaultSpec};

pub use windows::{DisconnectTracker, FaultWindows};

/// The shortest silence an underrun inserts, s (one ALSA period of 480 frames at 48 kHz): a zero-length fault
/// window still costs a period.
pub const MIN_UNDERRUN_S: f64 = 0.010;

/// What the interface physically played, in true (virtual) time.
#[derive(Debug, Clone, PartialEq)]
pub struct Playback {
    /// Virtual time at which frame 0 sounds at the outputs, s (submit time plus latency).
    pub start_s: f64,
    /// True frame rate, Hz (nominal rate with the clock offset applied).
    pub frame_rate_hz: f64,
    /// Interleaved channels per frame.
    pub channels: u32,
    /// Interleaved samples as played, full scale 1.0, underrun gaps (zeros) included.
    pub samples: Arc<Vec<f32>>,
    /// Underruns during this playback.
    pub underruns: u32,
}

impl Playback {
    /// Frames physically played (gaps included).
    pub fn frames(&self) -> usize {
        self.samples.len() / (self.channels.max(1) as usize)
    }

    /// Virtual time at which the last frame has finished, s.
    pub fn end_s(&self) -> f64 {
        self.start_s + self.frames() as f64 / self.frame_rate_hz
    }
}

/// Told of every playback as it is submitted (the mock lab's signal chain).
pub trait PlaybackObserver: Send + Sync {
    /// `playback` has just been scheduled.
    fn on_playback(&self, playback: &Playback);
}

/// The mock multichannel audio interface (a MOTU 24Ao class device as the scene describes it).
pub struct MockPcm {
    spec: AudioSpec,
    clock: Arc<VirtualClock>,
    windows: FaultWindows,
    disconnects: DisconnectTracker,
    observer: Option<Arc<dyn PlaybackObserver>>,
    open: Option<PcmParams>,
    playing: Option<Playback>,
    last: Option<Playback>,
}

impl std::fmt::Debug for MockPcm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MockPcm").field("spec", &self.spec).field("open", &self.open).finish_non_exhaustive()
    }
}

impl MockPcm {
    /// An interface as `spec` describes it, on `clock`, suffering the `audio_underrun` and `disconnect` faults of
    /// `faults` (other kinds are ignored).
    pub fn new(spec: &AudioSpec, clock: Arc<VirtualClock>, faults: &[FaultSpec]) -> Self {
        let windows = FaultWindows::new(faults);
        let disconnects = DisconnectTracker::new(&windows);
        Self { spec: *spec, clock, windows, disconnects, observer: None, open: None, playing: None, last: None }
    }

    /// Hands every playback to `observer` at submit.
    pub fn with_observer(mut self, observer: Arc<dyn PlaybackObserver>) -> Self {
        self.observer = Some(observer);
        self
    }

    /// The true frame rate, Hz: nominal with the clock offset.
    pub fn true_rate_hz(&self) -> f64 {
        self.spec.sample_rate_hz * (1.0 + self.spec.clock_offset_ppm * 1e-6)
    }

    /// The last playback submitted (for tests).
    pub fn last_playback(&self) -> Option<&Playback> {
        self.last.as_ref()
    }

    fn check_link(&mut self) -> Result<(), PcmError> {
        if self.disconnects.is_away(self.clock.now_s()) {
            self.open = None;
            self.playing = None;
            return Err(PcmError::Disconnected("mock audio interface is off the bus".into()));
        }
        Ok(())
    }

    /// The physical samples of `interleaved` starting at `start_s`: silence inserted for each underrun window that
    /// meets the playback. Returns the samples and the underrun count.
    fn with_underruns(&self, interleaved: Vec<f32>, channels: usize, start_s: f64) -> (Vec<f32>, u32) {
        let rate = self.true_rate_hz();
        let mut samples = interleaved;
        let mut underruns = 0;
        let mut end_s = start_s + (samples.len() / channels) as f64 / rate;
        for fault in self.windows.of_kind(FaultKind::AudioUnderrun) {
            let fault_end = fault.at_s + fault.duration_s;
            if fault_end < start_s || fault.at_s > end_s {
                continue;
            }
            let gap_start_s = fault.at_s.max(start_s);
            let frame = (((gap_start_s - start_s) * rate).round() as usize).min(samples.len() / channels);
            let gap_frames = ((fault_end - gap_start_s).max(MIN_UNDERRUN_S) * rate).round() as usize;
            let at = frame * channels;
            samples.splice(at..at, std::iter::repeat_n(0.0, gap_frames * channels));
            end_s += gap_frames as f64 / rate;
            underruns += 1;
        }
        (samples, underruns)
    }
}

impl PcmSink for MockPcm {
    fn describe(&self) -> (String, String, String) {
        ("metaplate".into(), "mock-24Ao".into(), "mock:audio0".into())
    }

    /// Opens at exactly the scene's nominal rate and up to its channel count (a real interface's fixed clock).
    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        if !self.disconnects.reopen(self.clock.now_s()) {
            return Err(PcmError::Disconnected("mock audio interface is still off the bus".into()));
        }
        if wanted.channels == 0 || wanted.channels > self.spec.channels {
            return Err(PcmError::Params(format!(
                "{} channels asked, the interface has 1 to {}",
                wanted.channels, self.spec.channels
            )));
        }
        let params = PcmParams { sample_rate_hz: self.spec.sample_rate_hz, channels: wanted.channels };
        self.open = Some(params);
        self.playing = None;
        Ok(params)
    }

    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        self.check_link()?;
        let params = self.open.ok_or_else(|| PcmError::State("submit before open".into()))?;
        if self.playing.is_some() {
            return Err(PcmError::State("submit while a buffer is playing".into()));
        }
        let channels = params.channels as usize;
        if interleaved.is_empty() || !interleaved.len().is_multiple_of(channels) {
            return Err(PcmError::Params(format!("{} samples is not a whole number of frames", interleaved.len())));
        }
        let start_s = self.clock.now_s() + self.spec.latency_s;
        let (samples, underruns) = self.with_underruns(interleaved, channels, start_s);
        let playback = Playback {
            start_s,
            frame_rate_hz: self.true_rate_hz(),
            channels: params.channels,
            samples: Arc::new(samples),
            underruns,
        };
        if let Some(observer) = &self.observer {
            observer.on_playback(&playback);
        }
        self.playing = Some(playback);
        Ok(())
    }

    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        self.check_link()?;
        let playback = self.playing.take().ok_or_else(|| PcmError::State("wait with nothing submitted".into()))?;
        let remaining_s = playback.end_s() - self.clock.now_s();
        self.clock.advance(remaining_s);
        let status = PcmStatus { frames_played: playback.frames() as u64, underruns: playback.underruns };
        self.last = Some(playback);
        Ok(status)
    }

    fn close(&mut self) {
        self.open = None;
        self.playing = None;
    }
}

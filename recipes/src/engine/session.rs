//! The rig's session for recipes: one acquisition ([`Rig::play_and_record`] at the session's velocity range), and
//! recovery from device faults: reconnect,
//! reopen, re-apply settings, poll while a device stays away.

use metaplate_core::aim::AimError;
use metaplate_core::audio::{AudioConfig, AudioError};
use metaplate_core::daq::{DaqConfig, DaqError};
use metaplate_core::rig::{PlayRecordError, Recording, Rig};
use metaplate_core::vibrometer::{VelocityScale, VibrometerError};

use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};

/// How long and how often a recipe waits for a device that went away.
///
/// Valid range: finite `poll_interval_s > 0`, finite `pause_after_s >= 0`, `reference_limit_db` finite (or
/// infinite to never warn).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecoveryPolicy {
    /// Seconds between reconnection attempts (rig clock).
    pub poll_interval_s: f64,
    /// After this long without the device the run reports itself paused, and keeps polling (it never gives up on a
    /// device that is merely absent: an overnight scan waits for someone to plug the cable back in).
    pub pause_after_s: f64,
    /// After a recovery a scan re-measures a committed reference point; a relative error (error energy over the
    /// committed response's energy) above this, dB, is reported as a warning: the rig may not be as it was
    /// (moved plate, shifted beam, a setting not restored).
    pub reference_limit_db: f64,
}

impl Default for RecoveryPolicy {
    /// Poll every 2 s; report a pause after 60 s; warn when the reference point moved by more than -20 dB (10 %
    /// in amplitude: noise between two quick-protocol measurements is some 30 dB down, see the faults test).
    fn default() -> Self {
        Self { poll_interval_s: 2.0, pause_after_s: 60.0, reference_limit_db: -20.0 }
    }
}

/// What one acquisition recorded ([`Recording`]: volts at the DAQ rate, clipping, gaps, underruns), with the
/// velocity scale in force.
#[derive(Debug, Clone, PartialEq)]
pub struct Acquisition {
    /// The recording.
    pub recording: Recording,
    /// The vibrometer's velocity scale in force.
    pub scale: VelocityScale,
}

impl Acquisition {
    /// Whether the recording is whole (no gap, no underrun); clipping is judged separately.
    pub fn is_whole(&self) -> bool {
        !self.recording.gap && self.recording.underruns == 0
    }
}

/// The session state that changes later measurements (today the velocity range in force): committed with every
/// unit (in its journal line, atomically with its rows) and restored on resume from the last committed unit, so that
/// what a unit measures depends only on the scene, the seed, the unit, its attempts and what was committed before
/// it, never on whether the run was interrupted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionState {
    /// Velocity range requested of the vibrometer, m/s (the configured one, widened tenfold at each clipping).
    pub velocity_range_m_s: f64,
}

impl SessionState {
    const VELOCITY_RANGE_KEY: &'static str = "velocity_range_m_s";

    /// The state as the journal stores it: `{"velocity_range_m_s": ...}`.
    pub fn to_json(self) -> serde_json::Map<String, serde_json::Value> {
        let mut map = serde_json::Map::new();
        map.insert(Self::VELOCITY_RANGE_KEY.into(), self.velocity_range_m_s.into());
        map
    }

    /// Reads a state that [`to_json`](Self::to_json) wrote (other keys, from a later version, are ignored).
    ///
    /// # Errors
    /// [`RecipeError::Config`] if the velocity range is missing, not a number, or not finite and positive.
    pub fn from_json(map: &serde_json::Map<String, serde_json::Value>) -> Result<Self, RecipeError> {
        let range = map.get(Self::VELOCITY_RANGE_KEY).and_then(serde_json::Value::as_f64);
        match range {
            Some(v) if v.is_finite() && v > 0.0 => Ok(Self { velocity_range_m_s: v }),
            _ => Err(RecipeError::Config(format!(
                "the committed session state {} has no valid {} (finite, > 0)",
                serde_json::Value::Object(map.clone()),
                Self::VELOCITY_RANGE_KEY
            ))),
        }
    }
}

/// A device failure, sorted by the remedy.
#[derive(Debug)]
pub(crate) enum Fault {
    /// A link fault: reconnect or reopen the device, then repeat the step.
    Link(Device, String),
    /// The acquisition was spoiled (an overrun that ended it, a protocol hiccup): repeat it.
    Spoiled(String),
    /// Nothing a retry can fix.
    Fatal(RecipeError),
}

/// Which instrument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Device {
    Vibrometer,
    Aim,
    Daq,
    Audio,
}

impl From<VibrometerError> for Fault {
    fn from(e: VibrometerError) -> Self {
        if e.suggests_reconnect() {
            Fault::Link(Device::Vibrometer, e.to_string())
        } else if matches!(e, VibrometerError::Protocol { .. }) {
            Fault::Spoiled(e.to_string())
        } else {
            Fault::Fatal(e.into())
        }
    }
}

impl From<AimError> for Fault {
    fn from(e: AimError) -> Self {
        if e.suggests_reconnect() { Fault::Link(Device::Aim, e.to_string()) } else { Fault::Fatal(e.into()) }
    }
}

impl From<DaqError> for Fault {
    fn from(e: DaqError) -> Self {
        match e {
            DaqError::Disconnected { .. } | DaqError::Timeout { .. } => Fault::Link(Device::Daq, e.to_string()),
            DaqError::Overrun { .. } | DaqError::Protocol { .. } | DaqError::Device { .. } => {
                Fault::Spoiled(e.to_string())
            }
            DaqError::Config { .. } | DaqError::Unavailable { .. } => Fault::Fatal(e.into()),
        }
    }
}

impl From<PlayRecordError> for Fault {
    fn from(e: PlayRecordError) -> Self {
        match e {
            PlayRecordError::Daq(e) => e.into(),
            PlayRecordError::Audio(e) => e.into(),
            PlayRecordError::Channels { .. } => Fault::Spoiled(e.to_string()),
        }
    }
}

impl From<AudioError> for Fault {
    fn from(e: AudioError) -> Self {
        if e.suggests_reopen() {
            Fault::Link(Device::Audio, e.to_string())
        } else if matches!(e, AudioError::State { .. }) {
            Fault::Spoiled(e.to_string())
        } else {
            Fault::Fatal(e.into())
        }
    }
}

/// Samples per channel of a DAQ block: 0.1 s at 24 kHz, a compromise between transfer overhead and how late a
/// stop is noticed.
pub(crate) const BLOCK_LEN_SAMPLES: u32 = 2400;

/// The rig, configured for recipes: the DAQ on the velocity and loopback inputs, the audio interface at its rate.
pub struct Instruments<'a> {
    /// The rig.
    pub rig: &'a mut Rig,
    daq_config: DaqConfig,
    audio_config: AudioConfig,
    /// Velocity range requested, m/s (re-applied after a reconnect by the driver).
    max_velocity_m_s: f64,
    scale: Option<VelocityScale>,
    policy: RecoveryPolicy,
    /// Where the beam should be (re-applied after a reconnect).
    beam_m: Option<(f64, f64)>,
    /// Set by every recovery; a scan clears it after re-measuring its reference point.
    pub(crate) recovered: bool,
}

impl<'a> Instruments<'a> {
    /// Validates the wiring and configures the DAQ (velocity and loopback inputs) and the audio interface, with
    /// recovery as `policy` says; the velocity range of `state` is set on first use.
    ///
    /// # Errors
    /// [`RecipeError::Config`] for an invalid wiring; device errors that recovery cannot fix.
    pub fn new(
        rig: &'a mut Rig,
        state: SessionState,
        policy: RecoveryPolicy,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Self, RecipeError> {
        rig.wiring.validate().map_err(RecipeError::Config)?;
        let daq_config = rig.wiring.daq_config(BLOCK_LEN_SAMPLES);
        let audio_config = rig.wiring.audio_config();
        let mut me = Self {
            rig,
            daq_config,
            audio_config,
            max_velocity_m_s: state.velocity_range_m_s,
            scale: None,
            policy,
            beam_m: None,
            recovered: false,
        };
        me.with_recovery(control, observer, |i| i.configure())?;
        me.recovered = false;
        Ok(me)
    }

    /// The session state now: what a unit committed now hands on to the next.
    pub fn state(&self) -> SessionState {
        SessionState { velocity_range_m_s: self.max_velocity_m_s }
    }

    /// Where the beam was last sent, m.
    pub fn beam(&self) -> Option<(f64, f64)> {
        self.beam_m
    }

    /// The DAQ sample rate, Hz.
    pub fn daq_rate_hz(&self) -> f64 {
        self.daq_config.sample_rate_hz
    }

    fn configure(&mut self) -> Result<(), Fault> {
        self.rig.daq.configure(&self.daq_config)?;
        self.rig.audio.configure(&self.audio_config)?;
        self.scale = Some(self.rig.vibrometer.set_velocity_range(self.max_velocity_m_s)?);
        if let Some((x, y)) = self.beam_m {
            self.rig.aim.aim_at(x, y)?;
        }
        Ok(())
    }

    /// Runs `step` until it succeeds, recovering from link faults (reconnect, reopen, re-apply every setting) and
    /// repeating spoiled steps; gives up only on a fatal fault, or when a stop to abandon is requested while a
    /// device is away.
    pub(crate) fn with_recovery<T>(
        &mut self,
        control: &RunControl,
        observer: &mut dyn Observer,
        mut step: impl FnMut(&mut Self) -> Result<T, Fault>,
    ) -> Result<T, RecipeError> {
        // Spoiled steps are repeated a bounded number of times in a row; a device that spoils every step is broken.
        const MAX_SPOILED_IN_A_ROW: u32 = 20;
        let mut spoiled = 0;
        loop {
            match step(self) {
                Ok(v) => return Ok(v),
                Err(Fault::Fatal(e)) => return Err(e),
                Err(Fault::Spoiled(detail)) => {
                    spoiled += 1;
                    tracing::warn!(%detail, "step spoiled, repeating");
                    if spoiled >= MAX_SPOILED_IN_A_ROW {
                        return Err(RecipeError::Device(format!(
                            "{MAX_SPOILED_IN_A_ROW} attempts in a row failed, the last with: {detail}"
                        )));
                    }
                    self.quiesce();
                }
                Err(Fault::Link(device, detail)) => {
                    tracing::warn!(?device, %detail, "link fault, recovering");
                    self.quiesce();
                    self.reconnect(device, &detail, control, observer)?;
                    observer.event(&Event::Recovered { detail: format!("{device:?}: {detail}") });
                    self.recovered = true;
                }
            }
        }
    }

    /// Best effort: stop whatever may be running so that the next step starts clean.
    fn quiesce(&mut self) {
        let _ = self.rig.daq.stop();
        let _ = self.rig.audio.finish();
    }

    /// Reconnects `device` and re-applies every setting, polling on the rig's clock while it stays away. A device
    /// found away while re-applying the settings (a hub glitch takes all three) joins the devices reopened at each
    /// poll, so that recovery never waits on a device it does not reopen.
    fn reconnect(
        &mut self,
        device: Device,
        detail: &str,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<(), RecipeError> {
        let clock = self.rig.clock.clone();
        let started_s = clock.now_s();
        let mut paused = false;
        let mut away = vec![device];
        loop {
            let attempt = away.iter().try_for_each(|d| self.reopen(*d)).and_then(|()| self.configure());
            match attempt {
                Ok(()) => return Ok(()),
                Err(Fault::Fatal(e)) => return Err(e),
                Err(Fault::Link(other, _)) if !away.contains(&other) => {
                    tracing::warn!(?other, "another device is away too; reopening it as well");
                    away.push(other);
                }
                Err(Fault::Link(..) | Fault::Spoiled(_)) => {}
            }
            if control.abandon_requested() {
                return Err(RecipeError::Interrupted { committed: 0 });
            }
            let away_s = clock.now_s() - started_s;
            if !paused && away_s >= self.policy.pause_after_s {
                paused = true;
                let detail = format!("{away:?} unreachable for {away_s:.0} s ({detail}); paused, still polling");
                tracing::error!("{detail}");
                observer.event(&Event::Paused { detail });
            }
            clock.sleep_s(self.policy.poll_interval_s);
        }
    }

    /// One attempt to reopen `device`.
    fn reopen(&mut self, device: Device) -> Result<(), Fault> {
        match device {
            Device::Vibrometer => self.rig.vibrometer.reconnect().map_err(Fault::from),
            Device::Aim => self.rig.aim.reconnect().map_err(Fault::from),
            Device::Daq => self.rig.daq.reopen().map_err(Fault::from),
            Device::Audio => self.rig.audio.reopen().map_err(Fault::from),
        }
    }

    /// Moves the beam to (`x_m`, `y_m`) and reads the signal level there (0 to 1).
    pub(crate) fn aim(&mut self, x_m: f64, y_m: f64) -> Result<f64, Fault> {
        self.beam_m = Some((x_m, y_m));
        self.rig.aim.aim_at(x_m, y_m)?;
        Ok(self.rig.vibrometer.signal_level()?)
    }

    /// Plays `buffers` while recording `record_samples` samples per channel.
    pub(crate) fn acquire(&mut self, buffers: &[Vec<f64>], record_samples: usize) -> Result<Acquisition, Fault> {
        let scale = match self.scale {
            Some(s) => s,
            None => {
                let s = self.rig.vibrometer.set_velocity_range(self.max_velocity_m_s)?;
                self.scale = Some(s);
                s
            }
        };
        let result = self.record(buffers, record_samples, scale);
        if result.is_err() {
            self.quiesce();
        }
        result
    }

    fn record(
        &mut self,
        buffers: &[Vec<f64>],
        record_samples: usize,
        scale: VelocityScale,
    ) -> Result<Acquisition, Fault> {
        Ok(Acquisition { recording: self.rig.play_and_record(buffers, record_samples)?, scale })
    }

    /// Asks for a larger velocity range after clipping: ten times the current full scale, if the instrument has
    /// one. Returns whether the range grew.
    pub(crate) fn widen_range(&mut self) -> Result<bool, Fault> {
        let current = self.scale.map_or(self.max_velocity_m_s, |s| s.full_scale_m_s);
        let wanted = current * 10.0;
        match self.rig.vibrometer.set_velocity_range(wanted) {
            Ok(s) => {
                let grew = s.full_scale_m_s > current;
                self.max_velocity_m_s = wanted;
                self.scale = Some(s);
                Ok(grew)
            }
            Err(VibrometerError::InvalidArgument { .. }) => Ok(false),
            Err(e) => Err(e.into()),
        }
    }
}

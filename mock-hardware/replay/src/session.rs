//! Whole sessions: re-running a recorded LDV or DAQ session through its real driver from the recorded commands
//! alone (what `metaplate replay` does), and recording short demo sessions against the mock devices.

use std::io::Write;
use std::sync::{Arc, Mutex};

use metaplate_cassette::{Cassette, DeviceIdentity, DeviceKind, Header};
use metaplate_core::clock::{Clock, RealClock, VirtualClock};
use metaplate_core::daq::{BlockIntegrity, Daq, DaqChannel, DaqConfig};
use metaplate_core::scene::LdvSpec;
use metaplate_core::vibrometer::{Tracking, Vibrometer};
use metaplate_daq::{DaqDriver, DriverSettings};
use metaplate_daq_protocol::{DeviceDecoder, HostCommand};
use metaplate_ldv::{LdvDriver, RetryPolicy};
use metaplate_ldv_protocol::{Command, CommandDecoder};
use metaplate_mock_daq::{FaultSchedule as DaqFaults, MockDaq, MockTransport, usb6211_info};
use metaplate_mock_ldv::{FaultSchedule as LdvFaults, MockController, MockDevice, MockLine};

use metaplate_audio::AudioDriver;
use metaplate_core::audio::{AudioConfig, AudioOut};

use crate::audio::{AudioStep, ReplaySink, audio_steps};
use crate::bulk::{RecordingTransport, ReplayTransport};
use crate::engine::ReplayStats;
use crate::faults::ReplayFaults;
use crate::line::{RecordingLine, ReplayLine};
use crate::load::ReplayError;
use crate::mismatch::Mismatch;
use crate::recorder::{RecordError, Recorder};
use crate::script::{Step, byte_steps};

/// One driver call made during a replay, and how it ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CallOutcome {
    /// The call, e.g. `exchange(IDN?)`, `read_block`.
    pub call: String,
    /// Its result: a short description of the value, or the driver's error message.
    pub result: Result<String, String>,
}

/// A block the DAQ driver returned during a replay.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockSummary {
    /// Its first sample's index in the acquisition.
    pub first_sample_index: u64,
    /// Samples per channel.
    pub frames: usize,
    /// What was lost before it, and whether it clipped.
    pub integrity: BlockIntegrity,
}

/// What a replayed session did.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionReport {
    /// The device kind of the cassette.
    pub device: DeviceKind,
    /// Records in the cassette.
    pub records: usize,
    /// Every driver call, in order.
    pub calls: Vec<CallOutcome>,
    /// DAQ blocks read (empty for the LDV).
    pub blocks: Vec<BlockSummary>,
    /// Retries the driver made (the LDV: resends the replay answered again; the DAQ: the driver's own count).
    pub retries: u64,
    /// What the replay transport did.
    pub stats: ReplayStats,
    /// The driver's first deviation from the recording, if any.
    pub mismatch: Option<Mismatch>,
    /// Whether every recorded call was played.
    pub finished: bool,
}

impl SessionReport {
    /// Calls that ended in an error.
    pub fn errors(&self) -> usize {
        self.calls.iter().filter(|c| c.result.is_err()).count()
    }
}

/// Replays `cassette` through the driver of its device kind (LDV, DAQ or audio interface).
///
/// # Errors
/// [`ReplayError::WrongDevice`] for a HID cassette (the keypad is read, not driven by commands).
pub fn replay(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    match cassette.header.device_kind {
        DeviceKind::LdvSerial => replay_ldv(cassette, faults),
        DeviceKind::DaqUsb => replay_daq(cassette, faults),
        DeviceKind::Audio => replay_audio(cassette, faults),
        found => Err(ReplayError::WrongDevice { expected: DeviceKind::LdvSerial, found }),
    }
}

/// Replays an audio session: a fresh [`AudioDriver`] over a [`ReplaySink`], one `configure` per recorded open,
/// one `start` per recorded buffer (de-interleaved back into channels: exact, f32 to f64 and back), one `finish`
/// per recorded wait. Stops at a mismatch.
///
/// # Errors
/// [`ReplayError::WrongDevice`] unless it is an audio cassette.
pub fn replay_audio(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    let (steps, _) = audio_steps(&cassette.records);
    let mut driver = AudioDriver::new(ReplaySink::new(cassette, faults)?);
    let mut channels = 1usize;
    let mut calls = Vec::new();
    for step in &steps {
        let (call, result) = match step {
            AudioStep::Open { wanted, .. } => {
                channels = (wanted.channels as usize).max(1);
                let config = AudioConfig { sample_rate_hz: wanted.sample_rate_hz, channels: wanted.channels };
                ("configure", driver.configure(&config).map(|()| "ok".to_string()))
            }
            AudioStep::Submit { samples, .. } => {
                let buffers: Vec<Vec<f64>> = (0..channels)
                    .map(|c| samples.iter().skip(c).step_by(channels).map(|&x| f64::from(x)).collect())
                    .collect();
                let frames = buffers.first().map_or(0, Vec::len);
                ("start", driver.start(&buffers).map(|()| format!("{frames} frames")))
            }
            AudioStep::Wait { .. } => {
                ("finish", driver.finish().map(|r| format!("{} frames, {} underruns", r.frames_played, r.underruns)))
            }
            // The driver closes only to reopen; a recorded close needs no call of its own.
            AudioStep::Close { .. } => continue,
        };
        calls.push(CallOutcome { call: call.into(), result: result.map_err(|e| e.to_string()) });
        if driver.sink().mismatch().is_some() {
            break;
        }
    }
    let sink = driver.sink();
    Ok(SessionReport {
        device: DeviceKind::Audio,
        records: cassette.records.len(),
        calls,
        blocks: Vec::new(),
        retries: 0,
        stats: sink.stats().clone(),
        mismatch: sink.mismatch().cloned(),
        finished: sink.is_finished(),
    })
}

/// The recorded host writes, in order.
fn recorded_writes(cassette: &Cassette) -> Vec<Vec<u8>> {
    byte_steps(&cassette.records)
        .0
        .into_iter()
        .filter_map(|s| match s {
            Step::Write { bytes, .. } => Some(bytes),
            _ => None,
        })
        .collect()
}

/// The driver calls implied by an LDV recording: each command other than `SYNC` (which the driver sends by
/// itself) is one `exchange`, except a resend (the same command again after a `SYNC`: a retry the driver will
/// make by itself).
fn ldv_commands(cassette: &Cassette) -> Vec<Command> {
    let mut commands: Vec<Command> = Vec::new();
    let mut synced_since_last = false;
    for bytes in recorded_writes(cassette) {
        let mut decoder = CommandDecoder::new();
        decoder.push(&bytes);
        while let Some(Ok(command)) = decoder.poll() {
            if matches!(command, Command::Sync(_)) {
                synced_since_last = true;
                continue;
            }
            let resend = synced_since_last && commands.last() == Some(&command);
            if !resend {
                commands.push(command);
            }
            synced_since_last = false;
        }
    }
    commands
}

/// Replays an LDV session: a fresh [`LdvDriver`] over a [`ReplayLine`], one `exchange` per recorded command.
/// Stops at a mismatch.
///
/// # Errors
/// [`ReplayError::WrongDevice`] unless it is an LDV cassette.
pub fn replay_ldv(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    let line = ReplayLine::new(cassette, faults)?;
    // Replay answers at once, so the clock only serves busy waits, which a virtual clock makes free.
    let clock: Arc<dyn Clock> = Arc::new(VirtualClock::new());
    let mut driver = LdvDriver::new(line, clock, RetryPolicy::default())
        .map_err(|e| ReplayError::Io { path: "LDV driver".into(), source: std::io::Error::other(e.to_string()) })?;
    let mut calls = Vec::new();
    for command in ldv_commands(cassette) {
        let result = driver.exchange(command).map(|reply| reply.to_string()).map_err(|e| e.to_string());
        calls.push(CallOutcome { call: format!("exchange({command})"), result });
        if driver.line().mismatch().is_some() {
            break;
        }
    }
    let line = driver.line();
    Ok(SessionReport {
        device: DeviceKind::LdvSerial,
        records: cassette.records.len(),
        calls,
        blocks: Vec::new(),
        retries: line.stats().retries_replayed as u64,
        stats: line.stats().clone(),
        mismatch: line.mismatch().cloned(),
        finished: line.is_finished(),
    })
}

fn daq_config(wire: &metaplate_daq_protocol::Configure) -> DaqConfig {
    DaqConfig {
        channels: wire
            .channels
            .iter()
            .map(|c| DaqChannel { input: c.index, range_v: f64::from(c.range_mv) / 1000.0 })
            .collect(),
        sample_rate_hz: f64::from(wire.sample_rate_hz),
        block_len_samples: u32::from(wire.samples_per_packet),
    }
}

/// Replays a DAQ session: `DaqDriver::open` (its `GetInfo`) over a [`ReplayTransport`], then per recorded
/// command `configure`, `start` (then `read_block` while the recording reads), `stop`; the same command twice in
/// a row is a retry the driver makes by itself; `GetInfo` after the first and `Reset` have no driver call and are
/// skipped (the replay then reports the mismatch). Stops at a mismatch.
///
/// # Errors
/// [`ReplayError::WrongDevice`] unless it is a DAQ cassette.
pub fn replay_daq(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    let transport = ReplayTransport::new(cassette, faults)?;
    let mut calls = Vec::new();
    let mut blocks = Vec::new();
    let mut driver = match DaqDriver::open(transport, DriverSettings::default()) {
        Ok(driver) => {
            calls.push(CallOutcome { call: "open".into(), result: Ok(format!("{:?}", driver.identity())) });
            driver
        }
        Err(e) => {
            calls.push(CallOutcome { call: "open".into(), result: Err(e.to_string()) });
            // Without an open driver there is nothing more to replay; the transport went with the failed open.
            let probe = ReplayTransport::new(cassette, ReplayFaults::none())?;
            return Ok(SessionReport {
                device: DeviceKind::DaqUsb,
                records: cassette.records.len(),
                calls,
                blocks,
                retries: 0,
                stats: probe.stats().clone(),
                mismatch: None,
                finished: false,
            });
        }
    };
    let mut previous: Option<HostCommand> = Some(HostCommand::GetInfo);
    for bytes in recorded_writes(cassette).iter().skip(1) {
        let mut decoder = DeviceDecoder::new();
        decoder.push(bytes);
        let Some(Ok(frame)) = decoder.poll() else { continue };
        let command = frame.message;
        if previous.as_ref() == Some(&command) {
            continue;
        }
        previous = Some(command.clone());
        let (call, result) = match &command {
            HostCommand::Configure(wire) => ("configure", driver.configure(&daq_config(wire)).map(|()| "ok".into())),
            HostCommand::Start => ("start", driver.start().map(|()| "ok".into())),
            HostCommand::Stop => ("stop", driver.stop().map(|()| "ok".into())),
            HostCommand::GetInfo | HostCommand::Reset => continue,
        };
        let started = matches!(command, HostCommand::Start) && result.is_ok();
        calls.push(CallOutcome { call: call.into(), result: result.map_err(|e| e.to_string()) });
        if started {
            while driver.transport().next_is_read() && driver.transport().mismatch().is_none() {
                let result = driver.read_block();
                if let Ok(block) = &result {
                    let frames = block.volts.first().map_or(0, Vec::len);
                    let (first_sample_index, integrity) = (block.first_sample_index, block.integrity);
                    blocks.push(BlockSummary { first_sample_index, frames, integrity });
                }
                let result = result.map(|b| format!("{} frames", b.volts.first().map_or(0, Vec::len)));
                calls.push(CallOutcome { call: "read_block".into(), result: result.map_err(|e| e.to_string()) });
            }
        }
        if driver.transport().mismatch().is_some() {
            break;
        }
    }
    let transport = driver.transport();
    Ok(SessionReport {
        device: DeviceKind::DaqUsb,
        records: cassette.records.len(),
        calls,
        blocks,
        retries: driver.stats().retries,
        stats: transport.stats().clone(),
        mismatch: transport.mismatch().cloned(),
        finished: transport.is_finished(),
    })
}

/// Why a demo recording failed.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// Writing the cassette failed.
    #[error(transparent)]
    Record(#[from] RecordError),
    /// The mock device or the driver failed (a bug: the demo sessions have no faults).
    #[error("demo session failed: {0}")]
    Session(String),
}

fn session_error(e: impl std::fmt::Display) -> DemoError {
    DemoError::Session(e.to_string())
}

/// The speckle and noise of the demo LDV.
pub fn demo_ldv_spec() -> LdvSpec {
    LdvSpec {
        noise_rms_m_s: 1e-6,
        speckle_mean_level: 0.7,
        speckle_spread: 0.2,
        dropout_probability: 0.0,
        max_velocity_m_s: 0.25,
        aim_error_rms_m: 0.0,
    }
}

/// Records a short LDV session against the mock controller (seed 11, serial `SN04512`, its virtual clock
/// timing the records) into `out`: identify, laser on, velocity range for 0.1 m/s, medium tracking, then two
/// points (move, signal level), laser off. Returns the calls' results.
///
/// # Errors
/// [`DemoError`].
pub fn record_mock_ldv<W: Write + Send>(out: W) -> Result<Vec<CallOutcome>, DemoError> {
    let controller = MockController::new(&demo_ldv_spec(), 11, "SN04512").map_err(session_error)?;
    let clock = Arc::new(VirtualClock::new());
    let device = Arc::new(Mutex::new(MockDevice::new(controller, LdvFaults::none()).with_clock(clock.clone())));
    let identity = DeviceIdentity {
        vendor: "Ometron".into(),
        model: "8330".into(),
        serial: "SN04512".into(),
        firmware: "2.14".into(),
    };
    let header = Header { device_kind: DeviceKind::LdvSerial, identity, start_unix_ns: 0 };
    let recorder = Recorder::start(out, &header, clock.clone())?;
    let line = RecordingLine::new(MockLine::new(device), recorder.clone());
    let mut ldv = LdvDriver::new(line, clock, RetryPolicy::default()).map_err(session_error)?;
    let mut calls = Vec::new();
    let mut push = |call: &str, result: Result<String, String>| calls.push(CallOutcome { call: call.into(), result });
    push("identify", ldv.identify().map(|id| format!("{id:?}")).map_err(|e| e.to_string()));
    push("set_laser(on)", ldv.set_laser(true).map(|()| "ok".into()).map_err(|e| e.to_string()));
    push("set_velocity_range(0.1)", ldv.set_velocity_range(0.1).map(|s| format!("{s:?}")).map_err(|e| e.to_string()));
    push("set_tracking(medium)", ldv.set_tracking(Tracking::Medium).map(|()| "ok".into()).map_err(|e| e.to_string()));
    for (x_m, y_m) in [(0.01, 0.02), (-0.03, 0.045)] {
        let moved = ldv.move_to(x_m, y_m).map(|()| "ok".into()).map_err(|e| e.to_string());
        push(&format!("move_to({x_m}, {y_m})"), moved);
        push("signal_level", ldv.signal_level().map(|l| l.to_string()).map_err(|e| e.to_string()));
    }
    push("set_laser(off)", ldv.set_laser(false).map(|()| "ok".into()).map_err(|e| e.to_string()));
    recorder.finish()?;
    Ok(calls)
}

/// Records a short DAQ session against the mock DAQ (serial `SN0001`; input 0 a 7 V 440 Hz sine, input 3 a
/// 0.8 V 1 kHz sine) into `out`: open, configure two channels at 24 kHz in blocks of 240 samples, start, read
/// `blocks` blocks, stop. Records are timed on the wall clock. Returns the blocks read.
///
/// # Errors
/// [`DemoError`].
pub fn record_mock_daq<W: Write + Send>(out: W, blocks: usize) -> Result<Vec<BlockSummary>, DemoError> {
    let source = |input: u8, first: u64, rate_hz: f64, out: &mut [f64]| {
        let (amplitude_v, freq_hz) = match input {
            0 => (7.0, 440.0),
            3 => (0.8, 1000.0),
            _ => (0.0, 0.0),
        };
        for (i, v) in out.iter_mut().enumerate() {
            let t_s = (first + i as u64) as f64 / rate_hz;
            *v = amplitude_v * (2.0 * std::f64::consts::PI * freq_hz * t_s).sin();
        }
    };
    let device = MockDaq::new(usb6211_info("SN0001"), Box::new(source)).map_err(session_error)?;
    let identity = DeviceIdentity {
        vendor: "metaplate".into(),
        model: "mock-6211".into(),
        serial: "SN0001".into(),
        firmware: "1.0.0".into(),
    };
    let header = Header { device_kind: DeviceKind::DaqUsb, identity, start_unix_ns: 0 };
    let recorder = Recorder::start(out, &header, Arc::new(RealClock::new()))?;
    let transport = RecordingTransport::new(MockTransport::new(device, DaqFaults::none()), recorder.clone());
    let mut daq = DaqDriver::open(transport, DriverSettings::default()).map_err(session_error)?;
    daq.configure(&demo_daq_config()).map_err(session_error)?;
    daq.start().map_err(session_error)?;
    let mut read = Vec::new();
    for _ in 0..blocks {
        let block = daq.read_block().map_err(session_error)?;
        let frames = block.volts.first().map_or(0, Vec::len);
        read.push(BlockSummary { first_sample_index: block.first_sample_index, frames, integrity: block.integrity });
    }
    daq.stop().map_err(session_error)?;
    recorder.finish()?;
    Ok(read)
}

/// The demo DAQ configuration: input 0 at +/-10 V and input 3 at +/-1 V, 24 kHz, 240-sample blocks.
pub fn demo_daq_config() -> DaqConfig {
    DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 3, range_v: 1.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 240,
    }
}

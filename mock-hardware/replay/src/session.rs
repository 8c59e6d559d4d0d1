//! Whole sessions: re-running a recorded LDV or DAQ session through its real driver from the recorded commands
//! alone (what `metaplate replay` does), and recording short demo sessions against the mock devices.

use std::io::Write;
use std::sync::{Arc, Mutex};

use metaplate_cassette::{Cassette, DeviceIdentity, DeviceKind, Header};
use metaplate_core::clock::{RealClock, VirtualClock};
use metaplate_core::daq::{BlockIntegrity, Daq, DaqChannel, DaqConfig};
use metaplate_core::vibrometer::{Tracking, Vibrometer};
use metaplate_daq::{DriverSettings, U6Driver};
use metaplate_ldv::{PolytecConfig, PolytecDriver, RetryPolicy};
use metaplate_mock_daq::{FaultSchedule as DaqFaults, MockTransport, MockU6, u6_info};
use metaplate_mock_ldv::{FaultSchedule as LdvFaults, MockController, MockDevice, MockLine, UnitSpec};
use metaplate_polytec_protocol::{Request, RequestDecoder};
use metaplate_u6_protocol::{Calibration, Command, StreamConfig};

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

/// The requests implied by an LDV recording, one `exchange` each, except a resend (the same request again with
/// no reply recorded since it: a retry the driver will make by itself).
fn ldv_requests(cassette: &Cassette) -> Vec<Request> {
    let mut requests: Vec<Request> = Vec::new();
    let mut answered_since_last = true;
    for step in byte_steps(&cassette.records).0 {
        match step {
            Step::Write { bytes, .. } => {
                let mut decoder = RequestDecoder::new();
                decoder.push(&bytes);
                while let Some(Ok(request)) = decoder.poll() {
                    let resend = !answered_since_last && requests.last() == Some(&request);
                    if !resend {
                        requests.push(request);
                    }
                    answered_since_last = !requests.last().is_some_and(|r| r.verb().expects_reply());
                }
            }
            Step::Read { result: Ok(bytes), .. } if !bytes.is_empty() => answered_since_last = true,
            _ => {}
        }
    }
    requests
}

/// Replays an LDV session: a fresh [`PolytecDriver`] over a [`ReplayLine`], one `exchange` per recorded request.
/// Stops at a mismatch.
///
/// # Errors
/// [`ReplayError::WrongDevice`] unless it is an LDV cassette.
pub fn replay_ldv(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    let line = ReplayLine::new(cassette, faults)?;
    let mut driver = PolytecDriver::new(line, RetryPolicy::default(), PolytecConfig::default())
        .map_err(|e| ReplayError::Io { path: "LDV driver".into(), source: std::io::Error::other(e.to_string()) })?;
    let mut calls = Vec::new();
    for request in ldv_requests(cassette) {
        let result = driver.exchange(&request).map(|reply| reply.unwrap_or_default()).map_err(|e| e.to_string());
        calls.push(CallOutcome { call: format!("exchange({request})"), result });
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

/// The driver configuration a recorded StreamConfig came from: its channels and rate; blocks of one packet's scans
/// (the block length is the host's, not on the wire; it changes how blocks are cut, not the transfers).
fn daq_config(wire: &StreamConfig) -> DaqConfig {
    let n = wire.channels.len().max(1);
    DaqConfig {
        channels: wire.channels.iter().map(|c| DaqChannel { input: c.positive, range_v: c.gain.range_v() }).collect(),
        sample_rate_hz: wire.scan_rate_hz(),
        block_len_samples: u32::from(wire.samples_per_packet) / n as u32,
    }
}

/// Replays a U6 session: `U6Driver::open` (StreamStop, ConfigU6, ReadCal 0-3) over a [`ReplayTransport`], then
/// per recorded command StreamConfig `configure`, StreamStart `start` (then `read_block` while the recording
/// reads), StreamStop `stop`; the same command twice in a row is a retry the driver makes by itself; ConfigU6 and
/// ReadCal (a reopen's) have no driver call of their own and are skipped (the replay then reports the mismatch).
/// Stops at a mismatch.
///
/// # Errors
/// [`ReplayError::WrongDevice`] unless it is a DAQ cassette.
pub fn replay_daq(cassette: &Cassette, faults: ReplayFaults) -> Result<SessionReport, ReplayError> {
    let transport = ReplayTransport::new(cassette, faults)?;
    let mut calls = Vec::new();
    let mut blocks = Vec::new();
    let mut driver = match U6Driver::open(transport, DriverSettings::default()) {
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
    // The opening's commands: StreamStop (before any StreamConfig), ConfigU6, ReadCal.
    let mut previous: Option<Command> = None;
    let mut configured = false;
    for bytes in recorded_writes(cassette) {
        let Ok(command) = Command::decode(&bytes) else { continue };
        if previous.as_ref() == Some(&command) {
            continue;
        }
        previous = Some(command.clone());
        let (call, result) = match &command {
            Command::StreamConfig(wire) => {
                configured = true;
                ("configure", driver.configure(&daq_config(wire)).map(|()| "ok".into()))
            }
            Command::StreamStart => ("start", driver.start().map(|()| "ok".into())),
            Command::StreamStop if configured => ("stop", driver.stop().map(|()| "ok".into())),
            Command::StreamStop | Command::ConfigU6 | Command::ReadMem { .. } => continue,
        };
        let started = matches!(command, Command::StreamStart) && result.is_ok();
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

/// Records a short LDV session against the mock Polytec controller ([`UnitSpec::lab_default`], seed 11, its
/// virtual clock timing the records) into `out`: identify, velocity range for 0.1 m/s, medium tracking, the signal
/// level at two beam spots (the beam put there as an aimer would). Returns the calls' results.
///
/// # Errors
/// [`DemoError`].
pub fn record_mock_ldv<W: Write + Send>(out: W) -> Result<Vec<CallOutcome>, DemoError> {
    let controller = MockController::new(UnitSpec::lab_default(), &metaplate_mock_ldv::quiet_spec(), 11);
    let clock = Arc::new(VirtualClock::new());
    let device = Arc::new(Mutex::new(MockDevice::new(controller, LdvFaults::none()).with_clock(clock.clone())));
    let identity = DeviceIdentity {
        vendor: "Polytec".into(),
        model: "OFV-5000 Vibrometer Controller".into(),
        serial: "not reported over RS-232".into(),
        firmware: "3.4".into(),
    };
    let header = Header { device_kind: DeviceKind::LdvSerial, identity, start_unix_ns: 0 };
    let recorder = Recorder::start(out, &header, clock)?;
    let line = RecordingLine::new(MockLine::new(device.clone()), recorder.clone());
    let mut ldv = PolytecDriver::new(line, RetryPolicy::default(), PolytecConfig::default()).map_err(session_error)?;
    let mut calls = Vec::new();
    let mut push = |call: &str, result: Result<String, String>| calls.push(CallOutcome { call: call.into(), result });
    push("identify", ldv.identify().map(|id| format!("{id:?}")).map_err(|e| e.to_string()));
    push("set_velocity_range(0.1)", ldv.set_velocity_range(0.1).map(|s| format!("{s:?}")).map_err(|e| e.to_string()));
    push("set_tracking(medium)", ldv.set_tracking(Tracking::Medium).map(|()| "ok".into()).map_err(|e| e.to_string()));
    for (x_m, y_m) in [(0.01, 0.02), (-0.03, 0.045)] {
        device
            .lock()
            .map_err(|_| DemoError::Session("the mock LDV lock is poisoned".into()))?
            .controller_mut()
            .set_beam(x_m, y_m);
        push(
            &format!("signal_level at ({x_m}, {y_m})"),
            ldv.signal_level().map(|l| l.to_string()).map_err(|e| e.to_string()),
        );
    }
    recorder.finish()?;
    Ok(calls)
}

/// Records a short DAQ session against the mock U6 (serial [`DEMO_U6_SERIAL`], nominal calibration; AIN0 a 7 V
/// 440 Hz sine, AIN3 a 0.8 V 1 kHz sine) into `out`: open, configure two channels at 24 kHz in blocks of 240
/// scans, start, read `blocks` blocks, stop. Records are timed on the wall clock. Returns the blocks read.
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
    let info = u6_info(DEMO_U6_SERIAL);
    let device = MockU6::new(info, Calibration::nominal(), Box::new(source));
    let identity = DeviceIdentity {
        vendor: "LabJack".into(),
        model: info.model().into(),
        serial: DEMO_U6_SERIAL.to_string(),
        firmware: info.firmware_version(),
    };
    let header = Header { device_kind: DeviceKind::DaqUsb, identity, start_unix_ns: 0 };
    let recorder = Recorder::start(out, &header, Arc::new(RealClock::new()))?;
    let transport = RecordingTransport::new(MockTransport::new(device, DaqFaults::none()), recorder.clone());
    let mut daq = U6Driver::open(transport, DriverSettings::default()).map_err(session_error)?;
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

/// The serial number of the demo sessions' mock U6.
pub const DEMO_U6_SERIAL: u32 = 360_012_345;

/// The demo DAQ configuration: input 0 at +/-10 V and input 3 at +/-1 V, 24 kHz, 240-scan blocks.
pub fn demo_daq_config() -> DaqConfig {
    DaqConfig {
        channels: vec![DaqChannel { input: 0, range_v: 10.0 }, DaqChannel { input: 3, range_v: 1.0 }],
        sample_rate_hz: 24_000.0,
        block_len_samples: 240,
    }
}

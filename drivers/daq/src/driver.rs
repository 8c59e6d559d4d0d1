//! [`DaqDriver`]: the [`Daq`] capability on metaplate's DAQ bulk protocol, over any [`BulkTransport`].
//!
//! Every command is one exchange: send the frame, then read IN transfers until the reply naming the command's
//! sequence number arrives. Replies to other sequence numbers are stale (from an attempt that timed out) and are
//! dropped. An attempt that times out is retried, at most [`DriverSettings::retries`] times; before each retry the
//! driver drains what the device still sends, so a late reply cannot be taken for the new one. Sample packets and
//! notifications that arrive while a command waits are queued for [`Daq::read_block`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use metaplate_core::daq::{BlockIntegrity, Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};
use metaplate_daq_protocol::{
    self as proto, ChannelConfig, Configure, DeviceInfo, DeviceMessage, ErrorCode, ErrorReport, HostCommand,
    HostDecoder, SamplePacket, StopReason, StreamEvent, StreamTracker, encode,
};

use crate::transport::{BulkTransport, TransportError};

/// Timeouts and retry bounds of a [`DaqDriver`].
///
/// Valid range: every duration > 0 (a zero timeout makes every exchange time out), counts >= 1 except `retries`
/// (0 = a single attempt).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriverSettings {
    /// How long one attempt of a command waits for its reply, and one read waits for samples.
    pub timeout: Duration,
    /// Extra attempts after the first, for a command that timed out or stalled, and consecutive empty reads
    /// tolerated by [`Daq::read_block`].
    pub retries: u32,
    /// How long a drain read waits before concluding the device has gone quiet.
    pub drain_timeout: Duration,
    /// The most IN transfers one drain reads (a streaming device never goes quiet).
    pub max_drain_transfers: u32,
    /// The most IN transfers one attempt reads while waiting for its reply (or one `read_block` for a fresh
    /// packet), so that a device streaming without answering cannot hold the driver forever.
    pub max_transfers_per_attempt: u32,
}

impl Default for DriverSettings {
    /// 1 s per attempt, 2 retries; drains of up to 64 transfers, 20 ms each; 4096 transfers per attempt (at 240
    /// samples per packet and 24 kHz, 41 s of samples: far more than any device buffers before it answers).
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(1),
            retries: 2,
            drain_timeout: Duration::from_millis(20),
            max_drain_transfers: 64,
            max_transfers_per_attempt: 4096,
        }
    }
}

/// What the driver has had to cope with since it was opened (for logs and tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DriverStats {
    /// Command attempts repeated after a timeout, stall or corrupted command.
    pub retries: u64,
    /// Replies dropped because they answered an earlier attempt or nothing.
    pub stale_replies: u64,
    /// Frames the decoder rejected (corrupt bytes, CRC mismatches, unknown messages).
    pub decode_errors: u64,
    /// IN transfers read while draining.
    pub drained_transfers: u64,
    /// Successful reopens.
    pub reopens: u64,
}

/// The running acquisition, host side.
#[derive(Debug)]
struct Stream {
    tracker: StreamTracker,
    /// Losses seen since the last block returned (charged to the next one).
    pending: BlockIntegrity,
    /// A fault the device reported without `of_seq` (a `Stopped` follows it).
    fault: Option<ErrorReport>,
}

/// A DAQ that speaks metaplate's bulk protocol, behind transport `T`.
#[derive(Debug)]
pub struct DaqDriver<T: BulkTransport> {
    transport: T,
    settings: DriverSettings,
    decoder: HostDecoder,
    next_seq: u32,
    info: DeviceInfo,
    identity: DaqIdentity,
    config: Option<Configure>,
    stream: Option<Stream>,
    /// Stream messages (samples, `Stopped`, faults) received while a command waited, in arrival order.
    inbox: VecDeque<DeviceMessage>,
    stats: DriverStats,
}

fn transport_error(e: TransportError) -> DaqError {
    match e {
        TransportError::Disconnected(detail) => DaqError::Disconnected { detail },
        TransportError::Timeout | TransportError::Stall => DaqError::Timeout { what: "a transfer".into(), attempts: 1 },
        TransportError::Other(detail) => DaqError::Unavailable { detail },
    }
}

fn device_error(report: &ErrorReport) -> DaqError {
    DaqError::Device { code: i64::from(report.code.code()), detail: format!("{}: {}", report.code, report.detail) }
}

fn protocol_error(e: proto::DaqError) -> DaqError {
    DaqError::Protocol { detail: e.to_string() }
}

fn unexpected(command: &str, reply: &DeviceMessage) -> DaqError {
    DaqError::Protocol { detail: format!("unexpected reply to {command}: {reply:?}") }
}

/// The reply's sequence number, for a message that is a reply.
fn reply_seq(msg: &DeviceMessage) -> Option<u32> {
    match msg {
        DeviceMessage::Info(info) => Some(info.of_seq),
        DeviceMessage::Ack { of_seq } => Some(*of_seq),
        DeviceMessage::Error(report) => report.of_seq,
        DeviceMessage::Samples(_) | DeviceMessage::Stopped { .. } => None,
    }
}

/// Converts a configuration in SI units to the wire's integers, and checks it against the device.
///
/// # Errors
/// [`DaqError::Config`] for a rate that is not a whole number of Hz in `1..=u32::MAX`, a range that is not a
/// whole number of mV (to 1 part in 1e9) in `1..=65535` mV, a block longer than 65535 samples, or anything
/// [`Configure::check`] refuses.
pub fn to_wire(config: &DaqConfig, info: &DeviceInfo) -> Result<Configure, DaqError> {
    let bad = |detail: String| DaqError::Config { detail };
    let rate = config.sample_rate_hz;
    if !(rate.is_finite() && rate >= 1.0 && rate <= f64::from(u32::MAX) && rate.fract() == 0.0) {
        return Err(bad(format!("sample rate {rate} Hz is not a whole number of Hz from 1 to {}", u32::MAX)));
    }
    // Exact: a whole number in u32 range.
    let sample_rate_hz = rate as u32;
    let samples_per_packet = u16::try_from(config.block_len_samples)
        .map_err(|_| bad(format!("block of {} samples exceeds 65535", config.block_len_samples)))?;
    let channels = config
        .channels
        .iter()
        .map(|ch| {
            let mv = ch.range_v * 1000.0;
            let rounded = mv.round();
            // Why a tolerance: 0.2 V * 1000 is 200.00000000000003 in f64.
            if !(mv.is_finite() && (1.0..=f64::from(u16::MAX)).contains(&rounded) && (mv - rounded).abs() <= 1e-9 * mv)
            {
                return Err(bad(format!("range {} V is not a whole number of mV from 1 to 65535", ch.range_v)));
            }
            Ok(ChannelConfig { index: ch.input, range_mv: rounded as u16 })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let wire = Configure { sample_rate_hz, samples_per_packet, channels };
    wire.check(info).map_err(|e| bad(e.to_string()))?;
    Ok(wire)
}

impl<T: BulkTransport> DaqDriver<T> {
    /// Opens the device behind `transport`: drains what it still sends and asks for its identity (`GetInfo`).
    /// Nothing else is sent until [`Daq::configure`], which also stops an acquisition left running.
    ///
    /// # Errors
    /// As every exchange: [`DaqError::Timeout`], [`DaqError::Disconnected`], [`DaqError::Unavailable`],
    /// [`DaqError::Device`], [`DaqError::Protocol`].
    pub fn open(transport: T, settings: DriverSettings) -> Result<Self, DaqError> {
        let mut driver = Self {
            transport,
            settings,
            decoder: HostDecoder::new(),
            next_seq: 0,
            info: DeviceInfo {
                of_seq: 0,
                n_channels: 0,
                max_aggregate_rate_hz: 0,
                ranges_mv: Vec::new(),
                vendor: String::new(),
                model: String::new(),
                serial: String::new(),
                firmware: String::new(),
            },
            identity: DaqIdentity::default(),
            config: None,
            stream: None,
            inbox: VecDeque::new(),
            stats: DriverStats::default(),
        };
        driver.drain()?;
        driver.handshake()?;
        Ok(driver)
    }

    /// The device's capabilities, from its `Info` reply.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The configuration in force, as sent on the wire (`None` before [`Daq::configure`]).
    pub fn wire_config(&self) -> Option<&Configure> {
        self.config.as_ref()
    }

    /// What the driver has coped with so far.
    pub fn stats(&self) -> &DriverStats {
        &self.stats
    }

    /// The transport (for inspection).
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The transport, mutably (for tests that inject faults).
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// `GetInfo`; keeps the identity and capabilities.
    fn handshake(&mut self) -> Result<(), DaqError> {
        let (reply, _) = self.transact(&HostCommand::GetInfo, "GetInfo")?;
        let DeviceMessage::Info(info) = reply else {
            return Err(match &reply {
                DeviceMessage::Error(report) => device_error(report),
                other => unexpected("GetInfo", other),
            });
        };
        self.identity = DaqIdentity {
            vendor: info.vendor.clone(),
            model: info.model.clone(),
            serial: info.serial.clone(),
            firmware: info.firmware.clone(),
        };
        self.info = info;
        self.stream = None;
        self.inbox.clear();
        Ok(())
    }

    /// Sends `Configure`; a device still running an acquisition the host does not know of (left by an earlier
    /// session, or across a glitch that did not power-cycle it) refuses it, so stop it and send it again.
    fn send_configure(&mut self, wire: &Configure) -> Result<(), DaqError> {
        let command = HostCommand::Configure(wire.clone());
        match self.transact(&command, "Configure")? {
            (DeviceMessage::Ack { .. }, _) => Ok(()),
            (DeviceMessage::Error(report), _) if report.code == ErrorCode::AlreadyRunning => {
                self.command_ack(&HostCommand::Stop, "Stop")?;
                self.drain()?;
                self.command_ack(&command, "Configure").map(|_| ())
            }
            (DeviceMessage::Error(report), _) => Err(device_error(&report)),
            (other, _) => Err(unexpected("Configure", &other)),
        }
    }

    /// Sends a command that is answered by `Ack`.
    fn command_ack(&mut self, command: &HostCommand, what: &str) -> Result<u32, DaqError> {
        let (reply, attempts) = self.transact(command, what)?;
        match reply {
            DeviceMessage::Ack { .. } => Ok(attempts),
            DeviceMessage::Error(report) => Err(device_error(&report)),
            other => Err(unexpected(what, &other)),
        }
    }

    /// One command exchange with bounded retries: its reply and the number of attempts it took.
    fn transact(&mut self, command: &HostCommand, what: &str) -> Result<(DeviceMessage, u32), DaqError> {
        let attempts = self.settings.retries.saturating_add(1);
        for attempt in 1..=attempts {
            if attempt > 1 {
                self.stats.retries += 1;
                // A late reply to the previous attempt must not be read as this one's (the sequence numbers
                // already tell them apart; draining also keeps the decoder from holding a torn frame).
                self.drain()?;
            }
            let seq = self.next_seq;
            self.next_seq = seq.wrapping_add(1);
            let bytes = encode(seq, command).map_err(protocol_error)?;
            match self.transport.write(&bytes, self.settings.timeout) {
                Ok(()) => {}
                Err(TransportError::Timeout | TransportError::Stall) => continue,
                Err(e) => return Err(transport_error(e)),
            }
            match self.await_reply(seq)? {
                // The device could not read our frame (CRC): send it again.
                Some(DeviceMessage::Error(report))
                    if report.of_seq.is_none() && report.code == ErrorCode::MalformedCommand => {}
                Some(reply) => return Ok((reply, attempt)),
                None => {}
            }
        }
        Err(DaqError::Timeout { what: format!("reply to {what}"), attempts })
    }

    /// Reads until the reply to `seq` arrives (`Some`), or the attempt times out (`None`).
    fn await_reply(&mut self, seq: u32) -> Result<Option<DeviceMessage>, DaqError> {
        let deadline = Instant::now() + self.settings.timeout;
        for _ in 0..self.settings.max_transfers_per_attempt {
            if let Some(reply) = self.route_decoded(Some(seq)) {
                return Ok(Some(reply));
            }
            let remaining = deadline.saturating_duration_since(Instant::now());
            if remaining.is_zero() {
                return Ok(None);
            }
            match self.transport.read(remaining) {
                Ok(bytes) => self.decoder.push(&bytes),
                Err(TransportError::Timeout | TransportError::Stall) => return Ok(None),
                Err(e) => return Err(transport_error(e)),
            }
        }
        Ok(self.route_decoded(Some(seq)))
    }

    /// Decodes what is buffered and routes each message: the reply to `awaiting` is returned (frames behind it
    /// stay buffered); stream messages go to the inbox while an acquisition runs; anything else is stale.
    fn route_decoded(&mut self, awaiting: Option<u32>) -> Option<DeviceMessage> {
        while let Some(result) = self.decoder.poll() {
            let msg = match result {
                Ok(frame) => frame.message,
                Err(_) => {
                    self.stats.decode_errors += 1;
                    continue;
                }
            };
            let seq = reply_seq(&msg);
            if seq.is_some() && seq == awaiting {
                return Some(msg);
            }
            match &msg {
                DeviceMessage::Error(report) if report.of_seq.is_none() => {
                    if report.code == ErrorCode::MalformedCommand && awaiting.is_some() {
                        return Some(msg);
                    }
                    if self.stream.is_some() {
                        self.inbox.push_back(msg);
                    } else {
                        self.stats.stale_replies += 1;
                    }
                }
                DeviceMessage::Samples(_) | DeviceMessage::Stopped { .. } if self.stream.is_some() => {
                    self.inbox.push_back(msg);
                }
                _ => self.stats.stale_replies += 1,
            }
        }
        None
    }

    /// Reads until the device goes quiet (or the drain bound), routing what arrives, then forgets any torn frame.
    fn drain(&mut self) -> Result<(), DaqError> {
        for _ in 0..self.settings.max_drain_transfers {
            self.route_decoded(None);
            match self.transport.read(self.settings.drain_timeout) {
                Ok(bytes) => {
                    self.stats.drained_transfers += 1;
                    self.decoder.push(&bytes);
                }
                Err(TransportError::Timeout | TransportError::Stall) => break,
                Err(e) => return Err(transport_error(e)),
            }
        }
        self.route_decoded(None);
        self.decoder.clear();
        Ok(())
    }

    /// Handles one stream message during `read_block`: a block for a fresh packet, an error for the end of the
    /// stream, `None` to keep reading.
    fn on_stream_message(&mut self, msg: DeviceMessage) -> Result<Option<DaqBlock>, DaqError> {
        let Some(stream) = self.stream.as_mut() else {
            return Err(DaqError::Protocol { detail: "no acquisition is running".into() });
        };
        match msg {
            DeviceMessage::Samples(packet) => on_packet(stream, &packet),
            DeviceMessage::Error(report) => {
                stream.fault = Some(report);
                Ok(None)
            }
            DeviceMessage::Stopped { reason, next_packet_seq } => {
                stream.tracker.finish(next_packet_seq);
                let fault = stream.fault.take();
                self.stream = None;
                let detail = fault.map_or_else(|| format!("device stopped ({reason:?})"), |f| f.detail);
                Err(match reason {
                    StopReason::BufferOverrun => DaqError::Overrun { detail },
                    StopReason::HardwareFault => {
                        DaqError::Device { code: i64::from(ErrorCode::HardwareFault.code()), detail }
                    }
                    StopReason::HostRequest | StopReason::Reset => {
                        DaqError::Protocol { detail: format!("acquisition ended unexpectedly: {detail}") }
                    }
                })
            }
            other => Err(unexpected("the sample stream", &other)),
        }
    }
}

/// Tracks one packet: the block it makes if fresh, with the losses charged to it.
fn on_packet(stream: &mut Stream, packet: &SamplePacket) -> Result<Option<DaqBlock>, DaqError> {
    let tracked = stream.tracker.track(packet);
    let mut clipped = false;
    for event in &tracked.events {
        match *event {
            StreamEvent::PacketsLost { count, .. } => stream.pending.packets_lost += u64::from(count),
            StreamEvent::Overrun { .. } => stream.pending.overrun = true,
            StreamEvent::Discontinuity { expected_index, got_index, packet_seq } => {
                if got_index < expected_index {
                    return Err(DaqError::Protocol {
                        detail: format!(
                            "packet {packet_seq}: sample clock went back from {expected_index} to {got_index}"
                        ),
                    });
                }
                stream.pending.samples_missing += got_index - expected_index;
            }
            StreamEvent::Clipped { .. } => clipped = true,
            // Dropped packets: a duplicate loses nothing; a late or malformed one was (or will be) counted lost
            // by the packet sequence of the next fresh packet.
            StreamEvent::Duplicate { .. } | StreamEvent::OutOfOrder { .. } | StreamEvent::WrongShape { .. } => {}
        }
    }
    if !tracked.fresh {
        return Ok(None);
    }
    let volts = stream.tracker.volts(packet).map_err(protocol_error)?;
    let mut integrity = std::mem::take(&mut stream.pending);
    integrity.clipped = clipped;
    Ok(Some(DaqBlock { first_sample_index: packet.first_sample_index, volts, integrity }))
}

impl<T: BulkTransport> Daq for DaqDriver<T> {
    fn identity(&self) -> &DaqIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if self.stream.is_some() {
            return Err(DaqError::Protocol { detail: "cannot configure while an acquisition runs".into() });
        }
        let wire = to_wire(config, &self.info)?;
        self.send_configure(&wire)?;
        self.config = Some(wire);
        Ok(())
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.stream.is_some() {
            return Err(DaqError::Protocol { detail: "an acquisition is already running".into() });
        }
        let Some(config) = &self.config else {
            return Err(DaqError::Protocol { detail: "start before configure".into() });
        };
        let tracker = StreamTracker::new(config).map_err(protocol_error)?;
        self.inbox.clear();
        // Set before sending: samples may follow the Ack in the same transfer.
        self.stream = Some(Stream { tracker, pending: BlockIntegrity::default(), fault: None });
        match self.transact(&HostCommand::Start, "Start") {
            Ok((DeviceMessage::Ack { .. }, _)) => Ok(()),
            // The Ack of an earlier attempt was lost, but that attempt started the acquisition.
            Ok((DeviceMessage::Error(report), attempts))
                if attempts > 1 && report.code == ErrorCode::AlreadyRunning =>
            {
                Ok(())
            }
            Ok((reply, _)) => {
                self.stream = None;
                Err(match &reply {
                    DeviceMessage::Error(report) => device_error(report),
                    other => unexpected("Start", other),
                })
            }
            Err(e) => {
                self.stream = None;
                Err(e)
            }
        }
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        if self.stream.is_none() {
            return Err(DaqError::Protocol { detail: "read_block while no acquisition runs".into() });
        }
        let mut quiet_reads = 0u32;
        let max_transfers =
            u64::from(self.settings.max_transfers_per_attempt) * u64::from(self.settings.retries.saturating_add(1));
        let mut transfers = 0u64;
        loop {
            while let Some(msg) = self.inbox.pop_front() {
                if let Some(block) = self.on_stream_message(msg)? {
                    return Ok(block);
                }
            }
            self.route_decoded(None);
            if !self.inbox.is_empty() {
                continue;
            }
            if transfers >= max_transfers {
                return Err(DaqError::Timeout { what: "fresh samples".into(), attempts: quiet_reads + 1 });
            }
            transfers += 1;
            match self.transport.read(self.settings.timeout) {
                Ok(bytes) => self.decoder.push(&bytes),
                Err(TransportError::Timeout | TransportError::Stall) => {
                    quiet_reads += 1;
                    if quiet_reads > self.settings.retries {
                        return Err(DaqError::Timeout { what: "samples".into(), attempts: quiet_reads });
                    }
                }
                Err(e) => return Err(transport_error(e)),
            }
        }
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        let result = self.command_ack(&HostCommand::Stop, "Stop");
        if result.is_ok() {
            self.stream = None;
            self.inbox.clear();
        }
        result.map(|_| ())
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.transport.reopen().map_err(transport_error)?;
        self.stream = None;
        self.inbox.clear();
        self.decoder.clear();
        let serial = self.identity.serial.clone();
        self.drain()?;
        self.handshake()?;
        if self.identity.serial != serial {
            return Err(DaqError::Unavailable {
                detail: format!("reopened a different device: serial {} instead of {serial}", self.identity.serial),
            });
        }
        if let Some(wire) = self.config.clone() {
            self.send_configure(&wire)?;
        }
        self.stats.reopens += 1;
        Ok(())
    }
}

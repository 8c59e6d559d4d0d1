//! [`U6Driver`]: the [`Daq`] capability on a LabJack U6, over any [`BulkTransport`].
//!
//! Commands are single exchanges on the command endpoints (User's Guide section 5.2): send the packet, read
//! responses until the one to this command arrives. A response to another command is stale (from an attempt
//! that timed out) and is dropped; `B8 B8` (the device saw a bad checksum) or a corrupted response resends the
//! command. An attempt that times out is retried, at most [`DriverSettings::retries`] times, after draining the
//! response endpoint. Stream data is read from the stream endpoint only by [`Daq::read_block`].
//!
//! Opening reads the identity (ConfigU6: serial number, firmware, U6 or U6-Pro) and the calibration constants
//! (ReadCal blocks 0-3), and stops a stream an earlier session may have left running (as LabJack's
//! `u6Stream.c` example does before configuring).

use std::time::Duration;

use metaplate_core::daq::{Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};
use metaplate_u6_protocol::{
    Calibration, Command, DeviceInfo, Errorcode, PRODUCT_ID, Response, ResponseBody, ScanAssembler, StreamConfig,
    StreamDecoder, StreamStats, U6Error,
};

use crate::blocks::BlockBuilder;
use crate::stream_config::to_stream_config;
use crate::transport::{BulkTransport, TransportError};

/// Timeouts, retry bounds and stream settings of a [`U6Driver`].
///
/// Valid range: every duration > 0 (a zero timeout makes every exchange time out), counts >= 1 except `retries`
/// (0 = a single attempt); `resolution_index` 0-8.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriverSettings {
    /// How long one attempt of a command waits for its response, and one stream read for data.
    pub timeout: Duration,
    /// Extra attempts after the first, for a command that timed out or stalled, and consecutive empty stream reads
    /// tolerated by [`Daq::read_block`].
    pub retries: u32,
    /// How long a drain read waits before concluding an endpoint has gone quiet.
    pub drain_timeout: Duration,
    /// The most IN transfers one drain reads per endpoint.
    pub max_drain_transfers: u32,
    /// The most IN transfers one attempt reads while waiting for its response (or one `read_block` while
    /// nothing but stale or corrupt data arrives).
    pub max_transfers_per_attempt: u32,
    /// StreamConfig's ResolutionIndex (0: the default, 1).
    pub resolution_index: u8,
    /// StreamConfig's SettlingFactor (0: the U6 chooses).
    pub settling_factor: u8,
}

impl Default for DriverSettings {
    /// 1 s per attempt, 2 retries; drains of up to 64 transfers, 20 ms each; 4096 transfers per attempt;
    /// resolution index 0 and automatic settling (the guide's usual stream settings).
    fn default() -> Self {
        Self {
            timeout: Duration::from_secs(1),
            retries: 2,
            drain_timeout: Duration::from_millis(20),
            max_drain_transfers: 64,
            max_transfers_per_attempt: 4096,
            resolution_index: 0,
            settling_factor: 0,
        }
    }
}

/// What the driver has had to cope with since it was opened (for logs and tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DriverStats {
    /// Command attempts repeated after a timeout, stall or corrupted exchange.
    pub retries: u64,
    /// Responses dropped because they answered another command.
    pub stale_responses: u64,
    /// Responses and stream bytes the codec rejected (bad checksums, garbage, wrong lengths).
    pub decode_errors: u64,
    /// IN transfers read while draining.
    pub drained_transfers: u64,
    /// Successful reopens.
    pub reopens: u64,
    /// The stream accounting of every acquisition so far (missed packets, auto-recovery, backlog).
    pub stream: StreamStats,
}

/// The running acquisition, host side.
#[derive(Debug)]
struct Stream {
    decoder: StreamDecoder,
    assembler: ScanAssembler,
    blocks: BlockBuilder,
}

/// A LabJack U6 behind transport `T`.
#[derive(Debug)]
pub struct U6Driver<T: BulkTransport> {
    transport: T,
    settings: DriverSettings,
    info: DeviceInfo,
    identity: DaqIdentity,
    calibration: Calibration,
    /// The StreamConfig in force and the block length asked for.
    config: Option<(StreamConfig, usize)>,
    stream: Option<Stream>,
    stats: DriverStats,
}

fn transport_error(e: TransportError) -> DaqError {
    match e {
        TransportError::Disconnected(detail) => DaqError::Disconnected { detail },
        TransportError::Timeout | TransportError::Stall => DaqError::Timeout { what: "a transfer".into(), attempts: 1 },
        TransportError::Other(detail) => DaqError::Unavailable { detail },
    }
}

fn device_error(command: &str, errorcode: Errorcode) -> DaqError {
    DaqError::Device { code: i64::from(errorcode.0), detail: format!("{command} returned {errorcode}") }
}

/// The typed error for a stream errorcode: the overflows (the U6's buffers, a scan overlapping the next, scans
/// lost beyond what auto-recovery counts) as [`DaqError::Overrun`], others as [`DaqError::Device`].
fn stream_error(packet_number: u8, errorcode: Errorcode) -> DaqError {
    let detail = format!("stream packet {packet_number}: {errorcode}");
    match errorcode.0 {
        3 | 4 | 54 | 55 | 63 => DaqError::Overrun { detail },
        _ => DaqError::Device { code: i64::from(errorcode.0), detail },
    }
}

fn protocol_error(e: U6Error) -> DaqError {
    DaqError::Protocol { detail: e.to_string() }
}

impl<T: BulkTransport> U6Driver<T> {
    /// Opens the U6 behind `transport`: drains both IN endpoints, stops a stream left running, reads the identity
    /// (ConfigU6) and the calibration constants (ReadCal blocks 0-3).
    ///
    /// # Errors
    /// As every exchange ([`DaqError::Timeout`], [`DaqError::Disconnected`], [`DaqError::Device`]);
    /// [`DaqError::Unavailable`] for a device that is not a U6 (ProductID) or whose calibration memory holds
    /// implausible constants.
    pub fn open(transport: T, settings: DriverSettings) -> Result<Self, DaqError> {
        let mut driver = Self {
            transport,
            settings,
            info: DeviceInfo::default(),
            identity: DaqIdentity::default(),
            calibration: Calibration::nominal(),
            config: None,
            stream: None,
            stats: DriverStats::default(),
        };
        driver.handshake()?;
        Ok(driver)
    }

    /// The identity ConfigU6 returned.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The calibration constants read from the device.
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// The StreamConfig in force (`None` before [`Daq::configure`]).
    pub fn stream_config(&self) -> Option<&StreamConfig> {
        self.config.as_ref().map(|(c, _)| c)
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

    /// Drains, stops a stream left running, reads identity and calibration.
    fn handshake(&mut self) -> Result<(), DaqError> {
        self.stream = None;
        self.drain(false)?;
        self.drain(true)?;
        self.stop_stream()?;
        self.drain(true)?;
        let response = self.exchange(&Command::ConfigU6)?.0;
        let ResponseBody::ConfigU6(info) = response.body else {
            return Err(DaqError::Protocol { detail: "ConfigU6 answered with another function".into() });
        };
        if info.product_id != PRODUCT_ID {
            return Err(DaqError::Unavailable {
                detail: format!("ConfigU6 reports ProductID {}, not a U6 ({PRODUCT_ID})", info.product_id),
            });
        }
        let mut blocks = [[0u8; 32]; 4];
        for (block, out) in (0u8..).zip(blocks.iter_mut()) {
            let (response, _) = self.exchange(&Command::ReadMem { calibration: true, block })?;
            let ResponseBody::ReadMem { data, .. } = response.body else {
                return Err(DaqError::Protocol { detail: "ReadCal answered with another function".into() });
            };
            *out = data;
        }
        self.calibration = Calibration::from_blocks(&blocks)
            .map_err(|e| DaqError::Unavailable { detail: format!("U6 {}: calibration memory: {e}", info.serial) })?;
        self.identity = DaqIdentity {
            vendor: "LabJack".into(),
            model: info.model().into(),
            serial: info.serial.to_string(),
            firmware: info.firmware_version(),
        };
        self.info = info;
        Ok(())
    }

    /// StreamStop, accepting errorcode 52 (`STREAM_NOT_RUNNING`): afterwards no stream runs.
    fn stop_stream(&mut self) -> Result<(), DaqError> {
        let (response, _) = self.exchange(&Command::StreamStop)?;
        match response.errorcode {
            Errorcode::OK | Errorcode::STREAM_NOT_RUNNING => Ok(()),
            e => Err(device_error("StreamStop", e)),
        }
    }

    /// Sends StreamConfig; a stream still running (errorcode 48, `STREAM_IS_ACTIVE`) is stopped and the
    /// configuration sent again.
    fn send_stream_config(&mut self, config: &StreamConfig) -> Result<(), DaqError> {
        let command = Command::StreamConfig(config.clone());
        let mut errorcode = self.exchange(&command)?.0.errorcode;
        if errorcode == Errorcode::STREAM_IS_ACTIVE {
            self.stop_stream()?;
            self.drain(true)?;
            errorcode = self.exchange(&command)?.0.errorcode;
        }
        if errorcode.is_ok() { Ok(()) } else { Err(device_error("StreamConfig", errorcode)) }
    }

    /// One command exchange with bounded retries: its response and the number of attempts it took.
    fn exchange(&mut self, command: &Command) -> Result<(Response, u32), DaqError> {
        let bytes = command.encode().map_err(protocol_error)?;
        let attempts = self.settings.retries.saturating_add(1);
        for attempt in 1..=attempts {
            if attempt > 1 {
                self.stats.retries += 1;
                // A late response to the previous attempt must not be taken for this one's.
                self.drain(false)?;
            }
            match self.transport.write(&bytes, self.settings.timeout) {
                Ok(()) => {}
                Err(TransportError::Timeout | TransportError::Stall) => continue,
                Err(e) => return Err(transport_error(e)),
            }
            if let Some(response) = self.await_response(command)? {
                return Ok((response, attempt));
            }
        }
        Err(DaqError::Timeout { what: format!("response to {}", command.name()), attempts })
    }

    /// Reads until the response to `command` arrives (`Some`), or the attempt ends (`None`: timed out, or the
    /// command must be sent again).
    fn await_response(&mut self, command: &Command) -> Result<Option<Response>, DaqError> {
        for _ in 0..self.settings.max_transfers_per_attempt {
            let bytes = match self.transport.read(self.settings.timeout) {
                Ok(bytes) => bytes,
                Err(TransportError::Timeout | TransportError::Stall) => return Ok(None),
                Err(e) => return Err(transport_error(e)),
            };
            match Response::decode_for(command, &bytes) {
                Ok(response) => return Ok(Some(response)),
                Err(U6Error::UnexpectedCommandBytes { .. }) => self.stats.stale_responses += 1,
                // The device could not read the command, or its response was corrupted: send it again.
                Err(_) => {
                    self.stats.decode_errors += 1;
                    return Ok(None);
                }
            }
        }
        Ok(None)
    }

    /// Reads an IN endpoint (the stream endpoint if `stream`) until it goes quiet or the drain bound, discarding
    /// what arrives.
    fn drain(&mut self, stream: bool) -> Result<(), DaqError> {
        let max_len = self.stream_read_len();
        for _ in 0..self.settings.max_drain_transfers {
            let result = if stream {
                self.transport.read_stream(max_len, self.settings.drain_timeout)
            } else {
                self.transport.read(self.settings.drain_timeout)
            };
            match result {
                Ok(_) => self.stats.drained_transfers += 1,
                Err(TransportError::Timeout | TransportError::Stall) => break,
                Err(e) => return Err(transport_error(e)),
            }
        }
        Ok(())
    }

    /// Bytes asked for per stream read: the packets of one block (of one largest packet before configuration). A
    /// U6 ends a transfer at a packet shorter than 64 bytes, so it may send fewer; the mock U6 digitises what is
    /// asked for at once, so the mock lab's clock moves a block per read.
    fn stream_read_len(&self) -> usize {
        let Some((config, block_len)) = &self.config else {
            return metaplate_u6_protocol::packet_len(25);
        };
        let scans_per_packet = usize::from(config.samples_per_packet) / config.channels.len().max(1);
        // At most 4096 packets (a block of 100 k scans at 25 samples per packet): a bounded buffer.
        let packets = block_len.div_ceil(scans_per_packet.max(1)).clamp(1, 4096);
        packets * metaplate_u6_protocol::packet_len(config.samples_per_packet)
    }

    /// Adds the running stream's counters to the driver's.
    fn end_stream(&mut self) {
        if let Some(stream) = self.stream.take() {
            let s = stream.assembler.stats();
            let total = &mut self.stats.stream;
            total.packets += s.packets;
            total.packets_missed += s.packets_missed;
            total.scans_discarded += s.scans_discarded;
            total.autorecover_packets += s.autorecover_packets;
            total.stale_packets += s.stale_packets;
            total.max_backlog = total.max_backlog.max(s.max_backlog);
        }
    }
}

impl<T: BulkTransport> Daq for U6Driver<T> {
    fn identity(&self) -> &DaqIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if self.stream.is_some() {
            return Err(DaqError::Protocol { detail: "cannot configure while an acquisition runs".into() });
        }
        let stream = to_stream_config(config, self.settings.resolution_index, self.settings.settling_factor)?;
        self.send_stream_config(&stream)?;
        self.config = Some((stream, config.block_len_samples as usize));
        Ok(())
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.stream.is_some() {
            return Err(DaqError::Protocol { detail: "an acquisition is already running".into() });
        }
        let Some((config, block_len)) = &self.config else {
            return Err(DaqError::Protocol { detail: "start before configure".into() });
        };
        let assembler = ScanAssembler::new(config, self.calibration).map_err(protocol_error)?;
        let stream = Stream {
            decoder: StreamDecoder::new(config.samples_per_packet),
            assembler,
            blocks: BlockBuilder::new(*block_len, config.channels.len()),
        };
        let (response, attempts) = self.exchange(&Command::StreamStart)?;
        match response.errorcode {
            Errorcode::OK => {}
            // The response of an earlier attempt was lost, but that attempt started the stream.
            Errorcode::STREAM_IS_ACTIVE if attempts > 1 => {}
            e => return Err(device_error("StreamStart", e)),
        }
        self.stream = Some(stream);
        Ok(())
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        let max_len = self.stream_read_len();
        let (timeout, retries) = (self.settings.timeout, self.settings.retries);
        let max_transfers =
            u64::from(self.settings.max_transfers_per_attempt) * u64::from(self.settings.retries.saturating_add(1));
        let (mut quiet_reads, mut transfers) = (0u32, 0u64);
        loop {
            let Some(stream) = self.stream.as_mut() else {
                return Err(DaqError::Protocol { detail: "read_block while no acquisition runs".into() });
            };
            if let Some(block) = stream.blocks.ready() {
                return Ok(block);
            }
            match stream.decoder.poll() {
                Some(Ok(packet)) => match stream.assembler.accept(&packet) {
                    Ok(scans) => {
                        if let Some(block) = stream.blocks.push(scans) {
                            return Ok(block);
                        }
                    }
                    Err(U6Error::StreamError { packet_number, errorcode }) => {
                        self.end_stream();
                        return Err(stream_error(packet_number, errorcode));
                    }
                    Err(e) => {
                        self.end_stream();
                        return Err(protocol_error(e));
                    }
                },
                Some(Err(_)) => self.stats.decode_errors += 1,
                None => {
                    if transfers >= max_transfers {
                        return Err(DaqError::Timeout { what: "fresh samples".into(), attempts: quiet_reads + 1 });
                    }
                    transfers += 1;
                    match self.transport.read_stream(max_len, timeout) {
                        Ok(bytes) => stream.decoder.push(&bytes),
                        Err(TransportError::Timeout | TransportError::Stall) => {
                            quiet_reads += 1;
                            if quiet_reads > retries {
                                return Err(DaqError::Timeout { what: "stream data".into(), attempts: quiet_reads });
                            }
                        }
                        Err(e) => return Err(transport_error(e)),
                    }
                }
            }
        }
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        self.stop_stream()?;
        self.end_stream();
        // Packets the U6 had buffered when it stopped: not part of any block now.
        self.drain(true)
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.transport.reopen().map_err(transport_error)?;
        self.end_stream();
        let serial = self.identity.serial.clone();
        self.handshake()?;
        if self.identity.serial != serial {
            return Err(DaqError::Unavailable {
                detail: format!("reopened a different U6: serial {} instead of {serial}", self.identity.serial),
            });
        }
        if let Some((config, _)) = self.config.clone() {
            self.send_stream_config(&config)?;
        }
        self.stats.reopens += 1;
        Ok(())
    }
}

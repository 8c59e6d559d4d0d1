//! The mock U6's device side: a state machine answering the U6's low-level functions (User's Guide section 5.2)
//! and producing StreamData packets from a caller's signal source, as the guide and LabJackPython's `u6.py`
//! describe the device.
//!
//! Time is fast-forward: stream packets are produced when the host reads the stream endpoint, so the device's scan
//! index is its clock and no wall time passes.
//!
//! Where the guide leaves the device's behaviour open, the mock chooses, and says so: StreamStart before any
//! StreamConfig answers errorcode 50 (`STREAM_CONFIG_INVALID`); a function it does not implement (Feedback,
//! ConfigIO, user memory...) gets no response, or errorcode 26 (`INVALID_BLOCK`) for memory blocks other than
//! calibration blocks 0-3; after an overflow it cannot count (errorcode 63) it stops streaming.

use std::collections::VecDeque;

use metaplate_u6_protocol::{
    BAD_CHECKSUM_RESPONSE, Calibration, Command, DeviceInfo, Errorcode, Response, ResponseBody, StreamConfig,
    StreamPacket, U6Error,
};

/// The analog signal at the device's inputs.
pub trait SignalSource: Send {
    /// Writes the voltage at analog input `input` for scans `first_sample_index ..` (per-channel sample clock, 0
    /// at the stream's start) at `sample_rate_hz` into `out`, V. Voltages beyond the channel's range clip; a
    /// non-finite value is a hardware fault (the device ends the stream with errorcode 63).
    fn fill(&mut self, input: u8, first_sample_index: u64, sample_rate_hz: f64, out: &mut [f64]);
}

impl<F: FnMut(u8, u64, f64, &mut [f64]) + Send> SignalSource for F {
    fn fill(&mut self, input: u8, first_sample_index: u64, sample_rate_hz: f64, out: &mut [f64]) {
        self(input, first_sample_index, sample_rate_hz, out);
    }
}

/// The identity of a U6 (not a Pro) with serial number `serial`: firmware 1.43, bootloader 6.15, hardware 2.00,
/// LocalID 1 (VersionInfo 4, as LabJackPython's `configU6` docstring shows for a U6).
pub fn u6_info(serial: u32) -> DeviceInfo {
    DeviceInfo {
        firmware: (1, 43),
        bootloader: (6, 15),
        hardware: (2, 0),
        serial,
        product_id: metaplate_u6_protocol::PRODUCT_ID,
        local_id: 1,
        version_info: 4,
    }
}

/// A running stream.
#[derive(Debug, Clone, Copy)]
struct Run {
    packet_number: u8,
    /// Index of the next scan to digitise.
    scan_index: u64,
    /// Scans discarded by an overflow not yet reported (errorcode 59 sent, 60 due).
    discarding: Option<u64>,
}

/// The mock U6.
pub struct MockU6 {
    info: DeviceInfo,
    calibration: Calibration,
    source: Box<dyn SignalSource>,
    config: Option<StreamConfig>,
    run: Option<Run>,
    /// Samples digitised, not yet sent (the U6's stream buffer).
    buffer: VecDeque<u16>,
    /// An overflow injected, to report from the next packet on: scans it discards.
    overflow: Option<u64>,
    /// The next packet reports an overflow auto-recovery cannot count (errorcode 63).
    fatal: bool,
    /// Responses waiting on the response endpoint.
    responses: VecDeque<Vec<u8>>,
}

impl std::fmt::Debug for MockU6 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MockU6")
            .field("serial", &self.info.serial)
            .field("config", &self.config)
            .field("run", &self.run)
            .finish_non_exhaustive()
    }
}

impl MockU6 {
    /// A powered-on, unconfigured U6 with identity `info`, calibration memory holding `calibration` (as fixed
    /// point holds it: the device digitises with the constants a host reads back), sampling `source`.
    pub fn new(info: DeviceInfo, calibration: Calibration, source: Box<dyn SignalSource>) -> Self {
        let calibration = Calibration::from_blocks(&calibration.to_blocks()).unwrap_or(calibration);
        Self {
            info,
            calibration,
            source,
            config: None,
            run: None,
            buffer: VecDeque::new(),
            overflow: None,
            fatal: false,
            responses: VecDeque::new(),
        }
    }

    /// The identity ConfigU6 returns.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// The stream configuration in force.
    pub fn config(&self) -> Option<&StreamConfig> {
        self.config.as_ref()
    }

    /// Whether a stream runs.
    pub fn is_running(&self) -> bool {
        self.run.is_some()
    }

    /// The device's scan clock: scans since the running stream started (`None` if idle).
    pub fn scan_index(&self) -> Option<u64> {
        self.run.map(|r| r.scan_index)
    }

    /// Power cycle (a USB disconnect): the stream, configuration, buffer and queued responses are gone.
    pub fn power_cycle(&mut self) {
        self.config = None;
        self.run = None;
        self.buffer.clear();
        self.overflow = None;
        self.fatal = false;
        self.responses.clear();
    }

    /// The stream buffer overflows: the next packet carries errorcode 59 (auto-recovery active, its samples
    /// good), then the buffer's remaining scans and `lost_scans` more (at least 1) are discarded, and the packet
    /// after reports errorcode 60 with the dummy scan and TimeStamp = scans discarded. Nothing happens while idle.
    pub fn overflow(&mut self, lost_scans: u64) {
        if self.run.is_some() {
            self.overflow = Some(lost_scans.max(1));
        }
    }

    /// An overflow too long for auto-recovery to count: the next packet carries errorcode 63
    /// (`STREAM_AUTORECOVER_OVERFLOW`) and the stream ends. Nothing happens while idle.
    pub fn fatal_overflow(&mut self) {
        if self.run.is_some() {
            self.fatal = true;
        }
    }

    /// Takes one OUT transfer (one command) from the host and queues its response.
    pub fn receive(&mut self, bytes: &[u8]) {
        match Command::decode(bytes) {
            Ok(command) => {
                if let Some(response) = self.command(command) {
                    self.responses.push_back(response.encode());
                }
            }
            Err(U6Error::Checksum { .. }) => self.responses.push_back(BAD_CHECKSUM_RESPONSE.to_vec()),
            // No response to a function the mock does not implement (see the module documentation).
            Err(_) => {}
        }
    }

    /// The next response on the response endpoint, `None` when none is waiting.
    pub fn next_response(&mut self) -> Option<Vec<u8>> {
        self.responses.pop_front()
    }

    /// The next stream-endpoint transfer: up to `max_packets` StreamData packets (at least 1), or `None` while no
    /// stream runs.
    pub fn next_stream_transfer(&mut self, max_packets: usize) -> Option<Vec<u8>> {
        let spp = usize::from(self.config.as_ref()?.samples_per_packet);
        let mut out = Vec::new();
        for _ in 0..max_packets.max(1) {
            if self.run.is_none() {
                break;
            }
            // Digitise the transfer's scans in one pass over the source (the lab's signals are cheaper in runs).
            let want = spp * max_packets.max(1);
            if self.buffer.len() < spp {
                self.digitise(want.saturating_sub(self.buffer.len()));
            }
            match self.next_packet() {
                Some(packet) => out.extend(packet),
                None => break,
            }
        }
        (!out.is_empty()).then_some(out)
    }

    fn command(&mut self, command: Command) -> Option<Response> {
        let reply = |errorcode: Errorcode, body| Some(Response { errorcode, body });
        match command {
            Command::ConfigU6 => reply(Errorcode::OK, ResponseBody::ConfigU6(self.info)),
            Command::ReadMem { calibration: true, block } if block < 4 => {
                let data = self.calibration.to_blocks()[usize::from(block)];
                reply(Errorcode::OK, ResponseBody::ReadMem { calibration: true, data })
            }
            Command::ReadMem { calibration, .. } => {
                reply(Errorcode::INVALID_BLOCK, ResponseBody::ReadMem { calibration, data: [0; 32] })
            }
            Command::StreamConfig(_) if self.run.is_some() => {
                reply(Errorcode::STREAM_IS_ACTIVE, ResponseBody::StreamConfig)
            }
            Command::StreamConfig(config) => {
                let errorcode = match config.check() {
                    Ok(()) => {
                        self.config = Some(config);
                        Errorcode::OK
                    }
                    Err(U6Error::ConfigRejected { errorcode, .. }) => errorcode,
                    Err(_) => Errorcode::STREAM_CONFIG_INVALID,
                };
                reply(errorcode, ResponseBody::StreamConfig)
            }
            Command::StreamStart if self.run.is_some() => reply(Errorcode::STREAM_IS_ACTIVE, ResponseBody::StreamStart),
            Command::StreamStart if self.config.is_none() => {
                reply(Errorcode::STREAM_CONFIG_INVALID, ResponseBody::StreamStart)
            }
            Command::StreamStart => {
                self.run = Some(Run { packet_number: 0, scan_index: 0, discarding: None });
                self.buffer.clear();
                reply(Errorcode::OK, ResponseBody::StreamStart)
            }
            Command::StreamStop if self.run.is_none() => reply(Errorcode::STREAM_NOT_RUNNING, ResponseBody::StreamStop),
            Command::StreamStop => {
                // Fast-forward: nothing is buffered beyond what was read, so nothing follows the stop.
                self.end_run();
                reply(Errorcode::OK, ResponseBody::StreamStop)
            }
        }
    }

    fn end_run(&mut self) {
        self.run = None;
        self.buffer.clear();
        self.overflow = None;
        self.fatal = false;
    }

    /// Digitises whole scans holding at least `samples` samples into the buffer.
    fn digitise(&mut self, samples: usize) {
        let (Some(run), Some(config)) = (self.run.as_mut(), self.config.as_ref()) else { return };
        let n = config.channels.len();
        let scans = samples.div_ceil(n.max(1));
        let rate_hz = config.scan_rate_hz();
        let mut per_channel = Vec::with_capacity(n);
        let mut volts = vec![0.0; scans];
        for ch in &config.channels {
            self.source.fill(ch.positive, run.scan_index, rate_hz, &mut volts);
            let codes: Result<Vec<u16>, U6Error> =
                volts.iter().map(|&v| self.calibration.code(ch.gain, v).map(|(code, _)| code)).collect();
            match codes {
                Ok(codes) => per_channel.push(codes),
                Err(_) => {
                    // A non-finite input: the mock's stand-in for a hardware fault.
                    self.fatal = true;
                    return;
                }
            }
        }
        for i in 0..scans {
            self.buffer.extend(per_channel.iter().map(|codes| codes[i]));
        }
        run.scan_index += scans as u64;
    }

    /// The next packet from the buffer (with the overflow reports due), `None` if the stream ended.
    fn next_packet(&mut self) -> Option<Vec<u8>> {
        let config = self.config.as_ref()?;
        let (spp, n) = (usize::from(config.samples_per_packet), config.channels.len().max(1));
        let run = self.run.as_mut()?;
        let number = run.packet_number;
        run.packet_number = number.wrapping_add(1);
        let discarding = run.discarding.take();
        let mut packet = StreamPacket {
            timestamp: 0,
            packet_number: number,
            errorcode: Errorcode::OK,
            samples: Vec::new(),
            backlog: 0,
        };
        if self.fatal {
            return self.fatal_packet(packet, spp);
        }
        if let Some(lost) = self.overflow.take() {
            // The buffer is full: this packet goes out flagged; what stays buffered is discarded with `lost` more.
            packet.errorcode = Errorcode::STREAM_AUTORECOVER_ACTIVE;
            packet.backlog = 255;
            if let Some(run) = self.run.as_mut() {
                run.discarding = Some(lost);
            }
        } else if let Some(lost) = discarding {
            let buffered_scans = (self.buffer.len() / n) as u64;
            self.buffer.clear();
            if let Some(run) = self.run.as_mut() {
                run.scan_index += lost;
            }
            packet.errorcode = Errorcode::STREAM_AUTORECOVER_REPORT;
            // TimeStamp: every scan slot between the last one sent and the first one after, the dummy's included.
            packet.timestamp = u32::try_from(buffered_scans + lost).unwrap_or(u32::MAX);
            packet.samples = vec![0xffff; n.min(spp)];
        }
        let want = spp - packet.samples.len();
        if self.buffer.len() < want {
            self.digitise(want - self.buffer.len());
        }
        if self.fatal || self.buffer.len() < want {
            // Digitising failed (a non-finite input): report it in this packet.
            return self.fatal_packet(packet, spp);
        }
        packet.samples.extend(self.buffer.drain(..want));
        packet.encode().ok()
    }

    /// `packet` as the report of an overflow auto-recovery cannot count (errorcode 63); the stream ends.
    fn fatal_packet(&mut self, mut packet: StreamPacket, spp: usize) -> Option<Vec<u8>> {
        packet.errorcode = Errorcode::STREAM_AUTORECOVER_OVERFLOW;
        packet.samples = vec![0xffff; spp];
        self.end_run();
        packet.encode().ok()
    }
}

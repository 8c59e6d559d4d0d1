//! The mock DAQ's device side: a state machine on [`DeviceDecoder`] that answers commands and produces sample
//! packets from a caller's signal source, following metaplate's DAQ protocol.
//!
//! Time is fast-forward: a packet is produced when the host reads and nothing else is queued, so the device's
//! sample index is its clock and no wall time passes.

use std::collections::VecDeque;

use metaplate_daq_protocol::{
    Configure, DaqError, DeviceDecoder, DeviceInfo, DeviceMessage, ErrorCode, ErrorReport, HostCommand, SampleFlags,
    SamplePacket, StopReason, encode, scale::volts_to_raw,
};

/// The analog signal at the device's inputs.
pub trait SignalSource: Send {
    /// Writes the voltage at analog input `input` for samples `first_sample_index ..` (per-channel sample clock,
    /// 0 at the acquisition's start) at `sample_rate_hz` into `out`, V. Voltages beyond the channel's range clip;
    /// a non-finite value is a hardware fault (the device ends the acquisition).
    fn fill(&mut self, input: u8, first_sample_index: u64, sample_rate_hz: f64, out: &mut [f64]);
}

impl<F: FnMut(u8, u64, f64, &mut [f64]) + Send> SignalSource for F {
    fn fill(&mut self, input: u8, first_sample_index: u64, sample_rate_hz: f64, out: &mut [f64]) {
        self(input, first_sample_index, sample_rate_hz, out);
    }
}

/// The identity and capabilities of a USB-6211 class device (16 inputs, 250 kHz aggregate, +/-10, 5, 1, 0.2 V),
/// as the protocol's documented example, with serial number `serial`.
pub fn usb6211_info(serial: &str) -> DeviceInfo {
    DeviceInfo {
        of_seq: 0,
        n_channels: 16,
        max_aggregate_rate_hz: 250_000,
        ranges_mv: vec![10_000, 5_000, 1_000, 200],
        vendor: "metaplate".into(),
        model: "mock-6211".into(),
        serial: serial.into(),
        firmware: "1.0.0".into(),
    }
}

/// A running acquisition.
#[derive(Debug, Clone, Copy)]
struct Run {
    packet_seq: u32,
    sample_index: u64,
    /// Samples were dropped since the last packet: flag the next one.
    overrun: bool,
}

/// The mock DAQ.
pub struct MockDaq {
    info: DeviceInfo,
    source: Box<dyn SignalSource>,
    decoder: DeviceDecoder,
    out_seq: u32,
    config: Option<Configure>,
    run: Option<Run>,
    /// Encoded frames waiting for the host to read them.
    outbox: VecDeque<Vec<u8>>,
    /// Frames that could not be encoded (a bug of the mock if ever non-zero).
    unencodable: u64,
}

impl std::fmt::Debug for MockDaq {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MockDaq")
            .field("serial", &self.info.serial)
            .field("config", &self.config)
            .field("run", &self.run)
            .finish_non_exhaustive()
    }
}

impl MockDaq {
    /// A powered-on, idle, unconfigured device with identity `info` (its `of_seq` is ignored) sampling `source`.
    ///
    /// # Errors
    /// [`DaqError::Unencodable`] if `info` cannot be sent (a text field over 255 bytes, over 255 ranges).
    pub fn new(info: DeviceInfo, source: Box<dyn SignalSource>) -> Result<Self, DaqError> {
        encode(0, &DeviceMessage::Info(info.clone()))?;
        Ok(Self {
            info,
            source,
            decoder: DeviceDecoder::new(),
            out_seq: 0,
            config: None,
            run: None,
            outbox: VecDeque::new(),
            unencodable: 0,
        })
    }

    /// The configuration in force.
    pub fn config(&self) -> Option<&Configure> {
        self.config.as_ref()
    }

    /// Whether an acquisition runs.
    pub fn is_running(&self) -> bool {
        self.run.is_some()
    }

    /// The device's sample clock: samples per channel since the running acquisition started (`None` if idle).
    pub fn sample_index(&self) -> Option<u64> {
        self.run.map(|r| r.sample_index)
    }

    /// Frames the mock failed to encode (0 unless the mock has a bug).
    pub fn unencodable_frames(&self) -> u64 {
        self.unencodable
    }

    /// Power cycle (a USB disconnect): the acquisition, configuration, queued frames, partial input and frame
    /// counter are gone.
    pub fn power_cycle(&mut self) {
        self.decoder.clear();
        self.out_seq = 0;
        self.config = None;
        self.run = None;
        self.outbox.clear();
    }

    /// The buffer overflows: the next `lost_packets` packets' worth of samples are dropped at the source; the
    /// sample clock keeps counting and the next packet carries the overrun flag. Does nothing while idle.
    pub fn overrun(&mut self, lost_packets: u32) {
        let spp = self.config.as_ref().map_or(0, |c| u64::from(c.samples_per_packet));
        if let Some(run) = self.run.as_mut() {
            run.sample_index += u64::from(lost_packets) * spp;
            run.overrun = true;
        }
    }

    /// An overflow the device cannot recover from: it reports `Error` (buffer overrun) and `Stopped`. Does
    /// nothing while idle.
    pub fn fatal_overrun(&mut self) {
        self.abort(ErrorCode::BufferOverrun, StopReason::BufferOverrun, "sample buffer overflowed");
    }

    /// Takes one OUT transfer from the host and queues the replies.
    pub fn receive(&mut self, bytes: &[u8]) {
        self.decoder.push(bytes);
        while let Some(result) = self.decoder.poll() {
            match result {
                Ok(frame) => self.command(frame.seq, frame.message),
                Err(DaqError::Garbage { .. }) => {}
                // The decoder's errors do not carry the frame's sequence number, so every refusal goes without
                // `of_seq` (the protocol allows that only for a failed CRC: a documented limit of the mock).
                Err(DaqError::UnknownType { .. } | DaqError::VersionMismatch { .. }) => {
                    self.error(None, ErrorCode::UnsupportedCommand, "unsupported command");
                }
                Err(e) => self.error(None, ErrorCode::MalformedCommand, &e.to_string()),
            }
        }
    }

    /// The next IN transfer: queued frames (whole, up to `max_len` bytes, at least one), or else a new sample
    /// packet if running, or `None` when the device has nothing to send.
    pub fn next_transfer(&mut self, max_len: usize) -> Option<Vec<u8>> {
        if self.outbox.is_empty() {
            self.produce_packet();
        }
        let mut out = self.outbox.pop_front()?;
        while let Some(next) = self.outbox.front() {
            if out.len() + next.len() > max_len {
                break;
            }
            out.extend_from_slice(next);
            self.outbox.pop_front();
        }
        Some(out)
    }

    fn send(&mut self, message: &DeviceMessage) {
        match encode(self.out_seq, message) {
            Ok(bytes) => {
                self.outbox.push_back(bytes);
                self.out_seq = self.out_seq.wrapping_add(1);
            }
            Err(_) => self.unencodable += 1,
        }
    }

    fn error(&mut self, of_seq: Option<u32>, code: ErrorCode, detail: &str) {
        // Text fields hold at most 255 bytes: cut on a character boundary.
        let mut end = detail.len().min(255);
        while !detail.is_char_boundary(end) {
            end -= 1;
        }
        self.send(&DeviceMessage::Error(ErrorReport { of_seq, code, detail: detail[..end].into() }));
    }

    fn command(&mut self, seq: u32, command: HostCommand) {
        let ack = DeviceMessage::Ack { of_seq: seq };
        match command {
            HostCommand::GetInfo => {
                let info = DeviceInfo { of_seq: seq, ..self.info.clone() };
                self.send(&DeviceMessage::Info(info));
            }
            HostCommand::Configure(_) if self.run.is_some() => {
                self.error(Some(seq), ErrorCode::AlreadyRunning, "stop first");
            }
            HostCommand::Configure(config) => match config.check(&self.info) {
                Ok(()) => {
                    self.config = Some(config);
                    self.send(&ack);
                }
                Err(DaqError::ConfigRejected { code, reason }) => self.error(Some(seq), code, &reason),
                Err(e) => self.error(Some(seq), ErrorCode::BadConfig, &e.to_string()),
            },
            HostCommand::Start if self.config.is_none() => {
                self.error(Some(seq), ErrorCode::NotConfigured, "configure first");
            }
            HostCommand::Start if self.run.is_some() => self.error(Some(seq), ErrorCode::AlreadyRunning, "running"),
            HostCommand::Start => {
                self.run = Some(Run { packet_seq: 0, sample_index: 0, overrun: false });
                self.send(&ack);
            }
            HostCommand::Stop => {
                // Fast-forward: no sample is buffered, so nothing precedes `Stopped`.
                self.end_run(StopReason::HostRequest);
                self.send(&ack);
            }
            HostCommand::Reset => {
                self.end_run(StopReason::Reset);
                self.config = None;
                self.send(&ack);
            }
        }
    }

    fn end_run(&mut self, reason: StopReason) {
        if let Some(run) = self.run.take() {
            self.send(&DeviceMessage::Stopped { reason, next_packet_seq: run.packet_seq });
        }
    }

    fn abort(&mut self, code: ErrorCode, reason: StopReason, detail: &str) {
        if self.run.is_some() {
            self.error(None, code, detail);
            self.end_run(reason);
        }
    }

    /// Digitises the next packet of the running acquisition into the outbox.
    fn produce_packet(&mut self) {
        let (Some(run), Some(config)) = (self.run, self.config.as_ref()) else { return };
        let spp = usize::from(config.samples_per_packet);
        let n = config.channels.len();
        let rate_hz = f64::from(config.sample_rate_hz);
        let mut samples = vec![0i16; spp * n];
        let mut volts = vec![0.0; spp];
        let mut clipped = false;
        for (pos, ch) in config.channels.iter().enumerate() {
            self.source.fill(ch.index, run.sample_index, rate_hz, &mut volts);
            for (i, &v) in volts.iter().enumerate() {
                match volts_to_raw(v, ch.range_mv) {
                    Ok((code, clip)) => {
                        samples[i * n + pos] = code;
                        clipped |= clip;
                    }
                    Err(_) => {
                        let detail = format!("input {} produced a non-finite voltage", ch.index);
                        self.abort(ErrorCode::HardwareFault, StopReason::HardwareFault, &detail);
                        return;
                    }
                }
            }
        }
        // A configuration accepted by `check` has at most 255 channels.
        let n_channels = u8::try_from(n).unwrap_or(u8::MAX);
        let packet = SamplePacket {
            packet_seq: run.packet_seq,
            first_sample_index: run.sample_index,
            flags: SampleFlags { overrun: run.overrun, clipped },
            n_channels,
            samples,
        };
        self.send(&DeviceMessage::Samples(packet));
        self.run = Some(Run {
            packet_seq: run.packet_seq.wrapping_add(1),
            sample_index: run.sample_index + spp as u64,
            overrun: false,
        });
    }
}

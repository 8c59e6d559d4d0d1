//! Device-to-host messages (bulk IN): replies, sample packets and notifications.

use crate::codes::{ErrorCode, SampleFlags, StopReason};
use crate::error::DaqError;
use crate::frame::{Direction, MAX_PAYLOAD_LEN, Message};
use crate::wire::{Reader, count_u8, put_text, put_u16, put_u32, put_u64};

/// Message type of `Info`.
pub const TYPE_INFO: u8 = 0x81;
/// Message type of `Ack`.
pub const TYPE_ACK: u8 = 0x82;
/// Message type of `Error`.
pub const TYPE_ERROR: u8 = 0x83;
/// Message type of `Samples`.
pub const TYPE_SAMPLES: u8 = 0x84;
/// Message type of `Stopped`.
pub const TYPE_STOPPED: u8 = 0x85;

/// Bytes of a `Samples` payload before the sample values: packet_seq 4, first_sample_index 8, flags 1,
/// n_channels 1, n_samples 2.
pub const SAMPLES_HEADER_LEN: usize = 16;
/// The most i16 values one `Samples` packet carries (channels x samples): 8184.
pub const MAX_SAMPLE_VALUES: usize = (MAX_PAYLOAD_LEN - SAMPLES_HEADER_LEN) / 2;
/// The longest text field, bytes of UTF-8.
pub const MAX_TEXT_LEN: usize = u8::MAX as usize;

/// A message from the device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DeviceMessage {
    /// Reply to `GetInfo`.
    Info(DeviceInfo),
    /// A command was accepted and carried out.
    Ack {
        /// Sequence number of the acknowledged command.
        of_seq: u32,
    },
    /// A command was refused, or a fault happened.
    Error(ErrorReport),
    /// Acquired samples.
    Samples(SamplePacket),
    /// The acquisition ended: no `Samples` follow until the next `Start` is acknowledged.
    Stopped {
        /// Why it ended.
        reason: StopReason,
        /// The `packet_seq` the next packet would have carried: the number of packets sent (modulo 2^32), so the
        /// host can tell whether the last packets were lost.
        next_packet_seq: u32,
    },
}

/// The device's identity and capabilities (payload of `Info`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceInfo {
    /// Sequence number of the `GetInfo` this answers.
    pub of_seq: u32,
    /// Number of analog inputs; valid channel indices are `0..n_channels`.
    pub n_channels: u8,
    /// The highest aggregate rate, Hz: a configuration is accepted when `sample_rate_hz * channels` is at most this
    /// (250000 for a USB-6211 class device).
    pub max_aggregate_rate_hz: u32,
    /// The input ranges offered, mV (+/-range; 10000 = +/-10 V). At most 255.
    pub ranges_mv: Vec<u16>,
    /// Manufacturer (at most 255 bytes of UTF-8, as every text field).
    pub vendor: String,
    /// Model.
    pub model: String,
    /// Serial number.
    pub serial: String,
    /// Firmware version.
    pub firmware: String,
}

/// A refusal or fault reported by the device (payload of `Error`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ErrorReport {
    /// Sequence number of the refused command; `None` for a fault not caused by a command, or for a command frame
    /// whose sequence number could not be trusted (failed CRC).
    pub of_seq: Option<u32>,
    /// What went wrong.
    pub code: ErrorCode,
    /// A human-readable explanation (at most 255 bytes of UTF-8; may be empty).
    pub detail: String,
}

/// One packet of interleaved samples (payload of `Samples`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SamplePacket {
    /// Packet counter of this acquisition: 0 for the first packet after `Start`, +1 per packet sent, wrapping at
    /// 2^32. The device never skips a value, so a gap means packets were lost between device and host.
    pub packet_seq: u32,
    /// The device's sample clock at this packet's first sample: samples per channel since `Start` (0 for the first
    /// sample), the packet's timestamp. The clock keeps counting samples the device lost to an overrun.
    pub first_sample_index: u64,
    /// Overrun and clipping flags.
    pub flags: SampleFlags,
    /// Number of channels, 1 to 255; equal to the configured channel count.
    pub n_channels: u8,
    /// Raw 16-bit codes, interleaved: sample 0 of every channel (in configuration order), then sample 1, and so on.
    /// Length: `n_channels * n_samples` with `n_samples >= 1`, at most [`MAX_SAMPLE_VALUES`] in all.
    pub samples: Vec<i16>,
}

impl SamplePacket {
    /// Samples per channel in this packet (0 if `n_channels` is 0, which does not encode).
    pub fn n_samples(&self) -> usize {
        if self.n_channels == 0 { 0 } else { self.samples.len() / usize::from(self.n_channels) }
    }

    /// The samples of channel position `pos` (position in the configuration, not analog input index), or `None`
    /// if `pos >= n_channels`.
    pub fn channel(&self, pos: usize) -> Option<impl Iterator<Item = i16> + '_> {
        let n = usize::from(self.n_channels);
        (pos < n).then(|| self.samples.iter().skip(pos).step_by(n).copied())
    }

    fn encode(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        let unencodable = |reason: String| DaqError::Unencodable { message: "Samples", reason };
        let n_ch = usize::from(self.n_channels);
        if n_ch == 0 || self.samples.is_empty() || !self.samples.len().is_multiple_of(n_ch) {
            return Err(unencodable(format!(
                "{} values do not make at least one whole sample of {n_ch} channels",
                self.samples.len()
            )));
        }
        if self.samples.len() > MAX_SAMPLE_VALUES {
            return Err(unencodable(format!("{} values, more than {MAX_SAMPLE_VALUES}", self.samples.len())));
        }
        // Fits: n_samples <= MAX_SAMPLE_VALUES < 2^16.
        let n_samples = u16::try_from(self.samples.len() / n_ch)
            .map_err(|_| unencodable("more than 65535 samples per channel".into()))?;
        put_u32(out, self.packet_seq);
        put_u64(out, self.first_sample_index);
        out.push(self.flags.bits());
        out.push(self.n_channels);
        put_u16(out, n_samples);
        for s in &self.samples {
            out.extend_from_slice(&s.to_le_bytes());
        }
        Ok(())
    }

    fn decode(payload: &[u8]) -> Result<Self, DaqError> {
        let mut r = Reader::new("Samples", payload);
        let packet_seq = r.u32()?;
        let first_sample_index = r.u64()?;
        let flags = SampleFlags::from_bits(r.u8()?)?;
        let n_channels = r.u8()?;
        let n_samples = r.u16()?;
        let invalid = |field, value: u8| DaqError::InvalidField {
            message: "Samples",
            field,
            value: u64::from(value),
            reason: "must be at least 1",
        };
        if n_channels == 0 {
            return Err(invalid("n_channels", 0));
        }
        if n_samples == 0 {
            return Err(invalid("n_samples", 0));
        }
        let n_values = usize::from(n_channels) * usize::from(n_samples);
        let expected = SAMPLES_HEADER_LEN + 2 * n_values;
        // Check the length before allocating: n_values is at most 255 * 65535, but the payload bounds it.
        if payload.len() != expected {
            return Err(DaqError::BadPayloadLength {
                message: "Samples",
                len: payload.len(),
                expected: format!("{expected} ({n_channels} channels x {n_samples} samples)"),
            });
        }
        let samples = r.bytes(2 * n_values)?.chunks_exact(2).map(|b| i16::from_le_bytes([b[0], b[1]])).collect();
        r.finish()?;
        Ok(Self { packet_seq, first_sample_index, flags, n_channels, samples })
    }
}

impl DeviceInfo {
    fn encode(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        let n_ranges = count_u8("Info", "ranges", self.ranges_mv.len(), usize::from(u8::MAX))?;
        put_u32(out, self.of_seq);
        out.push(self.n_channels);
        put_u32(out, self.max_aggregate_rate_hz);
        out.push(n_ranges);
        for &r in &self.ranges_mv {
            put_u16(out, r);
        }
        put_text(out, "Info", "vendor", &self.vendor)?;
        put_text(out, "Info", "model", &self.model)?;
        put_text(out, "Info", "serial", &self.serial)?;
        put_text(out, "Info", "firmware", &self.firmware)
    }

    fn decode(payload: &[u8]) -> Result<Self, DaqError> {
        let mut r = Reader::new("Info", payload);
        let of_seq = r.u32()?;
        let n_channels = r.u8()?;
        let max_aggregate_rate_hz = r.u32()?;
        let n_ranges = r.u8()?;
        let ranges_mv = (0..n_ranges).map(|_| r.u16()).collect::<Result<_, _>>()?;
        let info = Self {
            of_seq,
            n_channels,
            max_aggregate_rate_hz,
            ranges_mv,
            vendor: r.text("vendor")?,
            model: r.text("model")?,
            serial: r.text("serial")?,
            firmware: r.text("firmware")?,
        };
        r.finish()?;
        Ok(info)
    }
}

impl ErrorReport {
    fn encode(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        out.push(self.code.code());
        out.push(u8::from(self.of_seq.is_some()));
        put_u32(out, self.of_seq.unwrap_or(0));
        put_text(out, "Error", "detail", &self.detail)
    }

    fn decode(payload: &[u8]) -> Result<Self, DaqError> {
        let mut r = Reader::new("Error", payload);
        let code = ErrorCode::from_code(r.u8()?)?;
        let has_seq = r.u8()?;
        let seq = r.u32()?;
        // One encoding per message: absent means flag 0 and field 0.
        let of_seq = match (has_seq, seq) {
            (0, 0) => None,
            (1, seq) => Some(seq),
            (0, seq) => {
                return Err(DaqError::InvalidField {
                    message: "Error",
                    field: "of_seq",
                    value: u64::from(seq),
                    reason: "must be 0 when has_of_seq is 0",
                });
            }
            (flag, _) => {
                return Err(DaqError::InvalidField {
                    message: "Error",
                    field: "has_of_seq",
                    value: u64::from(flag),
                    reason: "must be 0 or 1",
                });
            }
        };
        let detail = r.text("detail")?;
        r.finish()?;
        Ok(Self { of_seq, code, detail })
    }
}

impl Message for DeviceMessage {
    const DIRECTION: Direction = Direction::DeviceToHost;

    fn msg_type(&self) -> u8 {
        match self {
            DeviceMessage::Info(_) => TYPE_INFO,
            DeviceMessage::Ack { .. } => TYPE_ACK,
            DeviceMessage::Error(_) => TYPE_ERROR,
            DeviceMessage::Samples(_) => TYPE_SAMPLES,
            DeviceMessage::Stopped { .. } => TYPE_STOPPED,
        }
    }

    fn encode_payload(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        match self {
            DeviceMessage::Info(info) => info.encode(out),
            DeviceMessage::Ack { of_seq } => {
                put_u32(out, *of_seq);
                Ok(())
            }
            DeviceMessage::Error(report) => report.encode(out),
            DeviceMessage::Samples(packet) => packet.encode(out),
            DeviceMessage::Stopped { reason, next_packet_seq } => {
                out.push(reason.code());
                put_u32(out, *next_packet_seq);
                Ok(())
            }
        }
    }

    fn decode_payload(msg_type: u8, payload: &[u8]) -> Result<Self, DaqError> {
        match msg_type {
            TYPE_INFO => DeviceInfo::decode(payload).map(DeviceMessage::Info),
            TYPE_ACK => {
                let mut r = Reader::new("Ack", payload);
                let of_seq = r.u32()?;
                r.finish()?;
                Ok(DeviceMessage::Ack { of_seq })
            }
            TYPE_ERROR => ErrorReport::decode(payload).map(DeviceMessage::Error),
            TYPE_SAMPLES => SamplePacket::decode(payload).map(DeviceMessage::Samples),
            TYPE_STOPPED => {
                let mut r = Reader::new("Stopped", payload);
                let reason = StopReason::from_code(r.u8()?)?;
                let next_packet_seq = r.u32()?;
                r.finish()?;
                Ok(DeviceMessage::Stopped { reason, next_packet_seq })
            }
            _ => Err(DaqError::UnknownType { msg_type, direction: Self::DIRECTION }),
        }
    }
}

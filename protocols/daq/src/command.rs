//! Host-to-device commands (bulk OUT) and the configuration check both sides share.

use std::collections::HashSet;

use crate::codes::ErrorCode;
use crate::error::DaqError;
use crate::frame::{Direction, Message};
use crate::reply::{DeviceInfo, MAX_SAMPLE_VALUES};
use crate::wire::{Reader, count_u8, put_u16, put_u32};

/// Message type of `GetInfo`.
pub const TYPE_GET_INFO: u8 = 0x01;
/// Message type of `Configure`.
pub const TYPE_CONFIGURE: u8 = 0x02;
/// Message type of `Start`.
pub const TYPE_START: u8 = 0x03;
/// Message type of `Stop`.
pub const TYPE_STOP: u8 = 0x04;
/// Message type of `Reset`.
pub const TYPE_RESET: u8 = 0x05;

/// A command from the host. The device answers every command with exactly one reply that names the command's
/// sequence number (see the crate documentation for the rules).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HostCommand {
    /// Ask for the device's identity and capabilities; answered by `Info`.
    GetInfo,
    /// Set channels, ranges, rate and packet size for the next acquisitions; answered by `Ack` or `Error`.
    Configure(Configure),
    /// Start acquiring with the current configuration; answered by `Ack`, then `Samples` stream.
    Start,
    /// Stop acquiring; the device sends its last `Samples`, then `Stopped`, then the `Ack`.
    Stop,
    /// Stop any acquisition and forget the configuration; answered by `Ack` (after `Stopped` if one was running).
    Reset,
}

/// One acquired channel: which analog input, with which range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ChannelConfig {
    /// Analog input index, 0 to `DeviceInfo::n_channels - 1`.
    pub index: u8,
    /// Input range, mV: the channel measures `-range_mv .. +range_mv` (10000 for +/-10 V). Must be one of the
    /// device's `DeviceInfo::ranges_mv`.
    pub range_mv: u16,
}

impl ChannelConfig {
    /// The range, V.
    pub fn range_v(self) -> f64 {
        f64::from(self.range_mv) / 1000.0
    }
}

/// The acquisition configuration (payload of `Configure`).
///
/// Any value of the fields encodes; which values a device accepts is decided by [`Configure::check`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Configure {
    /// Per-channel sample rate, Hz (integer: 24000 for the paper). Valid: 1 to
    /// `DeviceInfo::max_aggregate_rate_hz / channels.len()`.
    pub sample_rate_hz: u32,
    /// Samples per channel in each `Samples` packet (the last packet of an acquisition may hold fewer). Valid: 1 to
    /// `MAX_SAMPLE_VALUES / channels.len()`.
    pub samples_per_packet: u16,
    /// The acquired channels, in the order their samples are interleaved in each packet (at most 255).
    pub channels: Vec<ChannelConfig>,
}

impl Configure {
    /// Checks this configuration against a device's capabilities: what the device does before it acknowledges
    /// `Configure`, and what a host may do before sending it.
    ///
    /// # Errors
    /// [`DaqError::ConfigRejected`] with [`ErrorCode::BadConfig`] (no channels, an index the device lacks, a
    /// duplicate index, a range the device does not offer, a packet size of 0 or beyond one frame) or
    /// [`ErrorCode::RateOutOfRange`] (rate 0, or rate times channels above the device's aggregate maximum).
    pub fn check(&self, info: &DeviceInfo) -> Result<(), DaqError> {
        let bad = |reason: String| DaqError::ConfigRejected { code: ErrorCode::BadConfig, reason };
        let n = self.channels.len();
        if n == 0 {
            return Err(bad("no channels".into()));
        }
        let mut seen = HashSet::new();
        for ch in &self.channels {
            if ch.index >= info.n_channels {
                return Err(bad(format!("channel {} does not exist (device has {})", ch.index, info.n_channels)));
            }
            if !seen.insert(ch.index) {
                return Err(bad(format!("channel {} is listed twice", ch.index)));
            }
            if !info.ranges_mv.contains(&ch.range_mv) {
                return Err(bad(format!("range {} mV is not one of {:?}", ch.range_mv, info.ranges_mv)));
            }
        }
        let max_spp = MAX_SAMPLE_VALUES / n;
        if self.samples_per_packet == 0 || usize::from(self.samples_per_packet) > max_spp {
            return Err(bad(format!(
                "samples_per_packet {} is outside 1..={max_spp} for {n} channels",
                self.samples_per_packet
            )));
        }
        let aggregate_hz = u64::from(self.sample_rate_hz) * n as u64;
        if self.sample_rate_hz == 0 || aggregate_hz > u64::from(info.max_aggregate_rate_hz) {
            return Err(DaqError::ConfigRejected {
                code: ErrorCode::RateOutOfRange,
                reason: format!(
                    "{} Hz x {n} channels = {aggregate_hz} Hz is outside 1..={} Hz",
                    self.sample_rate_hz, info.max_aggregate_rate_hz
                ),
            });
        }
        Ok(())
    }

    fn encode(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        let n = count_u8("Configure", "channels", self.channels.len(), usize::from(u8::MAX))?;
        put_u32(out, self.sample_rate_hz);
        put_u16(out, self.samples_per_packet);
        out.push(n);
        for ch in &self.channels {
            out.push(ch.index);
            put_u16(out, ch.range_mv);
        }
        Ok(())
    }

    fn decode(payload: &[u8]) -> Result<Self, DaqError> {
        let mut r = Reader::new("Configure", payload);
        let sample_rate_hz = r.u32()?;
        let samples_per_packet = r.u16()?;
        let n = r.u8()?;
        let channels = (0..n)
            .map(|_| Ok(ChannelConfig { index: r.u8()?, range_mv: r.u16()? }))
            .collect::<Result<_, DaqError>>()?;
        r.finish()?;
        Ok(Self { sample_rate_hz, samples_per_packet, channels })
    }
}

impl Message for HostCommand {
    const DIRECTION: Direction = Direction::HostToDevice;

    fn msg_type(&self) -> u8 {
        match self {
            HostCommand::GetInfo => TYPE_GET_INFO,
            HostCommand::Configure(_) => TYPE_CONFIGURE,
            HostCommand::Start => TYPE_START,
            HostCommand::Stop => TYPE_STOP,
            HostCommand::Reset => TYPE_RESET,
        }
    }

    fn encode_payload(&self, out: &mut Vec<u8>) -> Result<(), DaqError> {
        match self {
            HostCommand::Configure(c) => c.encode(out),
            HostCommand::GetInfo | HostCommand::Start | HostCommand::Stop | HostCommand::Reset => Ok(()),
        }
    }

    fn decode_payload(msg_type: u8, payload: &[u8]) -> Result<Self, DaqError> {
        let empty = |message: &'static str, command: HostCommand| {
            Reader::new(message, payload).finish()?;
            Ok(command)
        };
        match msg_type {
            TYPE_GET_INFO => empty("GetInfo", HostCommand::GetInfo),
            TYPE_CONFIGURE => Configure::decode(payload).map(HostCommand::Configure),
            TYPE_START => empty("Start", HostCommand::Start),
            TYPE_STOP => empty("Stop", HostCommand::Stop),
            TYPE_RESET => empty("Reset", HostCommand::Reset),
            _ => Err(DaqError::UnknownType { msg_type, direction: Self::DIRECTION }),
        }
    }
}

//! Host-to-device commands (bulk OUT, endpoint 1) and their responses (bulk IN, endpoint 2).
//!
//! Layouts, byte offsets from the packet's start (User's Guide section 5.2; the same bytes LabJackPython's `u6.py`
//! and `LabJackPython.py` build; `cs8`/`cs16` are the checksums of [`crate::checksum`]):
//!
//! | function | command | response |
//! |---|---|---|
//! | ConfigU6 (5.2.2) | 26 bytes: `cs8 F8 0A 08 cs16 cs16`, 6: WriteMask (0: read only), 7: reserved, 8: LocalID, 9-25: reserved | 38 bytes: `cs8 F8 10 08 cs16 cs16`, 6: Errorcode, 7-8: reserved, 9-10: FirmwareVersion (minor, major), 11-12: BootloaderVersion, 13-14: HardwareVersion, 15-18: SerialNumber (u32 LE), 19-20: ProductID (u16 LE, 6), 21: LocalID, 22-36: reserved, 37: VersionInfo (12 for a U6-Pro) |
//! | StreamConfig (5.2.12) | `14 + 2 n` bytes: `cs8 F8 (n+4) 11 cs16 cs16`, 6: NumChannels `n`, 7: ResolutionIndex, 8: SamplesPerPacket, 9: reserved, 10: SettlingFactor, 11: ScanConfig (bit 3: 48 MHz clock, bit 1: divide by 256), 12-13: ScanInterval (u16 LE), then per channel ChannelNumber, ChannelOptions (bit 7 differential, bits 4-5 gain index) | 8 bytes: `cs8 F8 01 11 cs16 cs16`, 6: Errorcode, 7: 0 |
//! | StreamStart (5.2.13) | `A8 A8` | 4 bytes: `cs8 A9`, 2: Errorcode, 3: 0 |
//! | StreamStop (5.2.15) | `B0 B0` | 4 bytes: `cs8 B1`, 2: Errorcode, 3: 0 |
//! | ReadMem / ReadCal (5.2.6) | 8 bytes: `cs8 F8 01 2A` (ReadMem) or `2D` (ReadCal) `cs16 cs16`, 6: 0, 7: BlockNum | 40 bytes: `cs8 F8 11 (2A or 2D) cs16 cs16`, 6: Errorcode, 7: 0, 8-39: the block's 32 bytes |
//!
//! A command whose checksums are wrong is answered by the two bytes `B8 B8` (LabJackPython `_checkCommandBytes`).

use crate::checksum::{expected, is_extended, seal};
use crate::config::{StreamChannel, StreamClock, StreamConfig};
use crate::error::U6Error;
use crate::errorcode::Errorcode;

/// The response to a command whose checksums were wrong.
pub const BAD_CHECKSUM_RESPONSE: [u8; 2] = [0xb8, 0xb8];
/// ReadMem's extended command number.
const READ_MEM: u8 = 0x2a;
/// ReadCal's extended command number.
const READ_CAL: u8 = 0x2d;
/// ConfigU6's extended command number.
const CONFIG_U6: u8 = 0x08;
/// StreamConfig's extended command number.
const STREAM_CONFIG: u8 = 0x11;
/// ConfigU6 response length, bytes.
const CONFIG_U6_RESPONSE_LEN: usize = 38;
/// ReadMem/ReadCal response length, bytes.
const READ_MEM_RESPONSE_LEN: usize = 40;

/// A command from the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Command {
    /// ConfigU6, reading only (WriteMask 0): identity and versions.
    ConfigU6,
    /// StreamConfig: the scan list and clock of the next stream.
    StreamConfig(StreamConfig),
    /// StreamStart.
    StreamStart,
    /// StreamStop.
    StreamStop,
    /// ReadMem (`calibration = false`, user memory) or ReadCal (`true`, calibration memory): one 32-byte block.
    ReadMem {
        /// Calibration memory rather than user memory.
        calibration: bool,
        /// BlockNum.
        block: u8,
    },
}

/// The identity and versions ConfigU6 returns (all zero by default: nothing read yet).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DeviceInfo {
    /// FirmwareVersion as (major, minor): `(1, 43)` is "1.43".
    pub firmware: (u8, u8),
    /// BootloaderVersion as (major, minor).
    pub bootloader: (u8, u8),
    /// HardwareVersion as (major, minor).
    pub hardware: (u8, u8),
    /// SerialNumber.
    pub serial: u32,
    /// ProductID: 6 for a U6.
    pub product_id: u16,
    /// LocalID.
    pub local_id: u8,
    /// VersionInfo: 12 for a U6-Pro (LabJackPython `configU6`), 4 for a U6.
    pub version_info: u8,
}

impl DeviceInfo {
    /// "U6-Pro" or "U6", from VersionInfo.
    pub fn model(&self) -> &'static str {
        if self.version_info == 12 { "U6-Pro" } else { "U6" }
    }

    /// The firmware version as LabJack prints it, `major.minor` with two minor digits ("1.43").
    pub fn firmware_version(&self) -> String {
        format!("{}.{:02}", self.firmware.0, self.firmware.1)
    }
}

/// What a response carries besides its errorcode.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ResponseBody {
    /// ConfigU6's identity.
    ConfigU6(DeviceInfo),
    /// StreamConfig's acknowledgement.
    StreamConfig,
    /// StreamStart's acknowledgement.
    StreamStart,
    /// StreamStop's acknowledgement.
    StreamStop,
    /// A memory block (ReadMem or ReadCal).
    ReadMem {
        /// From the calibration memory (ReadCal).
        calibration: bool,
        /// The block's bytes.
        data: [u8; 32],
    },
}

/// A response from the device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Response {
    /// Errorcode; 0 is success.
    pub errorcode: Errorcode,
    /// The function's data.
    pub body: ResponseBody,
}

fn header(out: &mut Vec<u8>, command: u8, words: u8, extended_number: u8) {
    out.extend_from_slice(&[0, command, words, extended_number, 0, 0]);
}

impl Command {
    /// The command's bytes, checksums set.
    ///
    /// # Errors
    /// [`U6Error::ConfigRejected`] for a StreamConfig with more channels than one packet carries (over 25): the
    /// other fields are sent as they are (the device judges them).
    pub fn encode(&self) -> Result<Vec<u8>, U6Error> {
        let mut out = Vec::with_capacity(26);
        match self {
            Command::ConfigU6 => {
                header(&mut out, 0xf8, 0x0a, CONFIG_U6);
                out.resize(26, 0);
            }
            Command::StreamConfig(config) => {
                let n = config.channels.len();
                let Some(n) = u8::try_from(n).ok().filter(|&n| n <= 25) else {
                    return Err(U6Error::ConfigRejected {
                        errorcode: Errorcode::STREAM_CONFIG_INVALID,
                        reason: format!("{n} channels do not fit one StreamConfig (at most 25)"),
                    });
                };
                header(&mut out, 0xf8, n + 4, STREAM_CONFIG);
                let scan_config =
                    (u8::from(config.clock == StreamClock::Mhz48) << 3) | (u8::from(config.divide_by_256) << 1);
                out.extend_from_slice(&[n, config.resolution_index, config.samples_per_packet, 0]);
                out.extend_from_slice(&[config.settling_factor, scan_config]);
                out.extend_from_slice(&config.scan_interval.to_le_bytes());
                for ch in &config.channels {
                    out.extend_from_slice(&[ch.positive, ch.options_byte()]);
                }
            }
            Command::StreamStart => out.extend_from_slice(&[0, 0xa8]),
            Command::StreamStop => out.extend_from_slice(&[0, 0xb0]),
            Command::ReadMem { calibration, block } => {
                header(&mut out, 0xf8, 0x01, if *calibration { READ_CAL } else { READ_MEM });
                out.extend_from_slice(&[0, *block]);
            }
        }
        seal(&mut out);
        Ok(out)
    }

    /// The command in one OUT transfer (device side).
    ///
    /// # Errors
    /// [`U6Error::BadLength`], [`U6Error::Checksum`] (the device answers [`BAD_CHECKSUM_RESPONSE`]),
    /// [`U6Error::UnexpectedCommandBytes`] for a function this codec does not know, [`U6Error::InvalidField`]
    /// for reserved bits.
    pub fn decode(bytes: &[u8]) -> Result<Command, U6Error> {
        check_checksums("command", bytes)?;
        let unknown = || U6Error::UnexpectedCommandBytes {
            what: "command",
            got: bytes.iter().skip(1).take(3).copied().collect(),
            expected: Vec::new(),
        };
        if !is_extended(bytes[1]) {
            return match bytes {
                [_, 0xa8] => Ok(Command::StreamStart),
                [_, 0xb0] => Ok(Command::StreamStop),
                _ => Err(unknown()),
            };
        }
        let len_for = |words: u8| 6 + 2 * usize::from(words);
        if bytes.len() != len_for(bytes[2]) {
            return Err(U6Error::BadLength { what: "command", len: bytes.len(), expected: len_for(bytes[2]) });
        }
        match (bytes[1], bytes[3]) {
            (0xf8, CONFIG_U6) if bytes[2] == 0x0a => Ok(Command::ConfigU6),
            (0xf8, READ_MEM | READ_CAL) if bytes[2] == 0x01 => {
                Ok(Command::ReadMem { calibration: bytes[3] == READ_CAL, block: bytes[7] })
            }
            (0xf8, STREAM_CONFIG) => decode_stream_config(bytes).map(Command::StreamConfig),
            _ => Err(unknown()),
        }
    }

    /// The bytes (1, 2, 3 for an extended function; 1 for a normal one) its response starts with after Checksum8.
    fn response_command_bytes(&self) -> Vec<u8> {
        match self {
            Command::ConfigU6 => vec![0xf8, 0x10, CONFIG_U6],
            Command::StreamConfig(_) => vec![0xf8, 0x01, STREAM_CONFIG],
            Command::StreamStart => vec![0xa9],
            Command::StreamStop => vec![0xb1],
            Command::ReadMem { calibration, .. } => vec![0xf8, 0x11, if *calibration { READ_CAL } else { READ_MEM }],
        }
    }

    /// The command's name in the guide.
    pub fn name(&self) -> &'static str {
        match self {
            Command::ConfigU6 => "ConfigU6",
            Command::StreamConfig(_) => "StreamConfig",
            Command::StreamStart => "StreamStart",
            Command::StreamStop => "StreamStop",
            Command::ReadMem { calibration: true, .. } => "ReadCal",
            Command::ReadMem { calibration: false, .. } => "ReadMem",
        }
    }
}

fn check_checksums(what: &'static str, bytes: &[u8]) -> Result<(), U6Error> {
    let Some((want8, want16)) = expected(bytes) else {
        return Err(U6Error::BadLength { what, len: bytes.len(), expected: if bytes.len() < 2 { 2 } else { 6 } });
    };
    let got16 = if want16.is_some() { u16::from_le_bytes([bytes[4], bytes[5]]) } else { 0 };
    if bytes[0] != want8 || want16.is_some_and(|c| c != got16) {
        return Err(U6Error::Checksum { what, got8: bytes[0], want8, got16, want16: want16.unwrap_or(0) });
    }
    Ok(())
}

fn decode_stream_config(bytes: &[u8]) -> Result<StreamConfig, U6Error> {
    let Some(&n) = bytes.get(6).filter(|_| bytes.len() >= 14) else {
        return Err(U6Error::BadLength { what: "StreamConfig", len: bytes.len(), expected: 14 });
    };
    let n = usize::from(n);
    let expected = 14 + 2 * n;
    if bytes.len() != expected || usize::from(bytes[2]) != n + 4 {
        return Err(U6Error::BadLength { what: "StreamConfig", len: bytes.len(), expected });
    }
    let scan_config = bytes[11];
    if scan_config & !0x0a != 0 {
        return Err(U6Error::InvalidField {
            what: "StreamConfig",
            field: "ScanConfig",
            value: u64::from(scan_config),
            reason: "only bit 3 (48 MHz clock) and bit 1 (divide by 256) are defined",
        });
    }
    let channels = bytes[14..]
        .chunks_exact(2)
        .map(|pair| StreamChannel::from_bytes(pair[0], pair[1]))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(StreamConfig {
        resolution_index: bytes[7],
        samples_per_packet: bytes[8],
        settling_factor: bytes[10],
        clock: if scan_config & 0x08 != 0 { StreamClock::Mhz48 } else { StreamClock::Mhz4 },
        divide_by_256: scan_config & 0x02 != 0,
        scan_interval: u16::from_le_bytes([bytes[12], bytes[13]]),
        channels,
    })
}

impl Response {
    /// The response's bytes, checksums set (device side).
    pub fn encode(&self) -> Vec<u8> {
        let e = self.errorcode.0;
        let mut out = Vec::with_capacity(40);
        match &self.body {
            ResponseBody::ConfigU6(info) => {
                header(&mut out, 0xf8, 0x10, CONFIG_U6);
                out.resize(CONFIG_U6_RESPONSE_LEN, 0);
                out[6] = e;
                out[9] = info.firmware.1;
                out[10] = info.firmware.0;
                out[11] = info.bootloader.1;
                out[12] = info.bootloader.0;
                out[13] = info.hardware.1;
                out[14] = info.hardware.0;
                out[15..19].copy_from_slice(&info.serial.to_le_bytes());
                out[19..21].copy_from_slice(&info.product_id.to_le_bytes());
                out[21] = info.local_id;
                out[37] = info.version_info;
            }
            ResponseBody::StreamConfig => {
                header(&mut out, 0xf8, 0x01, STREAM_CONFIG);
                out.extend_from_slice(&[e, 0]);
            }
            ResponseBody::StreamStart => out.extend_from_slice(&[0, 0xa9, e, 0]),
            ResponseBody::StreamStop => out.extend_from_slice(&[0, 0xb1, e, 0]),
            ResponseBody::ReadMem { calibration, data } => {
                header(&mut out, 0xf8, 0x11, if *calibration { READ_CAL } else { READ_MEM });
                out.extend_from_slice(&[e, 0]);
                out.extend_from_slice(data);
            }
        }
        seal(&mut out);
        out
    }

    /// The response to `command` in the IN transfer `bytes` (host side).
    ///
    /// # Errors
    /// [`U6Error::DeviceSawBadChecksum`] for `B8 B8`; [`U6Error::Checksum`] for a corrupted response;
    /// [`U6Error::UnexpectedCommandBytes`] for the response of another command (a stale one);
    /// [`U6Error::BadLength`] for a response of the wrong length. A nonzero errorcode is not an error here: it is
    /// in the returned [`Response`].
    pub fn decode_for(command: &Command, bytes: &[u8]) -> Result<Response, U6Error> {
        if bytes == BAD_CHECKSUM_RESPONSE {
            return Err(U6Error::DeviceSawBadChecksum);
        }
        let what = command.name();
        check_checksums(what, bytes)?;
        let want = command.response_command_bytes();
        let got: Vec<u8> = bytes.iter().skip(1).take(want.len()).copied().collect();
        if got != want {
            return Err(U6Error::UnexpectedCommandBytes { what, got, expected: want });
        }
        let len = match command {
            Command::ConfigU6 => CONFIG_U6_RESPONSE_LEN,
            Command::StreamConfig(_) => 8,
            Command::StreamStart | Command::StreamStop => 4,
            Command::ReadMem { .. } => READ_MEM_RESPONSE_LEN,
        };
        if bytes.len() != len {
            return Err(U6Error::BadLength { what, len: bytes.len(), expected: len });
        }
        let pair = |i: usize| (bytes[i + 1], bytes[i]);
        let (errorcode, body) = match command {
            Command::ConfigU6 => (
                bytes[6],
                ResponseBody::ConfigU6(DeviceInfo {
                    firmware: pair(9),
                    bootloader: pair(11),
                    hardware: pair(13),
                    serial: u32::from_le_bytes([bytes[15], bytes[16], bytes[17], bytes[18]]),
                    product_id: u16::from_le_bytes([bytes[19], bytes[20]]),
                    local_id: bytes[21],
                    version_info: bytes[37],
                }),
            ),
            Command::StreamConfig(_) => (bytes[6], ResponseBody::StreamConfig),
            Command::StreamStart => (bytes[2], ResponseBody::StreamStart),
            Command::StreamStop => (bytes[2], ResponseBody::StreamStop),
            Command::ReadMem { calibration, .. } => {
                let mut data = [0u8; 32];
                data.copy_from_slice(&bytes[8..40]);
                (bytes[6], ResponseBody::ReadMem { calibration: *calibration, data })
            }
        };
        Ok(Response { errorcode: Errorcode(errorcode), body })
    }
}

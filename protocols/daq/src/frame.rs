//! Framing: header, CRC trailer, the frame encoder, and the [`Message`] trait that payload codecs implement.

use std::fmt;

use crate::error::DaqError;
use crate::wire::{put_u16, put_u32};

/// The two bytes every frame starts with: ASCII `"MD"` (metaplate DAQ).
pub const MAGIC: [u8; 2] = *b"MD";
/// The protocol version this crate speaks.
pub const PROTOCOL_VERSION: u8 = 1;
/// Header length, bytes: magic 2, version 1, type 1, flags 2, sequence 4, payload length 2.
pub const HEADER_LEN: usize = 12;
/// CRC trailer length, bytes.
pub const CRC_LEN: usize = 4;
/// The largest payload a frame may carry, bytes (16 KiB).
pub const MAX_PAYLOAD_LEN: usize = 16 * 1024;
/// The largest frame, bytes: header + maximum payload + CRC = 16400.
pub const MAX_FRAME_LEN: usize = HEADER_LEN + MAX_PAYLOAD_LEN + CRC_LEN;

/// Which way a message travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Host to device (bulk OUT): commands.
    HostToDevice,
    /// Device to host (bulk IN): replies, samples, notifications.
    DeviceToHost,
}

impl fmt::Display for Direction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Direction::HostToDevice => "host-to-device",
            Direction::DeviceToHost => "device-to-host",
        })
    }
}

/// A message that travels in one direction: the payload codec of that direction.
///
/// Implemented by [`crate::HostCommand`] (host to device) and [`crate::DeviceMessage`] (device to host).
pub trait Message: Sized {
    /// The direction this message type travels.
    const DIRECTION: Direction;

    /// The message type byte (offset 3 of the header).
    fn msg_type(&self) -> u8;

    /// Appends the payload bytes to `out`.
    ///
    /// # Errors
    /// [`DaqError::Unencodable`] if a field exceeds what the wire format carries.
    fn encode_payload(&self, out: &mut Vec<u8>) -> Result<(), DaqError>;

    /// Decodes a payload of type `msg_type`.
    ///
    /// # Errors
    /// [`DaqError::UnknownType`], [`DaqError::BadPayloadLength`], [`DaqError::InvalidField`],
    /// [`DaqError::InvalidUtf8`].
    fn decode_payload(msg_type: u8, payload: &[u8]) -> Result<Self, DaqError>;
}

/// One decoded frame: the sender's sequence number and the message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame<M> {
    /// The sender's frame sequence number (header offset 6).
    pub seq: u32,
    /// The message.
    pub message: M,
}

/// Appends one complete frame (header, payload, CRC) carrying `message` with sequence number `seq` to `out`.
///
/// On error `out` is left as it was.
///
/// # Errors
/// [`DaqError::Unencodable`] if a field exceeds the wire format, or the payload exceeds [`MAX_PAYLOAD_LEN`].
pub fn encode_into<M: Message>(seq: u32, message: &M, out: &mut Vec<u8>) -> Result<(), DaqError> {
    let start = out.len();
    out.extend_from_slice(&MAGIC);
    out.push(PROTOCOL_VERSION);
    out.push(message.msg_type());
    put_u16(out, 0); // flags: all reserved in version 1
    put_u32(out, seq);
    put_u16(out, 0); // payload length, patched below
    if let Err(e) = message.encode_payload(out) {
        out.truncate(start);
        return Err(e);
    }
    let payload_len = out.len() - start - HEADER_LEN;
    let Some(len) = u16::try_from(payload_len).ok().filter(|_| payload_len <= MAX_PAYLOAD_LEN) else {
        out.truncate(start);
        return Err(DaqError::Unencodable {
            message: "frame",
            reason: format!("payload of {payload_len} bytes exceeds the maximum of {MAX_PAYLOAD_LEN}"),
        });
    };
    out[start + HEADER_LEN - 2..start + HEADER_LEN].copy_from_slice(&len.to_le_bytes());
    let crc = crc32fast::hash(&out[start..]);
    put_u32(out, crc);
    Ok(())
}

/// Encodes one complete frame carrying `message` with sequence number `seq`.
///
/// # Errors
/// As [`encode_into`].
pub fn encode<M: Message>(seq: u32, message: &M) -> Result<Vec<u8>, DaqError> {
    let mut out = Vec::new();
    encode_into(seq, message, &mut out)?;
    Ok(out)
}

/// The fixed fields of a header, read from its 12 bytes (magic already checked).
pub(crate) struct Header {
    pub(crate) version: u8,
    pub(crate) msg_type: u8,
    pub(crate) flags: u16,
    pub(crate) seq: u32,
    pub(crate) payload_len: usize,
}

impl Header {
    pub(crate) fn parse(h: &[u8; HEADER_LEN]) -> Self {
        Self {
            version: h[2],
            msg_type: h[3],
            flags: u16::from_le_bytes([h[4], h[5]]),
            seq: u32::from_le_bytes([h[6], h[7], h[8], h[9]]),
            payload_len: usize::from(u16::from_le_bytes([h[10], h[11]])),
        }
    }
}

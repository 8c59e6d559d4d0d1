//! The one error type of this crate.

use crate::codes::ErrorCode;
use crate::frame::Direction;

/// Why bytes could not be decoded, a message could not be encoded, or a configuration or packet was refused.
///
/// Decoding errors come in two classes. Frame-level errors ([`DaqError::Garbage`], [`DaqError::PayloadTooLong`],
/// [`DaqError::CrcMismatch`]) mean the byte stream was corrupt: the decoder resynchronises on the next magic.
/// Message-level errors (the others returned by a decoder) come from a frame whose CRC was good: the sender produced
/// a frame this decoder does not accept, and the decoder skips exactly that frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DaqError {
    /// Bytes that were not part of any frame were skipped while looking for the magic (a connection picked up
    /// mid-stream, or corruption). Reported once per run of skipped bytes, when the next magic is found.
    #[error("skipped {skipped_bytes} bytes that were not part of a frame")]
    Garbage {
        /// Number of bytes skipped.
        skipped_bytes: usize,
    },
    /// A header announced a payload longer than [`crate::MAX_PAYLOAD_LEN`]: a corrupt header.
    #[error("frame header announces a {len}-byte payload, more than the maximum of {max}")]
    PayloadTooLong {
        /// Announced payload length, bytes.
        len: usize,
        /// The maximum, bytes.
        max: usize,
    },
    /// The CRC-32 trailer does not match the header and payload: the frame was corrupted in transit.
    #[error("CRC mismatch: frame carries {received:#010x}, header and payload give {computed:#010x}")]
    CrcMismatch {
        /// CRC read from the trailer.
        received: u32,
        /// CRC computed over header and payload.
        computed: u32,
    },
    /// A well-formed frame of a protocol version this crate does not speak.
    #[error("protocol version {received} is not supported (this side speaks version {supported})")]
    VersionMismatch {
        /// Version byte of the frame.
        received: u8,
        /// The version this crate speaks, [`crate::PROTOCOL_VERSION`].
        supported: u8,
    },
    /// A well-formed frame with header flag bits set that this version reserves (they must be zero).
    #[error("reserved header flags set: {flags:#06x}")]
    ReservedFlags {
        /// The flags field.
        flags: u16,
    },
    /// A well-formed frame whose message type is unknown, or belongs to the other direction.
    #[error("message type {msg_type:#04x} is not a {direction} message")]
    UnknownType {
        /// The type byte.
        msg_type: u8,
        /// The direction the decoder reads.
        direction: Direction,
    },
    /// A payload whose length does not fit its message type (or its own count fields).
    #[error("{message} payload is {len} bytes, expected {expected}")]
    BadPayloadLength {
        /// Message name.
        message: &'static str,
        /// Actual payload length, bytes.
        len: usize,
        /// Expected length, bytes (a description when it depends on count fields).
        expected: String,
    },
    /// A field holds a value outside its documented range (an unknown code, a zero count, reserved bits).
    #[error("{message}: field {field} = {value} is invalid: {reason}")]
    InvalidField {
        /// Message name.
        message: &'static str,
        /// Field name.
        field: &'static str,
        /// The offending value.
        value: u64,
        /// What the field accepts.
        reason: &'static str,
    },
    /// A text field is not valid UTF-8.
    #[error("{message}: text field {field} is not valid UTF-8")]
    InvalidUtf8 {
        /// Message name.
        message: &'static str,
        /// Field name.
        field: &'static str,
    },
    /// A message cannot be encoded because a field exceeds what the wire format can carry.
    #[error("cannot encode {message}: {reason}")]
    Unencodable {
        /// Message name.
        message: &'static str,
        /// What is out of range, and the limit.
        reason: String,
    },
    /// A configuration the device (or the host, checking before sending) refuses; `code` is the error code the
    /// device replies with.
    #[error("configuration rejected ({code}): {reason}")]
    ConfigRejected {
        /// The protocol error code for this refusal.
        code: ErrorCode,
        /// What is wrong.
        reason: String,
    },
    /// A sample packet whose shape does not match the configuration it is read with.
    #[error(
        "packet {packet_seq} has {n_channels} channels and {n_samples} samples; the configuration has {expected_channels} channels and at most {max_samples} samples per packet"
    )]
    PacketShape {
        /// The packet's sequence number.
        packet_seq: u32,
        /// Channels in the packet.
        n_channels: usize,
        /// Samples per channel in the packet.
        n_samples: usize,
        /// Configured channel count.
        expected_channels: usize,
        /// Configured samples per packet.
        max_samples: usize,
    },
    /// A voltage to quantise was NaN or infinite.
    #[error("cannot quantise a non-finite voltage ({volts})")]
    NonFiniteVolts {
        /// The value, V (as text, so that the error type stays `Eq`).
        volts: String,
    },
}

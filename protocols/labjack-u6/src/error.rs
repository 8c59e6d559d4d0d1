//! The one error type of this crate.

use crate::errorcode::Errorcode;

/// Why bytes could not be decoded, a packet encoded, or a configuration or calibration accepted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum U6Error {
    /// A packet shorter than its function's fixed length (or than a header).
    #[error("{what}: {len} bytes, expected {expected}")]
    BadLength {
        /// Which packet.
        what: &'static str,
        /// Bytes received.
        len: usize,
        /// Bytes its layout needs.
        expected: usize,
    },
    /// The checksums do not match the bytes: corrupted in transit.
    #[error(
        "{what}: checksum mismatch (Checksum8 {got8:#04x}, expected {want8:#04x}; Checksum16 {got16:#06x}, expected {want16:#06x})"
    )]
    Checksum {
        /// Which packet.
        what: &'static str,
        /// Checksum8 carried.
        got8: u8,
        /// Checksum8 computed.
        want8: u8,
        /// Checksum16 carried (0 for a normal packet).
        got16: u16,
        /// Checksum16 computed (0 for a normal packet).
        want16: u16,
    },
    /// The device answered `B8 B8`: it received a command whose checksums were wrong.
    #[error("the U6 reports a command with a bad checksum (response B8 B8)")]
    DeviceSawBadChecksum,
    /// Command bytes that are no function this codec knows, or not the response to the command sent (a stale
    /// response, or another function's).
    #[error("{what}: command bytes {got:02x?}, expected {expected:02x?}")]
    UnexpectedCommandBytes {
        /// Which packet was expected.
        what: &'static str,
        /// Bytes 1.. (up to 3) received.
        got: Vec<u8>,
        /// Bytes expected.
        expected: Vec<u8>,
    },
    /// A field outside what the guide allows (reserved bits set, a count out of range).
    #[error("{what}: {field} = {value} is invalid: {reason}")]
    InvalidField {
        /// Which packet.
        what: &'static str,
        /// Field name, as the guide names it.
        field: &'static str,
        /// The value.
        value: u64,
        /// What is allowed.
        reason: &'static str,
    },
    /// A stream configuration the U6 refuses (or the host, checking first); `errorcode` is the one the device
    /// answers with.
    #[error("stream configuration rejected ({errorcode}): {reason}")]
    ConfigRejected {
        /// The errorcode StreamConfig returns for it.
        errorcode: Errorcode,
        /// What is wrong.
        reason: String,
    },
    /// Calibration constants that cannot convert codes (a slope of the wrong sign or zero, a center off the
    /// 16-bit scale): an erased or corrupt calibration memory.
    #[error("calibration constant {name} = {value} is implausible: {reason}")]
    BadCalibration {
        /// Constant name (as LabJackPython's `CalibrationInfo` names it).
        name: String,
        /// Its value (as text, so that this type stays `Eq`).
        value: String,
        /// Why.
        reason: &'static str,
    },
    /// A voltage to digitise was NaN or infinite.
    #[error("cannot digitise a non-finite voltage ({volts})")]
    NonFiniteVolts {
        /// The value, V, as text.
        volts: String,
    },
    /// Bytes skipped on the stream endpoint while looking for the next StreamData header.
    #[error("skipped {skipped_bytes} bytes that were not part of a StreamData packet")]
    Garbage {
        /// Bytes skipped.
        skipped_bytes: usize,
    },
    /// A stream packet reports an errorcode that ends the stream (anything but 0, 59 and 60).
    #[error("stream packet {packet_number}: {errorcode}")]
    StreamError {
        /// The packet's PacketNumber.
        packet_number: u8,
        /// Its errorcode.
        errorcode: Errorcode,
    },
}

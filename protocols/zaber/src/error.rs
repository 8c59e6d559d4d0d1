//! What can be wrong with a line of Zaber's ASCII protocol.

/// Why a line is not a valid message. The line is dropped; the stream goes on with the next one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ZaberProtocolError {
    /// More than [`crate::MAX_LINE`] bytes without a terminator: the rest, up to the next terminator, is dropped.
    #[error("line longer than {max_bytes} bytes")]
    LineTooLong {
        /// The limit, bytes.
        max_bytes: usize,
    },
    /// A byte outside the protocol's printable ASCII (32..=126).
    #[error("byte 0x{byte:02x} at column {column} is not printable ASCII")]
    BadCharacter {
        /// The byte.
        byte: u8,
        /// Where in the line, from 0.
        column: usize,
    },
    /// The line does not start with the type character the reader expects (`/` for a command; `@`, `#` or `!`
    /// for a device's message).
    #[error("not a {expected} message: {line:?}")]
    WrongType {
        /// What was expected.
        expected: &'static str,
        /// The line, as received.
        line: String,
    },
    /// A field is missing or malformed.
    #[error("malformed {field} in {line:?}")]
    Malformed {
        /// Which field.
        field: &'static str,
        /// The line, as received.
        line: String,
    },
    /// The line carries a checksum that does not match its content.
    #[error("checksum mismatch in {line:?}")]
    Checksum {
        /// The line, as received.
        line: String,
    },
}

//! Why bytes or text did not decode.

/// A decoding or encoding failure. Every variant is a property of the bytes or text given, never of I/O.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PolytecProtocolError {
    /// A line grew past [`crate::MAX_LINE_CONTENT`] bytes without a terminator; the rest of it is dropped.
    #[error("line longer than {max_bytes} bytes")]
    LineTooLong {
        /// The limit, bytes.
        max_bytes: usize,
    },
    /// A line is not UTF-8 text, or holds a control character.
    #[error("byte 0x{byte:02x} at column {column} is not printable text")]
    BadCharacter {
        /// The first offending byte.
        byte: u8,
        /// Its position in the line, from 0.
        column: usize,
    },
    /// A request line does not follow the syntax `Verb,Device,Index,Attribute[,Value]`.
    #[error("malformed request {line:?}: {detail}")]
    MalformedRequest {
        /// The line (truncated to the line limit).
        line: String,
        /// What is wrong.
        detail: String,
    },
    /// A field to encode is empty or holds a comma, a control character or a line terminator.
    #[error("field {field:?} cannot be sent: {detail}")]
    BadField {
        /// The field.
        field: String,
        /// What is wrong.
        detail: String,
    },
    /// A reply that should name a velocity range (`5mm/s/V`) does not.
    #[error("{text:?} is not a velocity range (number, then m/s/V, mm/s/V or um/s/V)")]
    BadVelocityRange {
        /// The text.
        text: String,
    },
    /// A reply that should be a number is not.
    #[error("{text:?} is not {what}")]
    BadNumber {
        /// The text.
        text: String,
        /// What was expected.
        what: &'static str,
    },
}

//! The decoding error of this crate, and the controller's numeric error codes (`ERR <code> <text>`).

use std::fmt;

/// The controller's numeric error codes, sent as `ERR <code> <text>`. See the table in the crate documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorCode {
    /// 1: the first word of the line is not a command keyword.
    UnknownCommand,
    /// 2: the keyword is known but an argument is malformed (wrong count, not a decimal number, too many digits or
    /// decimals, an unknown choice word, a character outside printable ASCII).
    BadArgument,
    /// 3: an argument is well formed but outside its documented range.
    OutOfRange,
    /// 4: the line exceeded the maximum line length; it was discarded up to its terminator.
    LineTooLong,
    /// 5: plate coordinates were used but the beam has no valid plate calibration.
    NotCalibrated,
    /// 6: the command needs the laser on (signal level).
    LaserOff,
    /// 7: the controller is under front-panel control or running its self-test; retry after 100 ms.
    Busy,
    /// 8: a latched hardware fault (mirror drive or laser); cleared by `*CLS` or `*RST` once the cause is gone.
    HardwareFault,
}

impl ErrorCode {
    /// Every code, in numeric order.
    pub const ALL: [ErrorCode; 8] = [
        ErrorCode::UnknownCommand,
        ErrorCode::BadArgument,
        ErrorCode::OutOfRange,
        ErrorCode::LineTooLong,
        ErrorCode::NotCalibrated,
        ErrorCode::LaserOff,
        ErrorCode::Busy,
        ErrorCode::HardwareFault,
    ];

    /// The number sent on the wire, 1 to 8.
    pub fn number(self) -> u8 {
        match self {
            ErrorCode::UnknownCommand => 1,
            ErrorCode::BadArgument => 2,
            ErrorCode::OutOfRange => 3,
            ErrorCode::LineTooLong => 4,
            ErrorCode::NotCalibrated => 5,
            ErrorCode::LaserOff => 6,
            ErrorCode::Busy => 7,
            ErrorCode::HardwareFault => 8,
        }
    }

    /// The code with wire number `number`, or `None` when the specification defines no such code.
    pub fn from_number(number: i64) -> Option<Self> {
        Self::ALL.into_iter().find(|code| i64::from(code.number()) == number)
    }

    /// A short English description, used as the default text of an `ERR` reply.
    pub fn description(self) -> &'static str {
        match self {
            ErrorCode::UnknownCommand => "unknown command",
            ErrorCode::BadArgument => "bad argument",
            ErrorCode::OutOfRange => "out of range",
            ErrorCode::LineTooLong => "line too long",
            ErrorCode::NotCalibrated => "beam not calibrated",
            ErrorCode::LaserOff => "laser off",
            ErrorCode::Busy => "busy",
            ErrorCode::HardwareFault => "hardware fault",
        }
    }
}

impl fmt::Display for ErrorCode {
    /// Formats as `<number> (<description>)`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.number(), self.description())
    }
}

/// Why bytes could not be decoded into a message, or a value could not be built.
///
/// The same type serves both sides: the host's [`crate::ReplyDecoder`] and the device's [`crate::CommandDecoder`].
/// On the device side, [`LdvProtocolError::error_code`] gives the code of the `ERR` reply the controller sends for
/// it (see [`crate::Reply::from_error`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LdvProtocolError {
    /// A line grew beyond the maximum length; its bytes are discarded up to the next terminator, where decoding
    /// resumes. Reported once per overlong line, as soon as the limit is passed.
    #[error("line longer than {max_bytes} bytes before its terminator; discarded")]
    LineTooLong {
        /// The limit, bytes of content before the terminator ([`crate::MAX_LINE_CONTENT`]).
        max_bytes: usize,
    },
    /// A byte outside printable ASCII (0x20 to 0x7E) in a line.
    #[error("byte {byte:#04x} at column {column} is not printable ASCII")]
    BadCharacter {
        /// The offending byte.
        byte: u8,
        /// Its position in the line, from 0.
        column: usize,
    },
    /// The first word of the line is not a keyword of this direction (command or reply).
    #[error("unknown keyword {keyword:?}")]
    UnknownKeyword {
        /// The word as received.
        keyword: String,
    },
    /// A known keyword with the wrong number of arguments.
    #[error("{keyword} takes {expected} argument(s), got {found}")]
    ArgumentCount {
        /// The keyword, in its canonical spelling.
        keyword: &'static str,
        /// How many it takes.
        expected: usize,
        /// How many arrived.
        found: usize,
    },
    /// A numeric argument is not a plain decimal number of the allowed shape (NaN, inf, exponents, hex, too many
    /// digits or too many decimals are all refused).
    #[error("{what}: {text:?} is not a valid number ({reason})")]
    MalformedNumber {
        /// Which quantity, with its unit.
        what: &'static str,
        /// The text received.
        text: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A word argument is not one of its allowed words.
    #[error("{what}: {text:?} is not one of {expected}")]
    InvalidChoice {
        /// Which setting.
        what: &'static str,
        /// The word received.
        text: String,
        /// The allowed words.
        expected: &'static str,
    },
    /// A value is well formed but outside its documented range.
    #[error("{what} = {value} is outside {valid}")]
    OutOfRange {
        /// Which quantity, with its unit.
        what: &'static str,
        /// The value, as received or given.
        value: String,
        /// The valid range, with its unit.
        valid: &'static str,
    },
    /// A floating-point value given to a constructor is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which quantity, with its unit.
        what: &'static str,
    },
    /// A text field (identity field, error text) breaks its rules.
    #[error("{what}: {reason}")]
    InvalidText {
        /// Which field.
        what: &'static str,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// An `ERR` reply carries a code that the specification does not define.
    #[error("ERR reply with undefined error code {code}")]
    UnknownErrorCode {
        /// The code received.
        code: i64,
    },
}

impl LdvProtocolError {
    /// The code of the `ERR` reply a controller sends when a command line fails to decode with this error.
    pub fn error_code(&self) -> ErrorCode {
        match self {
            LdvProtocolError::LineTooLong { .. } => ErrorCode::LineTooLong,
            LdvProtocolError::UnknownKeyword { .. } => ErrorCode::UnknownCommand,
            LdvProtocolError::OutOfRange { .. } => ErrorCode::OutOfRange,
            LdvProtocolError::BadCharacter { .. }
            | LdvProtocolError::ArgumentCount { .. }
            | LdvProtocolError::MalformedNumber { .. }
            | LdvProtocolError::InvalidChoice { .. }
            | LdvProtocolError::NonFinite { .. }
            | LdvProtocolError::InvalidText { .. }
            | LdvProtocolError::UnknownErrorCode { .. } => ErrorCode::BadArgument,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_one_to_eight_and_invert() {
        for (i, code) in ErrorCode::ALL.into_iter().enumerate() {
            assert_eq!(usize::from(code.number()), i + 1);
            assert_eq!(ErrorCode::from_number(i64::from(code.number())), Some(code));
        }
        assert_eq!(ErrorCode::from_number(0), None);
        assert_eq!(ErrorCode::from_number(9), None);
        assert_eq!(ErrorCode::from_number(-1), None);
    }

    #[test]
    fn decode_errors_map_to_documented_codes() {
        let too_long = LdvProtocolError::LineTooLong { max_bytes: 126 };
        assert_eq!(too_long.error_code(), ErrorCode::LineTooLong);
        let unknown = LdvProtocolError::UnknownKeyword { keyword: "FOO".into() };
        assert_eq!(unknown.error_code(), ErrorCode::UnknownCommand);
        let range = LdvProtocolError::OutOfRange { what: "x", value: "1".into(), valid: "0" };
        assert_eq!(range.error_code(), ErrorCode::OutOfRange);
        let count = LdvProtocolError::ArgumentCount { keyword: "POS", expected: 2, found: 1 };
        assert_eq!(count.error_code(), ErrorCode::BadArgument);
    }
}

//! The errors of this crate: where a file went wrong and why, and why a record cannot be written.

use std::fmt;

/// Where in a file a decoding error happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// The dataset's ordinal in the file, from 1 (0: before the first dataset's opening delimiter).
    pub record: u64,
    /// The dataset number (58, 164, 2411, ...) once its identifier line has been read.
    pub dataset_number: Option<u32>,
    /// The line, from 1. In binary data: the line the data follows.
    pub line: u64,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "record {}", self.record)?;
        if let Some(number) = self.dataset_number {
            write!(f, " (dataset {number})")?;
        }
        write!(f, ", line {}", self.line)
    }
}

/// A decoding error: where, and what was wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{location}: {kind}")]
pub struct DecodeError {
    /// Where.
    pub location: Location,
    /// What.
    pub kind: Malformed,
}

/// What was wrong with the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Malformed {
    /// A line is longer than the decoder's limit (the format's lines are 80 columns).
    #[error("a line is longer than the limit of {max_bytes} bytes")]
    LineTooLong {
        /// The limit, bytes.
        max_bytes: usize,
    },
    /// A line is not what the format has at this place.
    #[error("expected {expected}, found {found:?}")]
    Unexpected {
        /// What the format has here.
        expected: &'static str,
        /// The start of the line found (at most 40 characters, non-ASCII shown as `?`).
        found: String,
    },
    /// A fixed-column field does not hold what its format says.
    #[error("{field} (columns {first_column}-{last_column}, {format}): found {found:?}")]
    Field {
        /// The field's name in the specification.
        field: &'static str,
        /// First column, from 1.
        first_column: usize,
        /// Last column, from 1.
        last_column: usize,
        /// The Fortran format or the values allowed.
        format: &'static str,
        /// The field's content (at most 40 characters, non-ASCII shown as `?`).
        found: String,
    },
    /// The file uses a part of the format this crate does not read (uneven abscissa, non-IEEE binary, ...).
    #[error("unsupported: {what}")]
    Unsupported {
        /// What, and the value found.
        what: String,
    },
    /// The byte count of a 58b identifier line does not match the values records 6 and 7 announce.
    #[error("the 58b identifier line states {stated} bytes of binary data; record 7 needs {expected}")]
    ByteCount {
        /// Bytes stated in the identifier line.
        stated: u64,
        /// Bytes the ordinate data type and number of values need.
        expected: u64,
    },
    /// More values or nodes than the decoder's limit.
    #[error("{what}: {count} exceeds the limit of {max}")]
    TooLarge {
        /// What is counted.
        what: &'static str,
        /// How many the file announces or holds.
        count: u64,
        /// The limit.
        max: u64,
    },
    /// The closing delimiter came before all the values record 7 announces.
    #[error("the dataset ends after {found} of the {expected} values record 7 announces")]
    TooFewValues {
        /// Values (real numbers; a complex value counts two) announced.
        expected: u64,
        /// Values found.
        found: u64,
    },
    /// A data line holds more values than record 7 announces.
    #[error("more than the {expected} values record 7 announces")]
    TooManyValues {
        /// Values (real numbers; a complex value counts two) announced.
        expected: u64,
    },
    /// An ordinate or coordinate value is NaN or infinite: a decoded record holds only finite numbers.
    #[error("value {index} is not finite ({value})")]
    NonFinite {
        /// Index of the offending value among the dataset's values (real numbers), from 0.
        index: u64,
        /// The value.
        value: f64,
    },
    /// The input ended inside a dataset.
    #[error("the input ends inside a dataset: expected {expected}")]
    Truncated {
        /// What was expected next.
        expected: &'static str,
    },
}

/// Why a record cannot be encoded. Nothing is appended to the caller's buffer when encoding fails.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EncodeError {
    /// A text field is too long for its columns, or holds a character outside printable Latin-1 (which would shift
    /// the fixed columns of every reader).
    #[error("{field} {text:?} is not at most {max_len} printable Latin-1 characters")]
    Text {
        /// Which field.
        field: &'static str,
        /// Its content.
        text: String,
        /// Its width, characters.
        max_len: usize,
    },
    /// A text field that fills its line reads `-1`: every reader would take it for the dataset's closing delimiter.
    #[error("{field} \"-1\" would read as the delimiter that closes the dataset")]
    Delimiter {
        /// Which field.
        field: &'static str,
    },
    /// An integer does not fit its columns or its range.
    #[error("{field} = {value} is out of range {min}..={max}")]
    Integer {
        /// Which field.
        field: &'static str,
        /// Its value.
        value: i64,
        /// Smallest value allowed.
        min: i64,
        /// Largest value allowed.
        max: i64,
    },
    /// A header number (abscissa start or step, z-axis value, unit factor) is not finite, or the step is not
    /// positive.
    #[error("{field} = {value} is not finite (or, for the abscissa step, not positive)")]
    Header {
        /// Which field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// An ordinate value or coordinate is NaN or infinite, or too large for single precision.
    #[error("value {index} ({value}) is not finite in {precision}")]
    Value {
        /// Index among the record's real numbers (a complex value counts two: real part, then imaginary).
        index: usize,
        /// The value.
        value: f64,
        /// "single precision" or "double precision".
        precision: &'static str,
    },
    /// A function has no values.
    #[error("a function has no values")]
    Empty,
    /// A record of a dataset this crate does not write.
    #[error("dataset {dataset_number} is read only, not written")]
    NotWritable {
        /// Its dataset number.
        dataset_number: u32,
    },
}

/// The start of `bytes` for an error message: at most 40 characters, bytes outside printable ASCII as `?`.
pub(crate) fn excerpt(bytes: &[u8]) -> String {
    bytes.iter().take(40).map(|&b| if (0x20..=0x7e).contains(&b) { char::from(b) } else { '?' }).collect()
}

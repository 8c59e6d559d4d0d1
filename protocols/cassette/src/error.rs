//! The one error type of this crate, and where in a cassette an error happened.

use std::fmt;

/// Which part of a cassette an error concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// The file header.
    Header,
    /// A record, by its ordinal: the number of record frames the decoder (or encoder) met before it, good or bad.
    Record(u64),
    /// The end marker.
    Trailer,
}

impl fmt::Display for Section {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Section::Header => write!(f, "header"),
            Section::Record(n) => write!(f, "record {n}"),
            Section::Trailer => write!(f, "trailer"),
        }
    }
}

/// Why a field's content is invalid although the framing around it is sound.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Invalid {
    /// A text field is not UTF-8.
    #[error("{field} is not valid UTF-8")]
    Utf8 {
        /// Which field.
        field: &'static str,
    },
    /// A text field is longer than the format allows.
    #[error("{field} is {len} bytes, more than the limit of {max}")]
    FieldTooLong {
        /// Which field.
        field: &'static str,
        /// Its length, bytes.
        len: usize,
        /// The limit, bytes.
        max: usize,
    },
    /// The header's identity fields run past its stated length.
    #[error("the identity fields overrun the header length of {header_len} bytes")]
    HeaderOverrun {
        /// The header length the file states, bytes.
        header_len: usize,
    },
    /// The header length is shorter than the fixed part of a header.
    #[error("header length {header_len} is shorter than the minimum of {min} bytes")]
    HeaderTooShort {
        /// The header length the file states, bytes.
        header_len: usize,
        /// The minimum, bytes.
        min: usize,
    },
    /// A stream block has no channels.
    #[error("a stream block has zero channels")]
    ZeroChannels,
    /// A stream block's sample rate is not a finite positive number of hertz.
    #[error("sample rate {sample_rate_hz} Hz is not finite and positive")]
    SampleRate {
        /// The rate found, Hz.
        sample_rate_hz: f64,
    },
    /// A stream block's samples do not fill whole frames (one sample per channel).
    #[error("{samples} samples do not divide into frames of {channels} channels")]
    PartialFrame {
        /// Number of samples, or of sample bytes when the payload is being decoded.
        samples: usize,
        /// Channels per frame (times the sample size in bytes when decoding).
        channels: usize,
    },
    /// A stream block's payload is shorter than its fixed sub-header.
    #[error("stream payload of {len} bytes is shorter than its {min}-byte sub-header")]
    StreamTooShort {
        /// Payload length, bytes.
        len: usize,
        /// Sub-header length, bytes.
        min: usize,
    },
    /// An `f32` sample is NaN or infinite: a cassette never carries one, so replay feeds only finite samples.
    #[error("sample {index} is not finite ({value})")]
    NonFiniteSample {
        /// Index of the first offending sample (interleaved).
        index: usize,
        /// Its value.
        value: f32,
    },
    /// An event payload is empty (it must hold at least the event kind).
    #[error("an event payload is empty")]
    EmptyEvent,
    /// An event other than a note carries text.
    #[error("a {event} event carries {len} bytes of text; only a note may")]
    EventText {
        /// The event's name.
        event: &'static str,
        /// Bytes of text found.
        len: usize,
    },
}

/// Everything that can go wrong when encoding or decoding a cassette.
///
/// Offsets are byte offsets from the start of the cassette: of the header, record or trailer concerned (for the
/// encoder, where it would have been written).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CassetteError {
    /// The file does not start with the cassette magic: it is not a cassette. Fatal.
    #[error("not a cassette: the file starts with {found:02x?}, not the magic \"MPCASSET\"")]
    BadMagic {
        /// The first bytes found (up to 8).
        found: Vec<u8>,
    },
    /// The file's major format version is not one this reader knows. Fatal.
    #[error("cassette format version {major}.{minor} is not supported (this reader reads major version {supported})")]
    UnsupportedVersion {
        /// Major version found.
        major: u16,
        /// Minor version found.
        minor: u16,
        /// The major version this reader supports.
        supported: u16,
    },
    /// A CRC-32 does not match its bytes: the cassette is corrupt.
    #[error(
        "checksum mismatch in the {covers} of {section} at byte {offset}: stored {stored:#010x}, computed {computed:#010x}"
    )]
    Checksum {
        /// Which part.
        section: Section,
        /// What the checksum covers ("header", "record head", "record", "trailer").
        covers: &'static str,
        /// Byte offset of the section.
        offset: u64,
        /// The checksum in the file.
        stored: u32,
        /// The checksum of the bytes read.
        computed: u32,
    },
    /// A length exceeds the format's limit; it is refused before anything is allocated.
    #[error("{what} of {section} at byte {offset} is {len} bytes, more than the limit of {max}")]
    Oversize {
        /// Which part.
        section: Section,
        /// What is too long.
        what: &'static str,
        /// Byte offset of the section.
        offset: u64,
        /// The length, bytes.
        len: u64,
        /// The limit, bytes.
        max: u64,
    },
    /// The input ended before the end marker: the recording was cut short (a crash mid-recording, or a partial
    /// copy). Every good record before the cut has been delivered.
    #[error("cassette truncated after {offset} bytes ({records} good records before the cut, no end marker)")]
    Truncated {
        /// Bytes received in all.
        offset: u64,
        /// Good records delivered.
        records: u64,
    },
    /// A kind code (device, record, event or sample format) that this version does not know.
    #[error("unknown {what} code {code} in {section} at byte {offset}")]
    UnknownKind {
        /// Which part.
        section: Section,
        /// Which kind of code.
        what: &'static str,
        /// The code found.
        code: u8,
        /// Byte offset of the section.
        offset: u64,
    },
    /// A record's timestamp is earlier than the previous good record's: timestamps never decrease.
    #[error("{section} at byte {offset} has timestamp {t_ns} ns, before the previous record's {previous_ns} ns")]
    OutOfOrder {
        /// Which record.
        section: Section,
        /// Byte offset of the record.
        offset: u64,
        /// Timestamp of the previous good record, ns since the session start.
        previous_ns: u64,
        /// This record's timestamp, ns since the session start.
        t_ns: u64,
    },
    /// Bytes follow the end marker.
    #[error("trailing garbage after the end marker, starting at byte {offset}")]
    TrailingGarbage {
        /// Byte offset of the first extra byte (it and everything after it is discarded).
        offset: u64,
    },
    /// Where a record or the end marker should begin, there is neither; the decoder skips to the next sync word.
    #[error("lost sync at byte {offset}: found {found:02x?} where a record or the end marker should begin")]
    LostSync {
        /// Byte offset where sync was lost.
        offset: u64,
        /// The 4 bytes found.
        found: [u8; 4],
    },
    /// The framing is sound (checksums match) but a field's content is invalid.
    #[error("invalid {section} at byte {offset}: {reason}")]
    Invalid {
        /// Which part.
        section: Section,
        /// Byte offset of the section.
        offset: u64,
        /// What is wrong.
        reason: Invalid,
    },
    /// The end marker's record count differs from the number of good records read: records were lost to
    /// corruption (reported before) or the file was spliced.
    #[error("the end marker counts {stored} records but {read} good records were read")]
    RecordCount {
        /// Count in the end marker.
        stored: u64,
        /// Good records read.
        read: u64,
    },
    /// The encoder was called out of order (a record before the header, anything after the end marker).
    #[error("encoder misuse: {reason}")]
    EncoderState {
        /// What was wrong.
        reason: &'static str,
    },
}

//! How a driver left its recorded session ([`Mismatch`]), and the bytes of a message ([`escape`]).

use std::fmt;

/// How the driver left the recorded session.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Deviation {
    /// It wrote other bytes than the recording.
    Bytes,
    /// It submitted other samples than the recording (audio): `first_difference` is a sample index.
    Samples,
    /// It wrote where the recording has a read or a reopen.
    UnexpectedWrite,
    /// It read where the recording has a write or a reopen.
    UnexpectedRead,
    /// It reopened where the recording has a read or a write.
    UnexpectedReopen,
    /// It called the transport after the recording's last call.
    PastEnd,
}

/// The driver did not do what the recording did: where, and how.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct Mismatch {
    /// How it deviated.
    pub deviation: Deviation,
    /// The cassette record index of the recorded call it was compared with (the record count when past the end).
    pub record: usize,
    /// The recorded bytes (for a write), else empty.
    pub expected: Vec<u8>,
    /// The driver's bytes (for a write), in the recording's terms, else empty.
    pub got: Vec<u8>,
    /// The first byte index where they differ (the shorter length when one is a prefix of the other).
    pub first_difference: Option<usize>,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.deviation {
            Deviation::Bytes => write!(
                f,
                "replay mismatch at record {}: expected {} got {} (first difference at byte {})",
                self.record,
                escape(&self.expected),
                escape(&self.got),
                self.first_difference.map_or_else(|| "?".into(), |i| i.to_string())
            ),
            Deviation::Samples => write!(
                f,
                "replay mismatch at record {}: other samples than recorded (first difference at sample {})",
                self.record,
                self.first_difference.map_or_else(|| "?".into(), |i| i.to_string())
            ),
            Deviation::UnexpectedWrite => {
                write!(f, "replay mismatch at record {}: the driver wrote {}", self.record, escape(&self.got))?;
                write!(f, " where the recording does not write")
            }
            Deviation::UnexpectedRead => {
                write!(f, "replay mismatch at record {}: the driver read where the recording does not", self.record)
            }
            Deviation::UnexpectedReopen => {
                write!(f, "replay mismatch at record {}: the driver reopened where the recording does not", self.record)
            }
            Deviation::PastEnd => {
                write!(f, "replay mismatch: the driver went on past the recording's end ({} records)", self.record)
            }
        }
    }
}

/// Bytes for a message: printable ASCII as is, the rest as `\xNN`, at most 64 bytes shown.
pub fn escape(bytes: &[u8]) -> String {
    let mut s = String::from("\"");
    for &b in bytes.iter().take(64) {
        match b {
            b'\r' => s.push_str("\\r"),
            b'\n' => s.push_str("\\n"),
            0x20..=0x7e if b != b'"' && b != b'\\' => s.push(char::from(b)),
            _ => s.push_str(&format!("\\x{b:02x}")),
        }
    }
    if bytes.len() > 64 {
        s.push_str(&format!("... ({} bytes)", bytes.len()));
    }
    s.push('"');
    s
}

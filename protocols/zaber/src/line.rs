//! Splitting a byte stream into messages, and the longitudinal redundancy check that may end one.
//!
//! *Manual, Message Format*: a message ends at CR, LF, or both (devices always end theirs with CR LF), so both
//! terminators end a line here and the empty lines between them are skipped; the protocol's characters are the
//! printable ASCII ones. A checksum is optional: `:` and two hex digits before the footer, the two's complement of
//! the 8-bit sum of the bytes between the type character and the colon.

use std::collections::VecDeque;

use crate::error::ZaberProtocolError;

/// The most bytes a line may hold before its terminator. A message of the protocol is at most 80 characters on
/// most firmware (longer content is split over continuation lines, which this crate does not use); 256 leaves
/// room without letting a stream of junk grow a buffer without bound.
pub const MAX_LINE: usize = 256;

/// Turns pushed bytes into lines (without terminators), for either side of the link.
#[derive(Debug, Default, Clone)]
pub struct LineSplitter {
    pending: VecDeque<u8>,
    line: Vec<u8>,
    /// Inside an overlong line, already reported: drop bytes up to the next terminator.
    skipping: bool,
}

impl LineSplitter {
    /// An empty splitter.
    pub fn new() -> Self {
        Self::default()
    }

    /// Queues received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.pending.extend(bytes);
    }

    /// Bytes held, queued or in the current line.
    pub fn buffered_len(&self) -> usize {
        self.pending.len() + self.line.len()
    }

    /// Drops everything held (after a reconnect, bytes in flight belong to nobody).
    pub fn clear(&mut self) {
        self.pending.clear();
        self.line.clear();
        self.skipping = false;
    }

    /// The next complete non-empty line as text; `None` when more bytes are needed.
    ///
    /// # Errors
    /// [`ZaberProtocolError::LineTooLong`] once per overlong line; [`ZaberProtocolError::BadCharacter`] for a
    /// line with a byte outside printable ASCII.
    pub fn next_line(&mut self) -> Option<Result<String, ZaberProtocolError>> {
        while let Some(byte) = self.pending.pop_front() {
            let end = byte == b'\r' || byte == b'\n';
            if self.skipping {
                self.skipping = !end;
                continue;
            }
            if end {
                let line = std::mem::take(&mut self.line);
                if line.is_empty() {
                    continue;
                }
                return Some(printable(line));
            }
            if self.line.len() == MAX_LINE {
                self.line.clear();
                self.skipping = true;
                return Some(Err(ZaberProtocolError::LineTooLong { max_bytes: MAX_LINE }));
            }
            self.line.push(byte);
        }
        None
    }
}

fn printable(line: Vec<u8>) -> Result<String, ZaberProtocolError> {
    if let Some((column, &byte)) = line.iter().enumerate().find(|(_, b)| !(32..=126).contains(*b)) {
        return Err(ZaberProtocolError::BadCharacter { byte, column });
    }
    // Printable ASCII is UTF-8.
    String::from_utf8(line)
        .map_err(|e| ZaberProtocolError::BadCharacter { byte: 0, column: e.utf8_error().valid_up_to() })
}

/// The checksum of `content` (the bytes between the type character and the colon): the two's complement of their
/// 8-bit sum, so that content and checksum sum to 0 modulo 256.
pub fn lrc(content: &[u8]) -> u8 {
    let sum = content.iter().fold(0u8, |sum, b| sum.wrapping_add(*b));
    sum.wrapping_neg()
}

/// Splits a line after its type character into content and checksum, verifying the checksum when there is one: a
/// colon and two hex digits at the end (a colon elsewhere is content: help text has them).
///
/// # Errors
/// [`ZaberProtocolError::Checksum`] when a checksum is present and wrong.
pub(crate) fn strip_checksum<'a>(body: &'a str, line: &str) -> Result<&'a str, ZaberProtocolError> {
    let Some((content, sum)) = body.rsplit_once(':') else { return Ok(body) };
    let Some(sum) = (sum.len() == 2).then(|| u8::from_str_radix(sum, 16).ok()).flatten() else { return Ok(body) };
    if lrc(content.as_bytes()) == sum {
        Ok(content)
    } else {
        Err(ZaberProtocolError::Checksum { line: line.to_owned() })
    }
}

/// Appends `:HH` (the checksum of `content`) to `content`.
pub(crate) fn with_checksum(content: &str) -> String {
    format!("{content}:{:02X}", lrc(content.as_bytes()))
}

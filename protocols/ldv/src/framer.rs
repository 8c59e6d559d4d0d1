//! Splitting a byte stream into lines: terminators, the length limit with resynchronisation, the character set.

use std::collections::VecDeque;

use crate::error::LdvProtocolError;

/// The longest line, bytes, terminator included: [`MAX_LINE_CONTENT`] bytes of content and CR LF.
pub const MAX_LINE_LEN: usize = 128;

/// The most content bytes a line may hold before its terminator.
pub const MAX_LINE_CONTENT: usize = MAX_LINE_LEN - 2;

/// Turns pushed bytes into line contents. Lines end at CR or LF (so CR LF is a line and an empty line); blank lines
/// are skipped. Holds the pushed bytes not yet scanned plus at most [`MAX_LINE_CONTENT`] bytes of the current line.
#[derive(Debug, Default)]
pub(crate) struct LineFramer {
    /// Bytes pushed and not yet scanned.
    pending: VecDeque<u8>,
    /// Content of the line being assembled; never longer than MAX_LINE_CONTENT.
    line: Vec<u8>,
    /// Inside an overlong line, already reported: drop bytes up to the next terminator.
    discarding: bool,
}

impl LineFramer {
    pub(crate) fn push(&mut self, bytes: &[u8]) {
        self.pending.extend(bytes);
    }

    /// Bytes held: pending plus the partial line.
    pub(crate) fn buffered_len(&self) -> usize {
        self.pending.len() + self.line.len()
    }

    pub(crate) fn clear(&mut self) {
        self.pending.clear();
        self.line.clear();
        self.discarding = false;
    }

    /// The next complete, non-blank line's content, or a line-level error; `None` when more bytes are needed.
    pub(crate) fn next_line(&mut self) -> Option<Result<String, LdvProtocolError>> {
        while let Some(byte) = self.pending.pop_front() {
            match byte {
                b'\r' | b'\n' if self.discarding => self.discarding = false,
                b'\r' | b'\n' => {
                    let result = check_line(&self.line);
                    self.line.clear();
                    match result {
                        Ok(line) if line.trim_matches(' ').is_empty() => continue,
                        other => return Some(other),
                    }
                }
                _ if self.discarding => {}
                _ if self.line.len() == MAX_LINE_CONTENT => {
                    // Report now, once; the rest of the line is dropped and decoding resumes after its terminator.
                    self.line.clear();
                    self.discarding = true;
                    return Some(Err(LdvProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT }));
                }
                _ => self.line.push(byte),
            }
        }
        None
    }
}

/// The line's content as text, if every byte is printable ASCII.
fn check_line(line: &[u8]) -> Result<String, LdvProtocolError> {
    match line.iter().position(|b| !(0x20..=0x7e).contains(b)) {
        Some(column) => Err(LdvProtocolError::BadCharacter { byte: line[column], column }),
        None => Ok(line.iter().map(|&b| char::from(b)).collect()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(input: &[u8]) -> Vec<Result<String, LdvProtocolError>> {
        let mut framer = LineFramer::default();
        framer.push(input);
        std::iter::from_fn(|| framer.next_line()).collect()
    }

    #[test]
    fn every_terminator_ends_a_line_and_blank_lines_vanish() {
        let got = lines(b"A\rB\nC\r\nD\n\r  \r\n\rE");
        let want: Vec<Result<String, LdvProtocolError>> =
            ["A", "B", "C", "D"].iter().map(|s| Ok((*s).to_owned())).collect();
        assert_eq!(got, want, "E has no terminator yet and must wait");
    }

    #[test]
    fn longest_line_passes_and_one_byte_more_is_reported_once() {
        let longest = "x".repeat(MAX_LINE_CONTENT);
        assert_eq!(lines(format!("{longest}\r").as_bytes()), [Ok(longest.clone())]);
        let got = lines(format!("{longest}yyyyyyyy\r\nOK\r").as_bytes());
        assert_eq!(got, [Err(LdvProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT }), Ok("OK".to_owned())]);
    }

    #[test]
    fn memory_stays_bounded_without_terminators() {
        let mut framer = LineFramer::default();
        let mut errors = 0;
        for _ in 0..1000 {
            framer.push(&[b'z'; 97]);
            while let Some(result) = framer.next_line() {
                assert!(result.is_err());
                errors += 1;
            }
            assert!(framer.buffered_len() <= MAX_LINE_CONTENT);
        }
        assert_eq!(errors, 1, "one endless line is one error");
    }

    #[test]
    fn bad_characters_are_reported_with_their_column() {
        let got = lines(b"PO\x00S?\rSIG\xff\rOK\r");
        assert_eq!(got[0], Err(LdvProtocolError::BadCharacter { byte: 0, column: 2 }));
        assert_eq!(got[1], Err(LdvProtocolError::BadCharacter { byte: 0xff, column: 3 }));
        assert_eq!(got[2], Ok("OK".to_owned()));
    }
}

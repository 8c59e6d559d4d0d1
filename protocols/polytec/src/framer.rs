//! Splitting a byte stream into lines: the LF terminator (a CR before it is dropped), the length limit, the
//! character set. Both directions use it: the host for reply lines, the device for request lines.

use std::collections::VecDeque;

use crate::error::PolytecProtocolError;

/// The most content bytes a line may hold before its terminator. The longest line of the command set is a `Set`
/// of a decoder's range (under 50 bytes) and the longest reply a `GetDevInfo` list of ranges (about 150 bytes for a
/// 12-range decoder); 512 leaves room for any unit without letting a stream of junk grow a buffer without bound.
pub const MAX_LINE_CONTENT: usize = 512;

/// Turns pushed bytes into line contents. A line ends at LF; a CR before the LF is dropped (the manual's lines end
/// in LF alone, but a host that sends CR LF is understood). Empty lines are skipped.
#[derive(Debug, Default)]
pub(crate) struct LineFramer {
    pending: VecDeque<u8>,
    line: Vec<u8>,
    /// Inside an overlong line, already reported: drop bytes up to the next terminator.
    discarding: bool,
}

impl LineFramer {
    pub(crate) fn push(&mut self, bytes: &[u8]) {
        self.pending.extend(bytes);
    }

    pub(crate) fn buffered_len(&self) -> usize {
        self.pending.len() + self.line.len()
    }

    pub(crate) fn clear(&mut self) {
        self.pending.clear();
        self.line.clear();
        self.discarding = false;
    }

    /// The next complete, non-empty line, or a line-level error; `None` when more bytes are needed.
    pub(crate) fn next_line(&mut self) -> Option<Result<String, PolytecProtocolError>> {
        while let Some(byte) = self.pending.pop_front() {
            match byte {
                b'\n' if self.discarding => self.discarding = false,
                b'\n' => {
                    if self.line.last() == Some(&b'\r') {
                        self.line.pop();
                    }
                    let result = check_line(&self.line);
                    self.line.clear();
                    match result {
                        Ok(line) if line.trim().is_empty() => continue,
                        other => return Some(other),
                    }
                }
                _ if self.discarding => {}
                _ if self.line.len() == MAX_LINE_CONTENT => {
                    self.line.clear();
                    self.discarding = true;
                    return Some(Err(PolytecProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT }));
                }
                _ => self.line.push(byte),
            }
        }
        None
    }
}

/// The line as text: UTF-8 (a decoder's `µm` is not ASCII) without control characters.
fn check_line(line: &[u8]) -> Result<String, PolytecProtocolError> {
    let text = std::str::from_utf8(line).map_err(|e| {
        let column = e.valid_up_to();
        PolytecProtocolError::BadCharacter { byte: line.get(column).copied().unwrap_or(0), column }
    })?;
    if let Some((column, c)) = text.char_indices().find(|(_, c)| c.is_control()) {
        return Err(PolytecProtocolError::BadCharacter { byte: u8::try_from(u32::from(c)).unwrap_or(0xff), column });
    }
    Ok(text.to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(input: &[u8]) -> Vec<Result<String, PolytecProtocolError>> {
        let mut framer = LineFramer::default();
        framer.push(input);
        std::iter::from_fn(|| framer.next_line()).collect()
    }

    #[test]
    fn lf_ends_a_line_cr_before_it_is_dropped_and_empty_lines_vanish() {
        let got = lines(b"A\nB\r\n\n\r\nC");
        assert_eq!(got, [Ok("A".to_owned()), Ok("B".to_owned())], "C has no terminator yet");
    }

    #[test]
    fn longest_line_passes_and_one_byte_more_is_reported_once() {
        let longest = "x".repeat(MAX_LINE_CONTENT);
        assert_eq!(lines(format!("{longest}\n").as_bytes()), [Ok(longest.clone())]);
        let got = lines(format!("{longest}yyyy\nOn\n").as_bytes());
        assert_eq!(got, [Err(PolytecProtocolError::LineTooLong { max_bytes: MAX_LINE_CONTENT }), Ok("On".into())]);
    }

    #[test]
    fn memory_stays_bounded_without_terminators() {
        let mut framer = LineFramer::default();
        let mut errors = 0;
        for _ in 0..200 {
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
    fn bad_bytes_are_reported_with_their_column_and_micro_sign_passes() {
        let got = lines(b"Ra\x00ge\n5\xff\n50\xc2\xb5m/V\n");
        assert_eq!(got[0], Err(PolytecProtocolError::BadCharacter { byte: 0, column: 2 }));
        assert_eq!(got[1], Err(PolytecProtocolError::BadCharacter { byte: 0xff, column: 1 }));
        assert_eq!(got[2], Ok("50µm/V".to_owned()));
    }
}

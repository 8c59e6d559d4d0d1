//! Replies (controller to host): one line of text per `Get` or `GetDevInfo`, ended by LF; with the interface's
//! echo on, the request line comes back first.

use crate::error::PolytecProtocolError;
use crate::framer::LineFramer;
use crate::request::Request;

/// What a reply line says, for the host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reply {
    /// A request line echoed (the interface's `Echo` is `On`): this request's, or an earlier one's that arrived
    /// late; no answer is ever spelt like a request. The answer follows on a later line.
    Echo,
    /// The unit has no such item or attribute: `Not Available` (ranges, frequencies, focus) or `not Installed`
    /// (a decoder's name), any letter case.
    NotAvailable,
    /// The answer's text, trimmed.
    Text(String),
}

impl Reply {
    /// Classifies `line` as the reply to `request`.
    pub fn classify(line: &str, request: &Request) -> Self {
        let text = line.trim();
        if text == request.to_string() || Request::parse(text).is_ok() {
            Reply::Echo
        } else if text.eq_ignore_ascii_case("Not Available") || text.eq_ignore_ascii_case("not Installed") {
            Reply::NotAvailable
        } else {
            Reply::Text(text.to_owned())
        }
    }

    /// The reply as the line the controller sends (for the mock controller): text and LF.
    pub fn encode(text: &str) -> Vec<u8> {
        let mut bytes = text.as_bytes().to_vec();
        bytes.push(b'\n');
        bytes
    }
}

/// The spelling of [`Reply::NotAvailable`] the controller sends.
pub const NOT_AVAILABLE: &str = "Not Available";

/// The items of a `GetDevInfo` list (`1mm/s/V,5mm/s/V,25mm/s/V`; `0,3300` for a focus range): comma-separated,
/// trimmed, empty items dropped.
pub fn split_list(text: &str) -> Vec<&str> {
    text.split(',').map(str::trim).filter(|s| !s.is_empty()).collect()
}

/// An unsigned integer reply (`Get,SignalLevel,0,Value`: `87`), at most 9 digits.
///
/// # Errors
/// [`PolytecProtocolError::BadNumber`] for anything else.
pub fn parse_count(text: &str) -> Result<u32, PolytecProtocolError> {
    let t = text.trim();
    if t.is_empty() || t.len() > 9 || !t.bytes().all(|b| b.is_ascii_digit()) {
        return Err(PolytecProtocolError::BadNumber { text: t.chars().take(64).collect(), what: "an integer" });
    }
    t.parse().map_err(|_| PolytecProtocolError::BadNumber { text: t.to_owned(), what: "an integer" })
}

/// The host side's decoder: bytes from the controller in, reply lines out.
#[derive(Debug, Default)]
pub struct ReplyDecoder {
    framer: LineFramer,
}

impl ReplyDecoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.framer.push(bytes);
    }

    /// The next complete line, or why it did not decode; `None` when more bytes are needed.
    pub fn poll(&mut self) -> Option<Result<String, PolytecProtocolError>> {
        self.framer.next_line()
    }

    /// Bytes held (a partial line among them).
    pub fn buffered_len(&self) -> usize {
        self.framer.buffered_len()
    }

    /// Drops everything held (after a timeout, before a retry).
    pub fn clear(&mut self) {
        self.framer.clear();
    }
}

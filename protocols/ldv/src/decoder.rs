//! Incremental decoders: bytes in, typed messages out, at any split of the input.

use std::fmt;
use std::marker::PhantomData;

use crate::command::Command;
use crate::error::LdvProtocolError;
use crate::framer::LineFramer;
use crate::reply::Reply;

mod sealed {
    pub trait Sealed {}
    impl Sealed for crate::Command {}
    impl Sealed for crate::Reply {}
}

/// A message decoded from one line: [`Command`] (device side) or [`Reply`] (host side).
pub trait LineMessage: Sized + sealed::Sealed {
    /// Parses one line's content, without its terminator.
    ///
    /// # Errors
    /// As [`Command::parse_line`] or [`Reply::parse_line`].
    fn parse_line(line: &str) -> Result<Self, LdvProtocolError>;
}

impl LineMessage for Command {
    fn parse_line(line: &str) -> Result<Self, LdvProtocolError> {
        Command::parse_line(line)
    }
}

impl LineMessage for Reply {
    fn parse_line(line: &str) -> Result<Self, LdvProtocolError> {
        Reply::parse_line(line)
    }
}

/// Decodes a byte stream into messages of type `M`, one per non-blank line: [`push`](Self::push) bytes as they
/// arrive, split anywhere, then [`poll`](Self::poll) (or [`drain`](Self::drain)) until it returns `None`.
///
/// Lines end at CR, LF or CR LF; blank lines are skipped. Each failed line gives one `Err` and decoding goes on
/// with the next line: an overlong line is reported as soon as it passes [`crate::MAX_LINE_CONTENT`] bytes and
/// dropped up to its terminator.
///
/// Memory: the decoder holds the bytes pushed and not yet polled, plus at most [`crate::MAX_LINE_CONTENT`] bytes
/// of the current line. Once `poll` has returned `None`, [`buffered_len`](Self::buffered_len) is at most
/// [`crate::MAX_LINE_CONTENT`], whatever the input.
pub struct LineDecoder<M> {
    framer: LineFramer,
    message: PhantomData<fn() -> M>,
}

/// The device side's decoder: host bytes in, [`Command`]s out.
pub type CommandDecoder = LineDecoder<Command>;

/// The host side's decoder: controller bytes in, [`Reply`]s out.
pub type ReplyDecoder = LineDecoder<Reply>;

impl<M: LineMessage> LineDecoder<M> {
    /// An empty decoder.
    pub fn new() -> Self {
        Self { framer: LineFramer::default(), message: PhantomData }
    }

    /// Appends received bytes. Nothing is decoded until [`poll`](Self::poll).
    pub fn push(&mut self, bytes: &[u8]) {
        self.framer.push(bytes);
    }

    /// The next message, or the error of the next bad line; `None` when the bytes pushed so far hold no further
    /// complete line.
    pub fn poll(&mut self) -> Option<Result<M, LdvProtocolError>> {
        self.framer.next_line().map(|line| line.and_then(|line| M::parse_line(&line)))
    }

    /// Polls until `None`: every message completed by the bytes pushed so far.
    pub fn drain(&mut self) -> impl Iterator<Item = Result<M, LdvProtocolError>> + '_ {
        std::iter::from_fn(|| self.poll())
    }

    /// Bytes held: pushed and not yet scanned, plus the partial line.
    pub fn buffered_len(&self) -> usize {
        self.framer.buffered_len()
    }

    /// Drops every byte held, the partial line included (for example after the port was reopened).
    pub fn clear(&mut self) {
        self.framer.clear();
    }
}

impl<M: LineMessage> Default for LineDecoder<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M> fmt::Debug for LineDecoder<M> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LineDecoder").field("framer", &self.framer).finish()
    }
}

//! Command and reply over the serial line: each command carries a message id, and the reply with the same device,
//! axis and id answers it (*Manual, Message Format*: "message ids"), so that a late reply to an earlier command, an
//! alert or an info line is never taken for the answer.

use metaplate_ldv::{LineError, SerialLine};
use metaplate_zaber_protocol::{Command, LineSplitter, MAX_ID, Message, Reply, ReplyFlag};

use crate::zaber::error::ZaberError;

/// How many unrelated lines (alerts, info, stale replies, noise) a request reads past before it gives up: bounds
/// the time a chattering line can hold it.
const MAX_SKIPPED_LINES: usize = 64;

/// The chain's line and what has been read of it.
pub(crate) struct Link<L> {
    line: L,
    splitter: LineSplitter,
    next_id: u8,
    reply_timeout_s: f64,
}

impl<L: SerialLine> Link<L> {
    pub(crate) fn new(line: L, reply_timeout_s: f64) -> Self {
        Self { line, splitter: LineSplitter::new(), next_id: 0, reply_timeout_s }
    }

    /// Reopens the line; what was read of the old one is dropped.
    pub(crate) fn reopen(&mut self) -> Result<(), ZaberError> {
        self.splitter.clear();
        self.line.reopen().map_err(ZaberError::Line)
    }

    /// Sends `text` to `device`'s `axis` and returns the accepted reply.
    ///
    /// # Errors
    /// [`ZaberError::Rejected`] for `RJ`; [`ZaberError::NoReply`] after the timeout; [`ZaberError::Line`].
    pub(crate) fn request(&mut self, device: u8, axis: u8, text: &str) -> Result<Reply, ZaberError> {
        let id = self.next_id;
        self.next_id = if id >= MAX_ID { 0 } else { id + 1 };
        let command = Command { device, axis, id: Some(id), text: text.to_owned() };
        self.line.write_all(&command.encode(false)).map_err(|e| self.lost(e, &command))?;
        let mut skipped = 0;
        loop {
            while let Some(line) = self.splitter.next_line() {
                if let Ok(Message::Reply(reply)) = line.and_then(|line| Message::parse(&line))
                    && (reply.device, reply.axis, reply.id) == (device, axis, Some(id))
                {
                    return match reply.flag {
                        ReplyFlag::Ok => Ok(reply),
                        ReplyFlag::Rejected => {
                            Err(ZaberError::Rejected { device, axis, command: command.text, reason: reply.data })
                        }
                    };
                }
                skipped += 1;
                if skipped > MAX_SKIPPED_LINES {
                    return Err(no_reply(&command));
                }
            }
            let mut buf = [0u8; 256];
            let n = self.line.read(&mut buf, self.reply_timeout_s).map_err(|e| self.lost(e, &command))?;
            self.splitter.push(buf.get(..n).unwrap_or_default());
        }
    }

    /// Sends `text` and parses the reply's data as one integer.
    pub(crate) fn get_i64(&mut self, device: u8, axis: u8, text: &str) -> Result<i64, ZaberError> {
        let reply = self.request(device, axis, text)?;
        reply.data.trim().parse().map_err(|_| ZaberError::BadReply {
            device,
            axis,
            command: text.to_owned(),
            data: reply.data,
        })
    }

    fn lost(&self, error: LineError, command: &Command) -> ZaberError {
        match error {
            LineError::Timeout => no_reply(command),
            other => ZaberError::Line(other),
        }
    }
}

fn no_reply(command: &Command) -> ZaberError {
    ZaberError::NoReply { device: command.device, axis: command.axis, command: command.text.clone() }
}

//! One request at a time on the line, with bounded retries: the transaction layer under the Polytec driver.

use std::time::{Duration, Instant};

use metaplate_core::vibrometer::VibrometerError;
use metaplate_polytec_protocol::{Reply, ReplyDecoder, Request};

use crate::line::{LineError, SerialLine};
use crate::policy::RetryPolicy;

/// The answer to a query: the unit's text, or its `Not Available`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Answer {
    /// The reply's text, trimmed.
    Text(String),
    /// `Not Available` / `not Installed`: the unit has no such item.
    NotAvailable,
}

/// The line, the reply decoder and the retry policy.
///
/// Before every request, bytes already waiting are discarded (a late reply to an earlier request, the rest of a
/// reply after a garbled byte), so a reply read is the reply to the request just sent. An echoed request line is
/// skipped. A query's reply is checked by the caller's parser; a reply that does not parse counts as a miss, like
/// a timeout, and the request is sent again (every request here is idempotent: absolute settings and queries).
pub(crate) struct Link<T: SerialLine> {
    line: T,
    decoder: ReplyDecoder,
    policy: RetryPolicy,
}

impl<T: SerialLine> Link<T> {
    pub(crate) fn new(line: T, policy: RetryPolicy) -> Self {
        Self { line, decoder: ReplyDecoder::new(), policy }
    }

    pub(crate) fn line(&self) -> &T {
        &self.line
    }

    pub(crate) fn reopen(&mut self) -> Result<(), VibrometerError> {
        self.decoder.clear();
        self.line.reopen().map_err(|e| VibrometerError::Disconnected { reason: e.to_string() })
    }

    /// Sends `request` (a `Get` or `GetDevInfo`) until its reply parses with `parse`.
    ///
    /// # Errors
    /// `Disconnected` when the line is gone; `Timeout` when every attempt missed (no reply, undecodable or
    /// unparsable), naming the last miss.
    pub(crate) fn query<V>(
        &mut self,
        request: &Request,
        mut parse: impl FnMut(&Answer) -> Result<V, String>,
    ) -> Result<V, VibrometerError> {
        let mut last_miss = String::new();
        for _ in 0..self.policy.attempts {
            self.send(request)?;
            match self.await_answer(request)? {
                Ok(answer) => match parse(&answer) {
                    Ok(value) => return Ok(value),
                    Err(why) => last_miss = format!("unusable reply {answer:?}: {why}"),
                },
                Err(miss) => last_miss = miss,
            }
        }
        Err(VibrometerError::Timeout {
            command: request.to_string(),
            detail: format!("{} attempts, the last: {last_miss}", self.policy.attempts),
        })
    }

    /// Sends a `Set` (which gets no reply).
    ///
    /// # Errors
    /// `Disconnected` when the line is gone; `Timeout` when it does not take the bytes.
    pub(crate) fn send(&mut self, request: &Request) -> Result<(), VibrometerError> {
        self.discard_waiting()?;
        match self.line.write_all(&request.encode()) {
            Ok(()) => Ok(()),
            Err(LineError::Disconnected { reason }) => Err(VibrometerError::Disconnected { reason }),
            Err(LineError::Timeout) => Err(VibrometerError::Timeout {
                command: request.to_string(),
                detail: "the line did not take the bytes".into(),
            }),
        }
    }

    /// Drops every byte already received and any partial line.
    fn discard_waiting(&mut self) -> Result<(), VibrometerError> {
        let mut buf = [0u8; 256];
        // Bounded: a device that streams without end is cut off after 64 reads and its bytes read as replies.
        for _ in 0..64 {
            match self.line.read(&mut buf, 0.0) {
                Ok(_) => {}
                Err(LineError::Timeout) => break,
                Err(LineError::Disconnected { reason }) => return Err(VibrometerError::Disconnected { reason }),
            }
        }
        self.decoder.clear();
        Ok(())
    }

    /// The reply to `request`, skipping its echo; the inner `Err` says why there is none.
    fn await_answer(&mut self, request: &Request) -> Result<Result<Answer, String>, VibrometerError> {
        let timeout_s = self.policy.scaled_timeout_s();
        let deadline = Instant::now() + Duration::try_from_secs_f64(timeout_s).unwrap_or(Duration::ZERO);
        let mut buf = [0u8; 256];
        loop {
            while let Some(line) = self.decoder.poll() {
                match line {
                    Err(e) => return Ok(Err(format!("undecodable reply ({e})"))),
                    Ok(text) => match Reply::classify(&text, request) {
                        Reply::Echo => continue,
                        Reply::NotAvailable => return Ok(Ok(Answer::NotAvailable)),
                        Reply::Text(t) => return Ok(Ok(Answer::Text(t))),
                    },
                }
            }
            let remaining_s = deadline.saturating_duration_since(Instant::now()).as_secs_f64();
            if remaining_s <= 0.0 {
                return Ok(Err(format!("no reply within {timeout_s} s")));
            }
            match self.line.read(&mut buf, remaining_s) {
                Ok(n) => self.decoder.push(buf.get(..n).unwrap_or(&buf)),
                Err(LineError::Timeout) => return Ok(Err(format!("no reply within {timeout_s} s"))),
                Err(LineError::Disconnected { reason }) => return Err(VibrometerError::Disconnected { reason }),
            }
        }
    }
}

//! The keypad driver: timestamped key events from any [`HidInput`].

use std::collections::VecDeque;
use std::sync::Arc;

use metaplate_core::clock::Clock;

use crate::transport::{HidInput, TransportError};
use metaplate_keypad_protocol::{BootDecoder, Key, KeyAction, ReportError};

/// One key press or release.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyEvent {
    /// Which key (usage ID on the HID keyboard page).
    pub key: Key,
    /// Pressed or released.
    pub action: KeyAction,
    /// When its report was read, seconds on the driver's [`Clock`]. The device itself polls (USB full speed:
    /// 1 to 10 ms, set by its descriptor), so a response time is known to that interval plus scheduling delay,
    /// and every change in one report carries the same time.
    pub time_s: f64,
}

/// Why the keypad failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KeypadError {
    /// The link failed.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The device sent a report that is not a boot keyboard report (roll-over is not an error: it is skipped).
    #[error("bad keypad report: {0}")]
    Report(#[from] ReportError),
    /// A call with an invalid argument (a timeout that is negative or not finite).
    #[error("invalid keypad request: {0}")]
    Request(String),
}

impl KeypadError {
    /// Whether [`Keypad::reopen`] may help.
    pub fn suggests_reopen(&self) -> bool {
        matches!(self, KeypadError::Transport(TransportError::Disconnected(_)))
    }
}

/// What the driver expects in front of each boot report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReportPrefix {
    /// Nothing: a boot keyboard interface without report IDs (the usual case).
    #[default]
    None,
    /// A report ID byte: reports with this ID are boot keyboard reports, others (consumer keys on a composite
    /// device) are ignored.
    ReportId(u8),
}

/// A response keypad that enumerates as a USB HID keyboard.
pub struct Keypad<T: HidInput> {
    transport: T,
    clock: Arc<dyn Clock>,
    prefix: ReportPrefix,
    decoder: BootDecoder,
    pending: VecDeque<KeyEvent>,
    roll_overs: u64,
}

impl<T: HidInput> Keypad<T> {
    /// A keypad on `transport`, timestamping events with `clock`.
    pub fn new(transport: T, clock: Arc<dyn Clock>, prefix: ReportPrefix) -> Self {
        Self { transport, clock, prefix, decoder: BootDecoder::new(), pending: VecDeque::new(), roll_overs: 0 }
    }

    /// The transport (for tests).
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The transport, mutably.
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }

    /// Keys held now, as far as the reports read so far tell.
    pub fn held(&self) -> impl Iterator<Item = Key> + '_ {
        self.decoder.held().iter().copied()
    }

    /// Roll-over reports skipped so far (too many keys held at once: a participant leaning on the pad).
    pub fn roll_overs(&self) -> u64 {
        self.roll_overs
    }

    /// The next key event, waiting at most `timeout_s` seconds on the driver's clock (valid range: finite,
    /// `>= 0`; 0 takes only what has already arrived). `Ok(None)` when nothing happened in time. Reports that
    /// change nothing (repeats) and roll-over reports are skipped.
    ///
    /// # Errors
    /// [`KeypadError::Request`] for a bad timeout; [`KeypadError::Report`] for a report that is not a boot keyboard
    /// report (nothing is lost: the next call goes on with the next report); [`KeypadError::Transport`].
    pub fn next_event(&mut self, timeout_s: f64) -> Result<Option<KeyEvent>, KeypadError> {
        if !(timeout_s.is_finite() && timeout_s >= 0.0) {
            return Err(KeypadError::Request(format!("timeout {timeout_s} s (must be finite and >= 0)")));
        }
        if let Some(event) = self.pending.pop_front() {
            return Ok(Some(event));
        }
        let deadline_s = self.clock.now_s() + timeout_s;
        loop {
            let remaining_s = (deadline_s - self.clock.now_s()).max(0.0);
            let Some(report) = self.transport.read_report(remaining_s)? else { return Ok(None) };
            let time_s = self.clock.now_s();
            if let Some(body) = self.strip_prefix(&report) {
                match self.decoder.decode(body) {
                    Ok(changes) => self.pending.extend(changes.into_iter().map(|change| KeyEvent {
                        key: change.key,
                        action: change.action,
                        time_s,
                    })),
                    Err(ReportError::RollOver) => self.roll_overs += 1,
                    Err(error) => return Err(error.into()),
                }
            }
            if let Some(event) = self.pending.pop_front() {
                return Ok(Some(event));
            }
            if self.clock.now_s() >= deadline_s {
                return Ok(None);
            }
        }
    }

    /// Reopens the device; the held keys are forgotten (its state is unknown after a reconnection) and queued
    /// events are dropped.
    ///
    /// # Errors
    /// [`KeypadError::Transport`] while the device is absent.
    pub fn reopen(&mut self) -> Result<(), KeypadError> {
        self.pending.clear();
        self.decoder.reset();
        self.transport.reopen()?;
        Ok(())
    }

    /// The boot report inside `report`, or `None` for a report with another ID.
    fn strip_prefix<'a>(&self, report: &'a [u8]) -> Option<&'a [u8]> {
        match self.prefix {
            ReportPrefix::None => Some(report),
            ReportPrefix::ReportId(id) => match report.split_first() {
                Some((&first, body)) if first == id => Some(body),
                _ => None,
            },
        }
    }
}

//! Messages, device to host: replies (`@`), info (`#`) and alerts (`!`).
//!
//! *Manual, Message Format, Replies*: `@DD A [id] FL STATUS WW data`: the two-digit device address, the axis (0
//! for the device), the command's message id if it had one, `OK` or `RJ` (rejected: the data names why, for
//! example `BADCOMMAND`, `BADDATA`, `BADAXIS`), `BUSY` while the axis moves or `IDLE`, the warning flag (`--` for
//! none) and the data (`0` when the command returns nothing). *Info*: `#DD A data`, extra lines after a reply
//! (help text, a `get` spread over lines). *Alerts*: `!DD A STATUS WW`, sent unasked (when a move ends, with
//! `comm.alert` on). Devices end every message with CR LF.

use crate::error::ZaberProtocolError;
use crate::line::{strip_checksum, with_checksum};
use crate::warning::WarningFlag;

/// Whether a command was accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplyFlag {
    /// `OK`.
    Ok,
    /// `RJ`: rejected; the reply's data is the reason.
    Rejected,
}

/// Whether the device or axis is moving.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// `BUSY`: moving.
    Busy,
    /// `IDLE`: at rest.
    Idle,
}

/// A reply to a command.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    /// Device address.
    pub device: u8,
    /// Axis number, 0 for the device.
    pub axis: u8,
    /// The command's message id, if it had one.
    pub id: Option<u8>,
    /// Accepted or rejected.
    pub flag: ReplyFlag,
    /// Moving or at rest.
    pub status: Status,
    /// The highest-priority warning flag.
    pub warning: WarningFlag,
    /// The data: a value, `0`, or the rejection reason.
    pub data: String,
}

/// A message from a device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Message {
    /// `@...`: a reply.
    Reply(Reply),
    /// `#DD A data`: an info line.
    Info {
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// The text.
        data: String,
    },
    /// `!DD A STATUS WW`: an alert.
    Alert {
        /// Device address.
        device: u8,
        /// Axis number.
        axis: u8,
        /// Moving or at rest.
        status: Status,
        /// The highest-priority warning flag.
        warning: WarningFlag,
    },
}

fn malformed(field: &'static str, line: &str) -> ZaberProtocolError {
    ZaberProtocolError::Malformed { field, line: line.to_owned() }
}

fn number(word: Option<&str>, field: &'static str, max: u8, line: &str) -> Result<u8, ZaberProtocolError> {
    word.filter(|w| w.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|w| w.parse::<u8>().ok())
        .filter(|v| *v <= max)
        .ok_or_else(|| malformed(field, line))
}

fn status(word: Option<&str>, line: &str) -> Result<Status, ZaberProtocolError> {
    match word {
        Some("BUSY") => Ok(Status::Busy),
        Some("IDLE") => Ok(Status::Idle),
        _ => Err(malformed("status", line)),
    }
}

fn warning(word: Option<&str>, line: &str) -> Result<WarningFlag, ZaberProtocolError> {
    word.and_then(WarningFlag::parse).ok_or_else(|| malformed("warning flag", line))
}

impl Message {
    /// Decodes a line (without its terminator), as the host does.
    ///
    /// # Errors
    /// [`ZaberProtocolError::WrongType`] for a line that is no device message (a command echoed by a terminal,
    /// noise); [`ZaberProtocolError::Checksum`]; [`ZaberProtocolError::Malformed`] naming the bad field.
    pub fn parse(line: &str) -> Result<Self, ZaberProtocolError> {
        let mut chars = line.chars();
        let kind = chars.next();
        let body = strip_checksum(chars.as_str(), line)?;
        let mut words = body.split(' ').filter(|w| !w.is_empty()).peekable();
        let device =
            |words: &mut std::iter::Peekable<_>| number(words.next(), "device address", crate::MAX_DEVICE, line);
        match kind {
            Some('@') => {
                let device = device(&mut words)?;
                let axis = number(words.next(), "axis", crate::MAX_AXIS, line)?;
                let id = match words.next_if(|w: &&str| w.bytes().all(|b| b.is_ascii_digit())) {
                    Some(word) => Some(number(Some(word), "message id", crate::MAX_ID, line)?),
                    None => None,
                };
                let flag = match words.next() {
                    Some("OK") => ReplyFlag::Ok,
                    Some("RJ") => ReplyFlag::Rejected,
                    _ => return Err(malformed("reply flag", line)),
                };
                let status = status(words.next(), line)?;
                let warning = warning(words.next(), line)?;
                let data = words.collect::<Vec<_>>().join(" ");
                Ok(Message::Reply(Reply { device, axis, id, flag, status, warning, data }))
            }
            Some('#') => {
                let device = device(&mut words)?;
                let axis = number(words.next(), "axis", crate::MAX_AXIS, line)?;
                Ok(Message::Info { device, axis, data: words.collect::<Vec<_>>().join(" ") })
            }
            Some('!') => {
                let device = device(&mut words)?;
                let axis = number(words.next(), "axis", crate::MAX_AXIS, line)?;
                let status = status(words.next(), line)?;
                let warning = warning(words.next(), line)?;
                Ok(Message::Alert { device, axis, status, warning })
            }
            _ => Err(ZaberProtocolError::WrongType { expected: "device", line: line.to_owned() }),
        }
    }

    /// The line a device sends: the message, `:HH` when `checksum`, CR LF.
    pub fn encode(&self, checksum: bool) -> Vec<u8> {
        let (kind, content) = match self {
            Message::Reply(r) => {
                let id = r.id.map(|id| format!(" {id}")).unwrap_or_default();
                let flag = match r.flag {
                    ReplyFlag::Ok => "OK",
                    ReplyFlag::Rejected => "RJ",
                };
                let data = if r.data.is_empty() { "0" } else { &r.data };
                (
                    '@',
                    format!(
                        "{:02} {}{id} {flag} {} {} {data}",
                        r.device,
                        r.axis,
                        status_word(r.status),
                        r.warning.code()
                    ),
                )
            }
            Message::Info { device, axis, data } => ('#', format!("{device:02} {axis} {data}").trim_end().to_owned()),
            Message::Alert { device, axis, status, warning } => {
                ('!', format!("{device:02} {axis} {} {}", status_word(*status), warning.code()))
            }
        };
        let content = if checksum { with_checksum(&content) } else { content };
        format!("{kind}{content}\r\n").into_bytes()
    }
}

fn status_word(status: Status) -> &'static str {
    match status {
        Status::Busy => "BUSY",
        Status::Idle => "IDLE",
    }
}

//! Commands, host to device: `/device axis [id] command words[:checksum]`.
//!
//! *Manual, Message Format, Commands*: `/` starts a command; the device address (0 or absent: every device),
//! the axis number (0 or absent: the whole device, or every axis) and a message id (0 to 99, echoed in the reply)
//! come first, each a number; then the command's words, separated by single spaces. An empty command (`/1 1`)
//! asks only for a reply: the device's status and warning flag.

use crate::error::ZaberProtocolError;
use crate::line::{strip_checksum, with_checksum};

/// The largest device address (*Manual*: addresses 1 to 99; 0 addresses all).
pub const MAX_DEVICE: u8 = 99;
/// The largest axis number this codec accepts (a controller's axes are numbered from 1).
pub const MAX_AXIS: u8 = 9;
/// The largest message id.
pub const MAX_ID: u8 = 99;

/// One command to a device or axis.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Command {
    /// Device address; 0 for every device on the chain.
    pub device: u8,
    /// Axis number; 0 for the device as a whole.
    pub axis: u8,
    /// Message id, echoed in the reply, if any.
    pub id: Option<u8>,
    /// The command's words, single-spaced (`move abs 1000`, `get pos`); empty for a status request.
    pub text: String,
}

impl Command {
    /// A command without a message id.
    pub fn new(device: u8, axis: u8, text: impl Into<String>) -> Self {
        Self { device, axis, id: None, text: text.into() }
    }

    /// The line to send: `/device axis [id] text`, with `:HH` when `checksum`, ending in LF.
    pub fn encode(&self, checksum: bool) -> Vec<u8> {
        let mut content = format!("{} {}", self.device, self.axis);
        if let Some(id) = self.id {
            content.push_str(&format!(" {id}"));
        }
        if !self.text.is_empty() {
            content.push(' ');
            content.push_str(&self.text);
        }
        let content = if checksum { with_checksum(&content) } else { content };
        format!("/{content}\n").into_bytes()
    }

    /// The command's words.
    pub fn words(&self) -> impl Iterator<Item = &str> {
        self.text.split(' ').filter(|w| !w.is_empty())
    }

    /// Decodes a line (without its terminator), as a device does.
    ///
    /// # Errors
    /// [`ZaberProtocolError::WrongType`] without the leading `/`; [`ZaberProtocolError::Checksum`] for a wrong
    /// checksum; [`ZaberProtocolError::Malformed`] for an address, axis or id out of range.
    pub fn parse(line: &str) -> Result<Self, ZaberProtocolError> {
        let Some(body) = line.strip_prefix('/') else {
            return Err(ZaberProtocolError::WrongType { expected: "command", line: line.to_owned() });
        };
        let body = strip_checksum(body, line)?;
        let mut words = body.split_whitespace().peekable();
        let mut numbers = [None; 3];
        for (slot, (field, max)) in numbers.iter_mut().zip([("device", MAX_DEVICE), ("axis", MAX_AXIS), ("id", MAX_ID)])
        {
            let Some(word) = words.next_if(|w| w.bytes().all(|b| b.is_ascii_digit())) else { break };
            let value = word.parse::<u8>().ok().filter(|v| *v <= max);
            *slot = Some(value.ok_or_else(|| ZaberProtocolError::Malformed { field, line: line.to_owned() })?);
        }
        let text = words.collect::<Vec<_>>().join(" ");
        Ok(Self { device: numbers[0].unwrap_or(0), axis: numbers[1].unwrap_or(0), id: numbers[2], text })
    }
}

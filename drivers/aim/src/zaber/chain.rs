//! What answers on a port: every device of a Zaber chain, asked at once (device address 0), for
//! `metaplate devices` and a hardware file's draft.

use metaplate_ldv::{LineError, SerialLine};
use metaplate_zaber_protocol::{Command, LineSplitter, Message, ReplyFlag};

use crate::zaber::error::ZaberError;

/// How many replies a listing reads at most: a chain has at most 99 devices; more is noise.
const MAX_DEVICES: usize = 99;

/// One device that answered.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChainDevice {
    /// Its address.
    pub address: u8,
    /// Its `deviceid` (Zaber's number for the product).
    pub device_id: String,
}

/// Asks every device on `line` for its `deviceid` (*Manual, Message Format*: device 0 addresses all of them, each
/// replying) and collects the replies that arrive within `timeout_s` of the last one. Lines that are not replies
/// (another instrument's chatter) are skipped; nothing answering is an empty list.
///
/// # Errors
/// [`ZaberError::Line`] when the line is gone.
pub fn list_chain<L: SerialLine>(line: &mut L, timeout_s: f64) -> Result<Vec<ChainDevice>, ZaberError> {
    line.write_all(&Command::new(0, 0, "get deviceid").encode(false)).map_err(ZaberError::Line)?;
    let mut splitter = LineSplitter::new();
    let mut devices: Vec<ChainDevice> = Vec::new();
    let mut buf = [0u8; 256];
    while devices.len() < MAX_DEVICES {
        match line.read(&mut buf, timeout_s) {
            Ok(n) => splitter.push(buf.get(..n).unwrap_or_default()),
            Err(LineError::Timeout) => break,
            Err(other) => return Err(ZaberError::Line(other)),
        }
        while let Some(text) = splitter.next_line() {
            if let Ok(Message::Reply(reply)) = text.and_then(|text| Message::parse(&text))
                && reply.flag == ReplyFlag::Ok
                && !devices.iter().any(|d| d.address == reply.device)
            {
                devices.push(ChainDevice { address: reply.device, device_id: reply.data });
            }
        }
    }
    devices.sort_by_key(|d| d.address);
    Ok(devices)
}

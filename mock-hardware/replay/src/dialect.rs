//! The dialects of the byte devices: what their protocols let a replay do after an injected fault.

use metaplate_daq_protocol::{DeviceDecoder, DeviceMessage, ErrorReport, HostDecoder, encode};
use metaplate_ldv_protocol::{Command, CommandDecoder, Reply, encode_reply};

use crate::engine::Dialect;

/// The LDV controller's line protocol: commands must match byte for byte (every command is absolute and the
/// driver resends it unchanged); a `SYNC <t>` in no recorded exchange (the driver resynchronising after an
/// injected fault) is answered with its echo, as the specification requires of the controller.
#[derive(Debug, Clone, Copy, Default)]
pub struct LdvDialect;

impl Dialect for LdvDialect {
    fn matches(&mut self, recorded: &[u8], got: &[u8], _recovering: bool) -> Result<(), Vec<u8>> {
        if recorded == got { Ok(()) } else { Err(got.to_vec()) }
    }

    fn synthesize(&mut self, got: &[u8]) -> Option<Vec<u8>> {
        let mut decoder = CommandDecoder::new();
        decoder.push(got);
        match decoder.poll()? {
            Ok(Command::Sync(token)) => Some(encode_reply(&Reply::Sync(token))),
            _ => None,
        }
    }

    fn translate_read(&self, recorded: &[u8]) -> Vec<u8> {
        recorded.to_vec()
    }
}

/// The DAQ's bulk protocol: a command frame carries the host's sequence number, which a retry increments. A
/// resent command (same message, another sequence number) matches while the replay recovers from a fault; from
/// then on every command must carry the recorded number plus that offset, and every recorded reply's `of_seq` is
/// shifted by it (the frames re-encoded, so their checksums hold).
#[derive(Debug, Clone, Copy, Default)]
pub struct DaqDialect {
    /// Driver's sequence number minus the recorded one.
    offset: u32,
}

impl DaqDialect {
    /// The current sequence offset (0 until a retry).
    pub fn offset(&self) -> u32 {
        self.offset
    }
}

/// The one command frame in `bytes`, if it is exactly one well-formed frame.
fn command_frame(bytes: &[u8]) -> Option<metaplate_daq_protocol::Frame<metaplate_daq_protocol::HostCommand>> {
    let mut decoder = DeviceDecoder::new();
    decoder.push(bytes);
    let frame = decoder.poll()?.ok()?;
    decoder.poll().is_none().then_some(frame)
}

fn shift(msg: DeviceMessage, offset: u32) -> DeviceMessage {
    match msg {
        DeviceMessage::Info(mut info) => {
            info.of_seq = info.of_seq.wrapping_add(offset);
            DeviceMessage::Info(info)
        }
        DeviceMessage::Ack { of_seq } => DeviceMessage::Ack { of_seq: of_seq.wrapping_add(offset) },
        DeviceMessage::Error(report) => {
            DeviceMessage::Error(ErrorReport { of_seq: report.of_seq.map(|s| s.wrapping_add(offset)), ..report })
        }
        other => other,
    }
}

impl Dialect for DaqDialect {
    fn matches(&mut self, recorded: &[u8], got: &[u8], recovering: bool) -> Result<(), Vec<u8>> {
        if self.offset == 0 && recorded == got {
            return Ok(());
        }
        let (Some(rec), Some(new)) = (command_frame(recorded), command_frame(got)) else {
            return Err(got.to_vec());
        };
        // The driver's frame in the recording's terms: its message under the recorded sequence number.
        let normalised = encode(rec.seq, &new.message).unwrap_or_else(|_| got.to_vec());
        let offset = new.seq.wrapping_sub(rec.seq);
        if rec.message == new.message && (recovering || offset == self.offset) {
            self.offset = offset;
            Ok(())
        } else if rec.message == new.message {
            // Same command, unexpected sequence number: show the driver's bytes as they are.
            Err(got.to_vec())
        } else {
            Err(normalised)
        }
    }

    fn synthesize(&mut self, _got: &[u8]) -> Option<Vec<u8>> {
        None
    }

    fn translate_read(&self, recorded: &[u8]) -> Vec<u8> {
        if self.offset == 0 {
            return recorded.to_vec();
        }
        let mut decoder = HostDecoder::new();
        decoder.push(recorded);
        let mut out = Vec::with_capacity(recorded.len());
        while let Some(frame) = decoder.poll() {
            // A recorded transfer that does not decode whole (torn or corrupt) is delivered as recorded.
            let Ok(frame) = frame else { return recorded.to_vec() };
            let Ok(bytes) = encode(frame.seq, &shift(frame.message, self.offset)) else {
                return recorded.to_vec();
            };
            out.extend_from_slice(&bytes);
        }
        if decoder.buffered_len() > 0 || out.len() != recorded.len() {
            return recorded.to_vec();
        }
        out
    }
}

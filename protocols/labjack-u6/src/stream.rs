//! StreamData packets (bulk IN, endpoint 3) and an incremental decoder for them.
//!
//! Layout (User's Guide section 5.2.14, "StreamData"; LabJackPython `streamData`, `samplesFromPacket`): `14 + 2 s`
//! bytes for SamplesPerPacket `s`:
//!
//! | offset | field |
//! |---|---|
//! | 0 | Checksum8 (over bytes 1-5) |
//! | 1 | `F9` |
//! | 2 | `4 + s` (data words) |
//! | 3 | `C0` |
//! | 4-5 | Checksum16 (over bytes 6 to the end), little-endian |
//! | 6-9 | TimeStamp (u32 LE): reserved, except in an auto-recovery report (errorcode 60): scans discarded |
//! | 10 | PacketNumber: +1 per packet, wrapping at 256 |
//! | 11 | Errorcode: 0; 59 auto-recovery active; 60 auto-recovery report; others end the stream |
//! | 12 .. 12+2s | `s` samples, u16 LE, oldest first, in scan-list order (scans may span packets) |
//! | 12+2s | Backlog: how full the U6's stream buffer was after this packet, 0-255 (256 would be 100 %) |
//! | 13+2s | `00` |
//!
//! A USB transfer on the stream endpoint holds whole packets (several only when a packet is exactly 64 bytes,
//! SamplesPerPacket 25); the decoder nevertheless takes bytes in any chunking.

use crate::checksum::{checksum8, checksum16, seal};
use crate::error::U6Error;
use crate::errorcode::Errorcode;

/// One StreamData packet.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StreamPacket {
    /// TimeStamp (scans discarded, in an auto-recovery report).
    pub timestamp: u32,
    /// PacketNumber.
    pub packet_number: u8,
    /// Errorcode.
    pub errorcode: Errorcode,
    /// The samples, raw 16-bit codes (1 to 25 of them).
    pub samples: Vec<u16>,
    /// Backlog, 0-255.
    pub backlog: u8,
}

/// A StreamData packet's length for `samples_per_packet` samples, bytes.
pub fn packet_len(samples_per_packet: u8) -> usize {
    14 + 2 * usize::from(samples_per_packet)
}

impl StreamPacket {
    /// The packet's bytes, checksums set (device side).
    ///
    /// # Errors
    /// [`U6Error::InvalidField`] for 0 or more than 25 samples.
    pub fn encode(&self) -> Result<Vec<u8>, U6Error> {
        let s =
            u8::try_from(self.samples.len()).ok().filter(|s| (1..=25).contains(s)).ok_or(U6Error::InvalidField {
                what: "StreamData",
                field: "samples",
                value: self.samples.len() as u64,
                reason: "a packet holds 1 to 25 samples",
            })?;
        let mut out = Vec::with_capacity(packet_len(s));
        out.extend_from_slice(&[0, 0xf9, 4 + s, 0xc0, 0, 0]);
        out.extend_from_slice(&self.timestamp.to_le_bytes());
        out.extend_from_slice(&[self.packet_number, self.errorcode.0]);
        for sample in &self.samples {
            out.extend_from_slice(&sample.to_le_bytes());
        }
        out.extend_from_slice(&[self.backlog, 0]);
        seal(&mut out);
        Ok(out)
    }
}

/// Decodes StreamData packets of a known SamplesPerPacket from bytes pushed in any chunking.
///
/// After a corruption it resynchronises on the next bytes that start a packet (`F9`, `4 + s`, `C0` at offsets 1-3
/// with good checksums). Bounded: after [`poll`](Self::poll) returns `None`, less than one packet is buffered.
#[derive(Debug, Clone)]
pub struct StreamDecoder {
    samples_per_packet: u8,
    buf: Vec<u8>,
    /// Bytes skipped since the last packet, reported with the next one found.
    skipped: usize,
}

impl StreamDecoder {
    /// A decoder for packets of `samples_per_packet` samples (1-25; other values are clamped into that range).
    pub fn new(samples_per_packet: u8) -> Self {
        Self { samples_per_packet: samples_per_packet.clamp(1, 25), buf: Vec::new(), skipped: 0 }
    }

    /// The packet length, bytes.
    pub fn packet_len(&self) -> usize {
        packet_len(self.samples_per_packet)
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes buffered, not yet decoded.
    pub fn buffered_len(&self) -> usize {
        self.buf.len()
    }

    /// Forgets buffered bytes (after a stop or a reconnect).
    pub fn clear(&mut self) {
        self.buf.clear();
        self.skipped = 0;
    }

    /// Whether the bytes at `at` may begin a packet, judging only the header bytes already buffered.
    fn may_start(&self, at: usize) -> bool {
        let want = [(1, 0xf9), (2, 4 + self.samples_per_packet), (3, 0xc0)];
        want.iter().all(|&(k, v)| self.buf.get(at + k).is_none_or(|&b| b == v))
    }

    /// The next packet or error, `None` when more bytes are needed.
    ///
    /// # Errors
    /// (as items) [`U6Error::Garbage`] for bytes skipped before a packet (reported once, before it);
    /// [`U6Error::Checksum`] for a packet-shaped run of bytes whose checksums fail (one byte is then skipped);
    /// [`U6Error::InvalidField`] for a packet whose last byte is not 0.
    pub fn poll(&mut self) -> Option<Result<StreamPacket, U6Error>> {
        let len = self.packet_len();
        let start = (0..self.buf.len()).find(|&at| self.may_start(at)).unwrap_or(self.buf.len());
        if start > 0 {
            self.skipped += start;
            self.buf.drain(..start);
        }
        if self.buf.len() < len {
            return None;
        }
        if self.skipped > 0 {
            let skipped_bytes = std::mem::take(&mut self.skipped);
            return Some(Err(U6Error::Garbage { skipped_bytes }));
        }
        let packet = &self.buf[..len];
        let want8 = checksum8(&packet[1..6]);
        let want16 = checksum16(&packet[6..]);
        let got16 = u16::from_le_bytes([packet[4], packet[5]]);
        if packet[0] != want8 || got16 != want16 {
            let error = U6Error::Checksum { what: "StreamData", got8: packet[0], want8, got16, want16 };
            self.buf.drain(..1);
            return Some(Err(error));
        }
        let decoded = decode_packet(packet);
        self.buf.drain(..len);
        Some(decoded)
    }
}

/// A packet whose header and checksums are known good.
fn decode_packet(packet: &[u8]) -> Result<StreamPacket, U6Error> {
    let n = packet.len();
    if packet[n - 1] != 0 {
        return Err(U6Error::InvalidField {
            what: "StreamData",
            field: "last byte",
            value: u64::from(packet[n - 1]),
            reason: "the guide's layout ends with 0x00",
        });
    }
    Ok(StreamPacket {
        timestamp: u32::from_le_bytes([packet[6], packet[7], packet[8], packet[9]]),
        packet_number: packet[10],
        errorcode: Errorcode(packet[11]),
        samples: packet[12..n - 2].chunks_exact(2).map(|p| u16::from_le_bytes([p[0], p[1]])).collect(),
        backlog: packet[n - 2],
    })
}

//! The byte layout's constants (see the crate documentation for the tables) and the little-endian field reader
//! that the decoder uses.

/// The file magic, at offset 0.
pub const MAGIC: [u8; 8] = *b"MPCASSET";
/// The major format version this crate writes and reads.
pub const FORMAT_MAJOR: u16 = 1;
/// The minor format version this crate writes (it reads any minor version of [`FORMAT_MAJOR`]).
pub const FORMAT_MINOR: u16 = 0;

/// Sync word that starts every record.
pub const RECORD_SYNC: [u8; 4] = [0x89, b'R', b'E', b'C'];
/// Sync word that starts the end marker.
pub const END_SYNC: [u8; 4] = [0x89, b'E', b'N', b'D'];

/// Bytes of the header before its identity fields: magic 8, version 2 + 2, header length 2, device kind 1,
/// start time 8.
pub const HEADER_FIXED_LEN: usize = 23;
/// The shortest header: the fixed part, four empty identity fields (one length byte each) and the CRC.
pub const MIN_HEADER_LEN: usize = HEADER_FIXED_LEN + 4 + 4;
/// The longest header a reader accepts, bytes (room for four full identity fields and later minor-version
/// extensions).
pub const MAX_HEADER_LEN: usize = 4096;
/// The longest identity field (vendor, model, serial, firmware), bytes of UTF-8: its length is one byte.
pub const MAX_IDENTITY_FIELD_LEN: usize = 255;

/// Bytes of a record before its payload: sync 4, kind 1, endpoint 2, timestamp 8, payload length 4, head CRC 4.
pub const RECORD_HEAD_LEN: usize = 23;
/// Bytes of the head covered by the head CRC.
pub const RECORD_HEAD_CRC_AT: usize = 19;
/// Bytes of a record besides its payload: the head and the closing record CRC.
pub const RECORD_OVERHEAD: usize = RECORD_HEAD_LEN + 4;
/// The longest record payload, bytes (16 MiB): about 170 s of one 24 kHz i16 channel, far more than one block.
pub const MAX_PAYLOAD_LEN: usize = 16 << 20;
/// The longest record in the file, bytes; also the bound on the decoder's buffer.
pub const MAX_RECORD_LEN: usize = RECORD_OVERHEAD + MAX_PAYLOAD_LEN;

/// Bytes of a stream block's sub-header: channels 2, sample format 1, sample rate 8, first sample index 8.
pub const STREAM_HEAD_LEN: usize = 19;
/// The longest note, bytes of UTF-8.
pub const MAX_NOTE_LEN: usize = 64 << 10;

/// Bytes of the end marker: sync 4, record count 8, CRC 4.
pub const TRAILER_LEN: usize = 16;

/// Reads little-endian fields from a slice whose length the caller has already checked; reading past the end
/// yields zeros instead of panicking (the caller's length check makes that unreachable, and a wrong check then
/// shows up as a checksum or content error, never as a crash).
pub(crate) struct Fields<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Fields<'a> {
    pub(crate) fn new(bytes: &'a [u8], at: usize) -> Self {
        Self { bytes, at }
    }

    pub(crate) fn position(&self) -> usize {
        self.at
    }

    /// The next `n` bytes, or fewer if the slice ends.
    pub(crate) fn take(&mut self, n: usize) -> &'a [u8] {
        let start = self.at.min(self.bytes.len());
        let end = self.at.saturating_add(n).min(self.bytes.len());
        self.at = self.at.saturating_add(n);
        &self.bytes[start..end]
    }

    fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        let src = self.take(N);
        out[..src.len()].copy_from_slice(src);
        out
    }

    pub(crate) fn u8(&mut self) -> u8 {
        self.array::<1>()[0]
    }

    pub(crate) fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.array())
    }

    pub(crate) fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.array())
    }

    pub(crate) fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.array())
    }

    pub(crate) fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.array())
    }
}

//! The incremental frame decoder, generic over the direction it reads.

use std::marker::PhantomData;

use crate::command::HostCommand;
use crate::error::DaqError;
use crate::frame::{
    CRC_LEN, Frame, HEADER_LEN, Header, MAGIC, MAX_FRAME_LEN, MAX_PAYLOAD_LEN, Message, PROTOCOL_VERSION,
};
use crate::reply::DeviceMessage;

/// The host's decoder: reads device-to-host frames from bulk IN transfers.
pub type HostDecoder = Decoder<DeviceMessage>;
/// The device's decoder: reads host-to-device commands from bulk OUT transfers.
pub type DeviceDecoder = Decoder<HostCommand>;

/// Incremental decoder of frames carrying messages of type `M`.
///
/// [`push`](Self::push) bytes as they arrive, split anywhere (a transfer may hold several frames or part of one),
/// then call [`poll`](Self::poll) until it returns `None`. The sequence of results does not depend on how the input
/// was split.
///
/// Memory: after `poll` has returned `None`, at most `MAX_FRAME_LEN - 1` bytes stay buffered (one unfinished frame),
/// and spare capacity above `2 * MAX_FRAME_LEN` left by a large push is released. A header announcing more than
/// [`MAX_PAYLOAD_LEN`] is an error at once, so the decoder never waits for more than one maximum frame.
///
/// Errors and resynchronisation: on a frame-level error (bad length, CRC mismatch) the decoder drops the first byte
/// of the bad frame and scans for the next magic, so a frame that starts inside the corrupt one is still found; the
/// bytes skipped are reported as [`DaqError::Garbage`] when the next magic is found. On a message-level error (the
/// CRC was good but the version, flags, type or payload is not accepted) it skips exactly that frame.
/// A false magic in corrupted data may hold back the frames behind it until enough bytes arrive to check its CRC
/// (at most one maximum frame); [`clear`](Self::clear) discards everything buffered, for example after a timeout.
#[derive(Debug)]
pub struct Decoder<M> {
    buf: Vec<u8>,
    /// Bytes before `start` are consumed; compacted when `poll` runs dry.
    start: usize,
    /// Bytes skipped since the last frame candidate, not yet reported.
    skipped: usize,
    _message: PhantomData<fn() -> M>,
}

impl<M: Message> Default for Decoder<M> {
    fn default() -> Self {
        Self::new()
    }
}

impl<M: Message> Decoder<M> {
    /// An empty decoder.
    pub fn new() -> Self {
        Self { buf: Vec::new(), start: 0, skipped: 0, _message: PhantomData }
    }

    /// Appends received bytes. Call [`poll`](Self::poll) until `None` afterwards: the buffer bound holds only then.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes buffered and not yet consumed (an unfinished frame, or input not yet polled).
    pub fn buffered_len(&self) -> usize {
        self.buf.len() - self.start
    }

    /// Discards all buffered bytes and any unreported skipped-byte count.
    pub fn clear(&mut self) {
        self.buf.clear();
        self.start = 0;
        self.skipped = 0;
    }

    /// An iterator over [`poll`](Self::poll) results, until the buffered input is exhausted.
    pub fn decoded(&mut self) -> impl Iterator<Item = Result<Frame<M>, DaqError>> + '_ {
        std::iter::from_fn(move || self.poll())
    }

    /// The next decoded frame or error, or `None` when the buffered bytes hold no complete frame.
    ///
    /// Errors are described on [`Decoder`]; after one, keep polling: decoding continues behind it.
    pub fn poll(&mut self) -> Option<Result<Frame<M>, DaqError>> {
        let avail = &self.buf[self.start..];
        let Some(at) = find_magic(avail) else {
            // Keep a trailing first magic byte: its partner may be in the next push.
            let keep = usize::from(avail.last() == Some(&MAGIC[0]));
            self.skip(avail.len() - keep);
            self.compact();
            return None;
        };
        if at > 0 {
            self.skip(at);
        }
        if self.skipped > 0 {
            let skipped_bytes = std::mem::take(&mut self.skipped);
            return Some(Err(DaqError::Garbage { skipped_bytes }));
        }
        let avail = &self.buf[self.start..];
        let Some(header_bytes) = avail.first_chunk::<HEADER_LEN>() else {
            self.compact();
            return None;
        };
        let header = Header::parse(header_bytes);
        if header.payload_len > MAX_PAYLOAD_LEN {
            self.start += 1;
            return Some(Err(DaqError::PayloadTooLong { len: header.payload_len, max: MAX_PAYLOAD_LEN }));
        }
        let body_len = HEADER_LEN + header.payload_len;
        let Some(frame) = avail.get(..body_len + CRC_LEN) else {
            self.compact();
            return None;
        };
        let (body, trailer) = frame.split_at(body_len);
        let mut crc_bytes = [0; CRC_LEN];
        crc_bytes.copy_from_slice(trailer);
        let received = u32::from_le_bytes(crc_bytes);
        let computed = crc32fast::hash(body);
        if received != computed {
            self.start += 1;
            return Some(Err(DaqError::CrcMismatch { received, computed }));
        }
        let result = decode_checked::<M>(&header, &body[HEADER_LEN..]);
        self.start += body_len + CRC_LEN;
        Some(result.map(|message| Frame { seq: header.seq, message }))
    }

    fn skip(&mut self, n: usize) {
        self.start += n;
        self.skipped += n;
    }

    /// Drops consumed bytes and releases spare capacity left by a large push.
    fn compact(&mut self) {
        self.buf.drain(..self.start);
        self.start = 0;
        if self.buf.capacity() > 2 * MAX_FRAME_LEN {
            self.buf.shrink_to(MAX_FRAME_LEN);
        }
    }
}

/// Message-level checks of a frame whose CRC was good.
fn decode_checked<M: Message>(header: &Header, payload: &[u8]) -> Result<M, DaqError> {
    if header.version != PROTOCOL_VERSION {
        return Err(DaqError::VersionMismatch { received: header.version, supported: PROTOCOL_VERSION });
    }
    if header.flags != 0 {
        return Err(DaqError::ReservedFlags { flags: header.flags });
    }
    M::decode_payload(header.msg_type, payload)
}

/// Offset of the first complete magic in `bytes`.
fn find_magic(bytes: &[u8]) -> Option<usize> {
    bytes.windows(MAGIC.len()).position(|w| w == MAGIC)
}

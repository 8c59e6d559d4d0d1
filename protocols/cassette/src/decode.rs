//! The incremental decoder: bytes in (split anywhere), frames out, with a bounded buffer.

use crate::error::{CassetteError, Invalid, Section};
use crate::layout::{
    END_SYNC, FORMAT_MAJOR, Fields, HEADER_FIXED_LEN, MAGIC, MAX_HEADER_LEN, MAX_PAYLOAD_LEN, MIN_HEADER_LEN,
    RECORD_HEAD_CRC_AT, RECORD_HEAD_LEN, RECORD_OVERHEAD, RECORD_SYNC, TRAILER_LEN,
};
use crate::model::{DeviceIdentity, DeviceKind, Header, Record};
use crate::payload::{PayloadError, read_payload};

/// A cassette's format version, as found in a file's header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FormatVersion {
    /// Major version: a reader reads only its own.
    pub major: u16,
    /// Minor version: any, within the major version.
    pub minor: u16,
}

/// One decoded piece of a cassette, in file order: the header, then records, then the end.
#[derive(Debug, Clone, PartialEq)]
pub enum Frame {
    /// The header (always first).
    Header(Header),
    /// A good record: its checksums match, its content is valid and its timestamp is not earlier than the
    /// previous good record's.
    Record(Record),
    /// The end marker: the cassette is complete. `records` is the count it states.
    End {
        /// Records the writer wrote.
        records: u64,
    },
}

/// Where the decoder is in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Waiting for the header.
    Header,
    /// At a frame boundary: a record or the end marker follows.
    Frames,
    /// Framing lost: scanning for the next sync word.
    Resync,
    /// Discarding this many bytes of an over-long record whose (checksummed) length is known.
    Skip(u64),
    /// The end marker was read; anything more is trailing garbage.
    Done,
    /// The file is not a readable cassette (bad magic, unsupported version, bad header); input is discarded.
    Failed,
}

/// What one step of the state machine produced.
enum Step {
    Emit(Result<Frame, CassetteError>),
    Again,
    Wait,
}

/// Decodes a cassette incrementally: [`push`](Self::push) bytes as they arrive, split anywhere, then
/// [`poll`](Self::poll) until it returns `None`; call [`finish`](Self::finish) at the end of the input and poll
/// once more.
///
/// It yields the header, every good record, and the end, in file order, with a typed error in place of each bad
/// part (see the crate documentation for how it recovers). Results do not depend on how the input was split.
///
/// Memory: the buffer holds only bytes pushed and not yet decoded; once `poll` has returned `None` it holds less
/// than one maximal record ([`MAX_RECORD_LEN`](crate::MAX_RECORD_LEN) bytes). A record's length is checked
/// (against its own head checksum and the limit) before the decoder waits for its payload.
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: Vec<u8>,
    /// Start of the undecoded bytes in `buf`.
    pos: usize,
    /// File offset of `buf[pos]`.
    offset: u64,
    received: u64,
    state: State,
    eof: bool,
    truncation_reported: bool,
    garbage_seen: bool,
    garbage_reported: bool,
    /// File offset just past the end marker.
    end_offset: u64,
    pending: Option<Result<Frame, CassetteError>>,
    version: Option<FormatVersion>,
    /// Record frames met so far, good or bad: the next record's ordinal.
    ordinal: u64,
    good: u64,
    last_t_ns: u64,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder at the start of a file.
    pub fn new() -> Self {
        Self {
            buf: Vec::new(),
            pos: 0,
            offset: 0,
            received: 0,
            state: State::Header,
            eof: false,
            truncation_reported: false,
            garbage_seen: false,
            garbage_reported: false,
            end_offset: 0,
            pending: None,
            version: None,
            ordinal: 0,
            good: 0,
            last_t_ns: 0,
        }
    }

    /// Feeds the next bytes of the file. Bytes pushed after [`finish`](Self::finish) are ignored; bytes after the
    /// end marker or after a fatal error are counted but not kept.
    pub fn push(&mut self, bytes: &[u8]) {
        if self.eof {
            return;
        }
        self.received += bytes.len() as u64;
        match self.state {
            State::Failed => {}
            State::Done => self.garbage_seen |= !bytes.is_empty(),
            _ => {
                self.compact();
                self.buf.extend_from_slice(bytes);
            }
        }
    }

    /// Marks the end of the input: if the end marker has not been read, the next polls report
    /// [`CassetteError::Truncated`] after every good record.
    pub fn finish(&mut self) {
        self.eof = true;
    }

    /// The next decoded frame or error, or `None` when more input (or [`finish`](Self::finish)) is needed or the
    /// input is exhausted.
    pub fn poll(&mut self) -> Option<Result<Frame, CassetteError>> {
        if let Some(pending) = self.pending.take() {
            return Some(pending);
        }
        loop {
            let step = match self.state {
                State::Header => self.step_header(),
                State::Frames => self.step_frame(),
                State::Resync => self.step_resync(),
                State::Skip(remaining) => self.step_skip(remaining),
                State::Done => self.step_done(),
                State::Failed => {
                    self.consume(self.available().len());
                    Step::Wait
                }
            };
            match step {
                Step::Emit(result) => return Some(result),
                Step::Again => continue,
                Step::Wait => return self.waiting(),
            }
        }
    }

    /// Polls until `None`, as an iterator.
    pub fn frames(&mut self) -> impl Iterator<Item = Result<Frame, CassetteError>> + '_ {
        std::iter::from_fn(move || self.poll())
    }

    /// The format version of the file, once its header has been read.
    pub fn format_version(&self) -> Option<FormatVersion> {
        self.version
    }

    /// Bytes buffered and not yet decoded.
    pub fn buffered_len(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Good records delivered so far.
    pub fn records(&self) -> u64 {
        self.good
    }

    /// Whether the end marker has been read (the cassette is complete).
    pub fn is_complete(&self) -> bool {
        self.state == State::Done
    }

    fn available(&self) -> &[u8] {
        &self.buf[self.pos..]
    }

    fn consume(&mut self, n: usize) {
        self.pos += n;
        self.offset += n as u64;
    }

    /// Drops decoded bytes from the front of the buffer. Done on push, not per record, so that a push holding
    /// many records costs one move of the remainder, not one per record.
    fn compact(&mut self) {
        if self.pos > 0 {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        // Return the memory of a past maximal record once it is no longer needed.
        if self.buf.capacity() > 1 << 20 && self.buf.len() < self.buf.capacity() / 4 {
            self.buf.shrink_to(self.buf.len().max(1 << 16));
        }
    }

    /// Called when a step needs more input: at the end of the input, reports the truncation once.
    fn waiting(&mut self) -> Option<Result<Frame, CassetteError>> {
        let finished = matches!(self.state, State::Done | State::Failed);
        if !self.eof || finished || self.truncation_reported {
            return None;
        }
        self.truncation_reported = true;
        self.consume(self.available().len());
        Some(Err(CassetteError::Truncated { offset: self.received, records: self.good }))
    }

    fn fail(&mut self, error: CassetteError) -> Step {
        self.state = State::Failed;
        self.consume(self.available().len());
        Step::Emit(Err(error))
    }

    fn step_header(&mut self) -> Step {
        let b = self.available();
        // The magic is judged on all 8 bytes (or on what there is at the end of the input), so that the error
        // does not depend on how the input was split.
        if b.len() < MAGIC.len() && !self.eof {
            return Step::Wait;
        }
        let n = b.len().min(MAGIC.len());
        if b[..n] != MAGIC[..n] {
            let found = b[..n].to_vec();
            return self.fail(CassetteError::BadMagic { found });
        }
        // Magic, major, minor and header length: enough to judge the version and the length.
        if b.len() < MAGIC.len() + 6 {
            return Step::Wait;
        }
        let mut f = Fields::new(b, MAGIC.len());
        let (major, minor, header_len) = (f.u16(), f.u16(), usize::from(f.u16()));
        if major != FORMAT_MAJOR {
            return self.fail(CassetteError::UnsupportedVersion { major, minor, supported: FORMAT_MAJOR });
        }
        if header_len < MIN_HEADER_LEN {
            let reason = Invalid::HeaderTooShort { header_len, min: MIN_HEADER_LEN };
            return self.fail(CassetteError::Invalid { section: Section::Header, offset: 0, reason });
        }
        if header_len > MAX_HEADER_LEN {
            return self.fail(CassetteError::Oversize {
                section: Section::Header,
                what: "header",
                offset: 0,
                len: header_len as u64,
                max: MAX_HEADER_LEN as u64,
            });
        }
        if b.len() < header_len {
            return Step::Wait;
        }
        let body = &b[..header_len - 4];
        let stored = Fields::new(b, header_len - 4).u32();
        let computed = crc32fast::hash(body);
        if stored != computed {
            let error =
                CassetteError::Checksum { section: Section::Header, covers: "header", offset: 0, stored, computed };
            return self.fail(error);
        }
        let code = f.u8();
        let Some(device_kind) = DeviceKind::from_code(code) else {
            let error = CassetteError::UnknownKind { section: Section::Header, what: "device kind", code, offset: 0 };
            return self.fail(error);
        };
        let start_unix_ns = f.u64();
        let identity = match read_identity(body) {
            Ok(identity) => identity,
            Err(reason) => return self.fail(CassetteError::Invalid { section: Section::Header, offset: 0, reason }),
        };
        self.consume(header_len);
        self.version = Some(FormatVersion { major, minor });
        self.state = State::Frames;
        Step::Emit(Ok(Frame::Header(Header { device_kind, identity, start_unix_ns })))
    }

    fn step_frame(&mut self) -> Step {
        let b = self.available();
        if b.len() < 4 {
            return Step::Wait;
        }
        let sync = [b[0], b[1], b[2], b[3]];
        if sync == RECORD_SYNC {
            self.step_record()
        } else if sync == END_SYNC {
            self.step_trailer()
        } else {
            let error = CassetteError::LostSync { offset: self.offset, found: sync };
            self.consume(1);
            self.state = State::Resync;
            Step::Emit(Err(error))
        }
    }

    fn step_record(&mut self) -> Step {
        let (offset, section) = (self.offset, Section::Record(self.ordinal));
        let b = self.available();
        if b.len() < RECORD_HEAD_LEN {
            return Step::Wait;
        }
        let mut f = Fields::new(b, 4);
        let (kind, endpoint, t_ns, len) = (f.u8(), f.u16(), f.u64(), f.u32() as usize);
        let stored = f.u32();
        let computed = crc32fast::hash(&b[..RECORD_HEAD_CRC_AT]);
        if stored != computed {
            // The length cannot be trusted: look for the next sync word from the next byte on.
            self.ordinal += 1;
            self.consume(1);
            self.state = State::Resync;
            return Step::Emit(Err(CassetteError::Checksum {
                section,
                covers: "record head",
                offset,
                stored,
                computed,
            }));
        }
        if len > MAX_PAYLOAD_LEN {
            // The length is genuine (its checksum matches): skip the record without buffering it.
            self.ordinal += 1;
            self.consume(RECORD_HEAD_LEN);
            self.state = State::Skip(len as u64 + 4);
            let max = MAX_PAYLOAD_LEN as u64;
            return Step::Emit(Err(CassetteError::Oversize { section, what: "payload", offset, len: len as u64, max }));
        }
        let total = RECORD_OVERHEAD + len;
        if b.len() < total {
            return Step::Wait;
        }
        let stored = Fields::new(b, total - 4).u32();
        let computed = crc32fast::hash(&b[..total - 4]);
        let result = if stored != computed {
            Err(CassetteError::Checksum { section, covers: "record", offset, stored, computed })
        } else {
            match read_payload(kind, &b[RECORD_HEAD_LEN..total - 4]) {
                Err(PayloadError::Unknown(what, code)) => {
                    Err(CassetteError::UnknownKind { section, what, code, offset })
                }
                Err(PayloadError::Invalid(reason)) => Err(CassetteError::Invalid { section, offset, reason }),
                Ok(_) if t_ns < self.last_t_ns => {
                    Err(CassetteError::OutOfOrder { section, offset, previous_ns: self.last_t_ns, t_ns })
                }
                Ok(body) => Ok(Frame::Record(Record { t_ns, endpoint, body })),
            }
        };
        // The head checksum vouched for the length: the next frame starts right after, whatever was wrong inside.
        self.ordinal += 1;
        self.consume(total);
        if result.is_ok() {
            self.good += 1;
            self.last_t_ns = t_ns;
        }
        Step::Emit(result)
    }

    fn step_trailer(&mut self) -> Step {
        let offset = self.offset;
        let b = self.available();
        if b.len() < TRAILER_LEN {
            return Step::Wait;
        }
        let mut f = Fields::new(b, 4);
        let (records, stored) = (f.u64(), f.u32());
        let computed = crc32fast::hash(&b[..TRAILER_LEN - 4]);
        if stored != computed {
            self.consume(1);
            self.state = State::Resync;
            return Step::Emit(Err(CassetteError::Checksum {
                section: Section::Trailer,
                covers: "trailer",
                offset,
                stored,
                computed,
            }));
        }
        self.consume(TRAILER_LEN);
        self.state = State::Done;
        self.end_offset = self.offset;
        let end = Ok(Frame::End { records });
        if records != self.good {
            // The count error first, then the end itself.
            self.pending = Some(end);
            return Step::Emit(Err(CassetteError::RecordCount { stored: records, read: self.good }));
        }
        Step::Emit(end)
    }

    fn step_resync(&mut self) -> Step {
        let b = self.available();
        let mut keep = b.len();
        let mut found = false;
        let starts = b.iter().enumerate().filter(|&(_, &byte)| byte == RECORD_SYNC[0]).map(|(i, _)| i);
        for i in starts {
            let rest = &b[i..];
            if rest.len() >= 4 {
                if rest[..4] == RECORD_SYNC || rest[..4] == END_SYNC {
                    (keep, found) = (i, true);
                    break;
                }
            } else if RECORD_SYNC.starts_with(rest) || END_SYNC.starts_with(rest) {
                // A sync word may be split across pushes: keep its start.
                keep = i;
                break;
            }
        }
        self.consume(keep);
        if found {
            self.state = State::Frames;
            Step::Again
        } else {
            Step::Wait
        }
    }

    fn step_skip(&mut self, remaining: u64) -> Step {
        let n = (self.available().len() as u64).min(remaining);
        // n <= the buffered length, a usize.
        self.consume(n as usize);
        if n == remaining {
            self.state = State::Frames;
            Step::Again
        } else {
            self.state = State::Skip(remaining - n);
            Step::Wait
        }
    }

    fn step_done(&mut self) -> Step {
        if !self.available().is_empty() {
            self.garbage_seen = true;
            self.consume(self.available().len());
        }
        if self.garbage_seen && !self.garbage_reported {
            self.garbage_reported = true;
            return Step::Emit(Err(CassetteError::TrailingGarbage { offset: self.end_offset }));
        }
        Step::Wait
    }
}

/// Reads the four identity fields that follow the header's fixed part, within `body` (the header without its
/// CRC). Bytes after them are a later minor version's extension, and are skipped.
fn read_identity(body: &[u8]) -> Result<DeviceIdentity, Invalid> {
    let mut at = HEADER_FIXED_LEN;
    let mut next = |field: &'static str| -> Result<String, Invalid> {
        let overrun = Invalid::HeaderOverrun { header_len: body.len() + 4 };
        let len = usize::from(*body.get(at).ok_or(overrun.clone())?);
        let text = body.get(at + 1..at + 1 + len).ok_or(overrun)?;
        at += 1 + len;
        std::str::from_utf8(text).map(str::to_owned).map_err(|_| Invalid::Utf8 { field })
    };
    Ok(DeviceIdentity {
        vendor: next("vendor")?,
        model: next("model")?,
        serial: next("serial")?,
        firmware: next("firmware")?,
    })
}

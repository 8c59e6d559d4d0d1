//! The encoder: a header, records, then the end marker, appended to a caller's buffer.

use crate::error::{CassetteError, Section};
use crate::layout::{
    END_SYNC, FORMAT_MAJOR, FORMAT_MINOR, HEADER_FIXED_LEN, MAGIC, MAX_PAYLOAD_LEN, RECORD_OVERHEAD, RECORD_SYNC,
};
use crate::model::{Header, Record};
use crate::payload::{check_body, payload_len, write_payload};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    Start,
    Records,
    Ended,
}

/// Writes a cassette incrementally (sans-IO: it appends bytes to a `Vec<u8>` that the caller writes out).
///
/// Call [`header`](Self::header) once, [`record`](Self::record) for each record in time order, then
/// [`end`](Self::end). A recorder that writes each call's bytes to disk as it goes leaves a readable cassette,
/// reported as truncated, if it crashes. Every call checks its input first: on error it appends nothing and the
/// encoder's state is unchanged, so the caller may fix the record and carry on.
#[derive(Debug, Clone)]
pub struct Encoder {
    stage: Stage,
    last_t_ns: u64,
    records: u64,
    written: u64,
}

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    /// An encoder that has written nothing.
    pub fn new() -> Self {
        Self { stage: Stage::Start, last_t_ns: 0, records: 0, written: 0 }
    }

    /// Records written so far.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Bytes appended so far (the offset of the next byte in the file).
    pub fn bytes_written(&self) -> u64 {
        self.written
    }

    /// Appends the header, in the current format version.
    ///
    /// # Errors
    /// [`CassetteError::EncoderState`] if a header was already written; [`CassetteError::Invalid`] for an identity
    /// field over its length limit.
    pub fn header(&mut self, header: &Header, out: &mut Vec<u8>) -> Result<(), CassetteError> {
        if self.stage != Stage::Start {
            return Err(CassetteError::EncoderState { reason: "the header was already written" });
        }
        header.identity.check().map_err(|reason| CassetteError::Invalid {
            section: Section::Header,
            offset: 0,
            reason,
        })?;
        let fields = header.identity.fields();
        let header_len = HEADER_FIXED_LEN + fields.iter().map(|(_, text)| 1 + text.len()).sum::<usize>() + 4;
        // Fits: `check` bounds each field to 255 bytes, so header_len <= 23 + 4 * 256 + 4 = 1051 <= MAX_HEADER_LEN.
        let header_len_u16 = header_len as u16;
        let start = out.len();
        out.reserve(header_len);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_MAJOR.to_le_bytes());
        out.extend_from_slice(&FORMAT_MINOR.to_le_bytes());
        out.extend_from_slice(&header_len_u16.to_le_bytes());
        out.push(header.device_kind.code());
        out.extend_from_slice(&header.start_unix_ns.to_le_bytes());
        for (_, text) in fields {
            // Fits: `check` bounds each field to 255 bytes.
            out.push(text.len() as u8);
            out.extend_from_slice(text.as_bytes());
        }
        let crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&crc.to_le_bytes());
        self.stage = Stage::Records;
        self.written += header_len as u64;
        Ok(())
    }

    /// Appends one record.
    ///
    /// # Errors
    /// [`CassetteError::EncoderState`] before the header or after the end marker; [`CassetteError::OutOfOrder`]
    /// if its timestamp is earlier than the previous record's; [`CassetteError::Oversize`] for a payload over
    /// [`MAX_PAYLOAD_LEN`]; [`CassetteError::Invalid`] for a bad stream block (no channels, a rate that is not
    /// finite and positive, a partial frame, a non-finite sample) or an over-long note.
    pub fn record(&mut self, record: &Record, out: &mut Vec<u8>) -> Result<(), CassetteError> {
        match self.stage {
            Stage::Start => return Err(CassetteError::EncoderState { reason: "a record before the header" }),
            Stage::Ended => return Err(CassetteError::EncoderState { reason: "a record after the end marker" }),
            Stage::Records => {}
        }
        let section = Section::Record(self.records);
        let offset = self.written;
        if record.t_ns < self.last_t_ns {
            return Err(CassetteError::OutOfOrder { section, offset, previous_ns: self.last_t_ns, t_ns: record.t_ns });
        }
        check_body(&record.body).map_err(|reason| CassetteError::Invalid { section, offset, reason })?;
        let len = payload_len(&record.body);
        if len > MAX_PAYLOAD_LEN {
            return Err(CassetteError::Oversize {
                section,
                what: "payload",
                offset,
                len: len as u64,
                max: MAX_PAYLOAD_LEN as u64,
            });
        }
        let start = out.len();
        out.reserve(len + RECORD_OVERHEAD);
        out.extend_from_slice(&RECORD_SYNC);
        out.push(record.body.kind_code());
        out.extend_from_slice(&record.endpoint.to_le_bytes());
        out.extend_from_slice(&record.t_ns.to_le_bytes());
        // Fits: len <= MAX_PAYLOAD_LEN < u32::MAX.
        out.extend_from_slice(&(len as u32).to_le_bytes());
        let head_crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&head_crc.to_le_bytes());
        write_payload(&record.body, out);
        let crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&crc.to_le_bytes());
        self.last_t_ns = record.t_ns;
        self.records += 1;
        self.written += (out.len() - start) as u64;
        Ok(())
    }

    /// Appends the end marker, which holds the record count; the cassette is then complete.
    ///
    /// # Errors
    /// [`CassetteError::EncoderState`] before the header or if the end marker was already written.
    pub fn end(&mut self, out: &mut Vec<u8>) -> Result<(), CassetteError> {
        match self.stage {
            Stage::Start => return Err(CassetteError::EncoderState { reason: "the end marker before the header" }),
            Stage::Ended => return Err(CassetteError::EncoderState { reason: "the end marker was already written" }),
            Stage::Records => {}
        }
        let start = out.len();
        out.extend_from_slice(&END_SYNC);
        out.extend_from_slice(&self.records.to_le_bytes());
        let crc = crc32fast::hash(&out[start..]);
        out.extend_from_slice(&crc.to_le_bytes());
        self.stage = Stage::Ended;
        self.written += (out.len() - start) as u64;
        Ok(())
    }
}

//! A whole cassette in memory: what a replayer walks and what a recorder builds.

use crate::decode::{Decoder, Frame};
use crate::encode::Encoder;
use crate::error::CassetteError;
use crate::model::{Header, Record};

/// A cassette in memory: a header and its records in time order. Plain data: copy it, edit its records (to inject
/// faults), encode it again.
#[derive(Debug, Clone, PartialEq)]
pub struct Cassette {
    /// What was recorded.
    pub header: Header,
    /// The records, timestamps non-decreasing.
    pub records: Vec<Record>,
}

/// What [`Cassette::recover`] could read from a damaged or truncated file.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovered {
    /// The header and every good record.
    pub cassette: Cassette,
    /// Every error met, in file order (a truncated recording ends with [`CassetteError::Truncated`]).
    pub errors: Vec<CassetteError>,
    /// Whether the end marker was read.
    pub complete: bool,
}

impl Cassette {
    /// A cassette with no records.
    pub fn new(header: Header) -> Self {
        Self { header, records: Vec::new() }
    }

    /// The complete file: header, records, end marker.
    ///
    /// # Errors
    /// As [`Encoder::header`] and [`Encoder::record`]: an over-long identity field, records out of time order, an
    /// oversize payload, an invalid stream block or note.
    pub fn to_bytes(&self) -> Result<Vec<u8>, CassetteError> {
        let mut encoder = Encoder::new();
        let mut out = Vec::new();
        encoder.header(&self.header, &mut out)?;
        for record in &self.records {
            encoder.record(record, &mut out)?;
        }
        encoder.end(&mut out)?;
        Ok(out)
    }

    /// Reads a complete, intact cassette.
    ///
    /// # Errors
    /// The first error in the file, [`CassetteError::Truncated`] included: use [`Cassette::recover`] to keep what
    /// precedes it.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CassetteError> {
        let recovered = Self::recover(bytes)?;
        match recovered.errors.into_iter().next() {
            Some(error) => Err(error),
            None => Ok(recovered.cassette),
        }
    }

    /// Reads what can be read: the header and every good record, with the errors met on the way. A crash
    /// mid-recording gives all records before the cut and a final [`CassetteError::Truncated`]; the caller
    /// decides whether that is good enough to replay.
    ///
    /// # Errors
    /// The header's error when there is no readable header (bad magic, unsupported version, corrupt or truncated
    /// header): without it there is no cassette.
    pub fn recover(bytes: &[u8]) -> Result<Recovered, CassetteError> {
        let mut decoder = Decoder::new();
        decoder.push(bytes);
        decoder.finish();
        let header = match decoder.poll() {
            Some(Ok(Frame::Header(header))) => header,
            Some(Err(error)) => return Err(error),
            // The decoder yields the header or an error first; anything else would be a decoder bug, reported as
            // a truncation rather than a panic.
            _ => return Err(CassetteError::Truncated { offset: bytes.len() as u64, records: 0 }),
        };
        let mut cassette = Cassette::new(header);
        let mut errors = Vec::new();
        for result in decoder.frames() {
            match result {
                Ok(Frame::Record(record)) => cassette.records.push(record),
                Ok(Frame::Header(_) | Frame::End { .. }) => {}
                Err(error) => errors.push(error),
            }
        }
        Ok(Recovered { cassette, errors, complete: decoder.is_complete() })
    }
}

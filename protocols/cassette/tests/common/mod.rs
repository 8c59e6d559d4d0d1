//! Helpers shared by the integration tests: decoding at chosen split points, and hand-framing of records (with
//! correct checksums) so that tests can build malformed content the encoder would refuse to write.
#![allow(dead_code)]

use metaplate_cassette::{
    CassetteError, Decoder, DeviceIdentity, DeviceKind, Frame, Header, MAX_RECORD_LEN, RECORD_SYNC,
};

/// Everything a decoder yields for `bytes` pushed in chunks cut at `cuts` (positions, any order, clamped), with
/// `finish` at the end. Also asserts the documented buffer bound after every drained push.
pub fn decode_split(bytes: &[u8], cuts: &[usize]) -> Vec<Result<Frame, CassetteError>> {
    let mut cuts: Vec<usize> = cuts.iter().map(|&c| c.min(bytes.len())).collect();
    cuts.push(0);
    cuts.push(bytes.len());
    cuts.sort_unstable();
    let mut decoder = Decoder::new();
    let mut out = Vec::new();
    for pair in cuts.windows(2) {
        decoder.push(&bytes[pair[0]..pair[1]]);
        out.extend(decoder.frames());
        assert!(decoder.buffered_len() < MAX_RECORD_LEN, "buffer {} over its bound", decoder.buffered_len());
    }
    decoder.finish();
    out.extend(decoder.frames());
    // Once finished and drained, nothing more may come.
    assert!(decoder.poll().is_none());
    out
}

/// Decodes in one push.
pub fn decode(bytes: &[u8]) -> Vec<Result<Frame, CassetteError>> {
    decode_split(bytes, &[])
}

/// Decodes one byte at a time.
pub fn decode_bytewise(bytes: &[u8]) -> Vec<Result<Frame, CassetteError>> {
    let cuts: Vec<usize> = (0..bytes.len()).collect();
    decode_split(bytes, &cuts)
}

/// A typical header.
pub fn header() -> Header {
    Header {
        device_kind: DeviceKind::LdvSerial,
        identity: DeviceIdentity {
            vendor: "Ometron".into(),
            model: "8330".into(),
            serial: "SN-42".into(),
            firmware: "2.1".into(),
        },
        start_unix_ns: 1_700_000_000_000_000_000,
    }
}

/// A record framed by hand: sync, kind, endpoint, timestamp, length, head CRC, payload, record CRC.
pub fn raw_record(kind: u8, endpoint: u16, t_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut r = RECORD_SYNC.to_vec();
    r.push(kind);
    r.extend_from_slice(&endpoint.to_le_bytes());
    r.extend_from_slice(&t_ns.to_le_bytes());
    r.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    let head_crc = crc32fast::hash(&r);
    r.extend_from_slice(&head_crc.to_le_bytes());
    r.extend_from_slice(payload);
    let crc = crc32fast::hash(&r);
    r.extend_from_slice(&crc.to_le_bytes());
    r
}

/// A stream payload framed by hand.
pub fn raw_stream(channels: u16, format: u8, sample_rate_hz: f64, first: u64, data: &[u8]) -> Vec<u8> {
    let mut p = channels.to_le_bytes().to_vec();
    p.push(format);
    p.extend_from_slice(&sample_rate_hz.to_le_bytes());
    p.extend_from_slice(&first.to_le_bytes());
    p.extend_from_slice(data);
    p
}

/// Recomputes the CRC at the end of the first `len` bytes of `bytes` (the last 4 of them), after a test edited
/// the bytes it covers.
pub fn reseal(bytes: &mut [u8], start: usize, len: usize) {
    let crc = crc32fast::hash(&bytes[start..start + len - 4]);
    bytes[start + len - 4..start + len].copy_from_slice(&crc.to_le_bytes());
}

/// The records among decoder results.
pub fn records(results: &[Result<Frame, CassetteError>]) -> Vec<metaplate_cassette::Record> {
    results
        .iter()
        .filter_map(|r| match r {
            Ok(Frame::Record(record)) => Some(record.clone()),
            _ => None,
        })
        .collect()
}

/// The errors among decoder results.
pub fn errors(results: &[Result<Frame, CassetteError>]) -> Vec<CassetteError> {
    results.iter().filter_map(|r| r.as_ref().err().cloned()).collect()
}

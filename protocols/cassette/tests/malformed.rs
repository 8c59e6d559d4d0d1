//! Each class of malformed input gives its typed error, at the right place, and the decoder recovers as documented.
//! Comparisons are exact: offsets, ordinals and counts are integers with one right answer.
#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{decode, decode_bytewise, errors, header, raw_record, raw_stream, records, reseal};
use metaplate_cassette::{
    Body, Cassette, CassetteError, Decoder, END_SYNC, Encoder, Event, FormatVersion, Frame, Invalid, MAX_NOTE_LEN,
    MAX_PAYLOAD_LEN, RECORD_SYNC, Record, Section,
};

/// A three-record session, its bytes, and the offset of each record and of the end marker.
struct Session {
    cassette: Cassette,
    bytes: Vec<u8>,
    record_at: Vec<usize>,
    end_at: usize,
}

fn session() -> Session {
    let cassette = Cassette {
        header: header(),
        records: vec![
            Record { t_ns: 10, endpoint: 0, body: Body::HostToDevice(b"*IDN?\r".to_vec()) },
            Record { t_ns: 20, endpoint: 0, body: Body::DeviceToHost(b"OMETRON,8330\r".to_vec()) },
            Record { t_ns: 30, endpoint: 0, body: Body::Event(Event::Close) },
        ],
    };
    let mut encoder = Encoder::new();
    let mut bytes = Vec::new();
    encoder.header(&cassette.header, &mut bytes).unwrap();
    let mut record_at = Vec::new();
    for r in &cassette.records {
        record_at.push(bytes.len());
        encoder.record(r, &mut bytes).unwrap();
    }
    let end_at = bytes.len();
    encoder.end(&mut bytes).unwrap();
    Session { cassette, bytes, record_at, end_at }
}

fn trailer(count: u64) -> Vec<u8> {
    let mut t = END_SYNC.to_vec();
    t.extend_from_slice(&count.to_le_bytes());
    let crc = crc32fast::hash(&t);
    t.extend_from_slice(&crc.to_le_bytes());
    t
}

/// Header bytes of a session, then `middle`, then an end marker counting `count` records.
fn framed(middle: &[u8], count: u64) -> Vec<u8> {
    let s = session();
    let mut bytes = s.bytes[..s.record_at[0]].to_vec();
    bytes.extend_from_slice(middle);
    bytes.extend_from_slice(&trailer(count));
    bytes
}

fn header_len() -> usize {
    session().record_at[0]
}

#[test]
fn empty_input_is_truncated() {
    assert_eq!(decode(&[]), vec![Err(CassetteError::Truncated { offset: 0, records: 0 })]);
}

#[test]
fn bad_magic_is_fatal() {
    let mut bytes = session().bytes;
    bytes[0] = b'X';
    let found = bytes[..8].to_vec();
    // Nothing after a bad magic is read, although valid records follow.
    assert_eq!(decode(&bytes), vec![Err(CassetteError::BadMagic { found: found.clone() })]);
    assert_eq!(decode_bytewise(&bytes), vec![Err(CassetteError::BadMagic { found })]);
    // A short file that is not a cassette, and one that is a cut-off cassette.
    assert_eq!(decode(b"hello"), vec![Err(CassetteError::BadMagic { found: b"hello".to_vec() })]);
    assert_eq!(decode(b"MPC"), vec![Err(CassetteError::Truncated { offset: 3, records: 0 })]);
}

#[test]
fn other_major_versions_are_refused() {
    for major in [0u16, 2, u16::MAX] {
        let mut bytes = session().bytes;
        bytes[8..10].copy_from_slice(&major.to_le_bytes());
        // The version is judged before the checksum: a newer layout may checksum differently.
        let want = CassetteError::UnsupportedVersion { major, minor: 0, supported: 1 };
        assert_eq!(decode(&bytes), vec![Err(want)]);
    }
}

#[test]
fn newer_minor_version_with_extension_bytes_is_read() {
    let s = session();
    let h = header_len();
    // Version 1.3 with 5 extension bytes before the header CRC.
    let mut bytes = s.bytes[..h - 4].to_vec();
    bytes[10..12].copy_from_slice(&3u16.to_le_bytes());
    bytes[12..14].copy_from_slice(&((h + 5) as u16).to_le_bytes());
    bytes.extend_from_slice(&[1, 2, 3, 4, 5, 0, 0, 0, 0]);
    reseal(&mut bytes, 0, h + 5);
    bytes.extend_from_slice(&s.bytes[h..]);
    let mut decoder = Decoder::new();
    decoder.push(&bytes);
    decoder.finish();
    let results: Vec<_> = decoder.frames().collect();
    assert_eq!(decoder.format_version(), Some(FormatVersion { major: 1, minor: 3 }));
    assert!(decoder.is_complete());
    assert_eq!(errors(&results), vec![]);
    assert_eq!(records(&results), s.cassette.records);
}

#[test]
fn header_checksum_mismatch_is_fatal() {
    let mut bytes = session().bytes;
    bytes[24] ^= 0x20; // a letter of the vendor
    let results = decode(&bytes);
    assert_eq!(results.len(), 1);
    assert!(matches!(
        results[0],
        Err(CassetteError::Checksum { section: Section::Header, covers: "header", offset: 0, stored, computed })
            if stored != computed
    ));
}

#[test]
fn header_length_out_of_range_is_refused() {
    let mut short = session().bytes;
    short[12..14].copy_from_slice(&30u16.to_le_bytes());
    let reason = Invalid::HeaderTooShort { header_len: 30, min: 31 };
    assert_eq!(decode(&short), vec![Err(CassetteError::Invalid { section: Section::Header, offset: 0, reason })]);

    // Refused from its 14 first bytes, before 4097 bytes are awaited.
    let mut long = session().bytes[..14].to_vec();
    long[12..14].copy_from_slice(&4097u16.to_le_bytes());
    let mut decoder = Decoder::new();
    decoder.push(&long);
    let want = CassetteError::Oversize { section: Section::Header, what: "header", offset: 0, len: 4097, max: 4096 };
    assert_eq!(decoder.poll(), Some(Err(want)));
}

#[test]
fn header_identity_defects_are_refused() {
    let h = header_len();
    // Vendor length byte (offset 23) claims more bytes than the header holds.
    let mut overrun = session().bytes;
    overrun[23] = 250;
    reseal(&mut overrun, 0, h);
    let reason = Invalid::HeaderOverrun { header_len: h };
    assert_eq!(decode(&overrun), vec![Err(CassetteError::Invalid { section: Section::Header, offset: 0, reason })]);

    let mut utf8 = session().bytes;
    utf8[24] = 0xff;
    reseal(&mut utf8, 0, h);
    let reason = Invalid::Utf8 { field: "vendor" };
    assert_eq!(decode(&utf8), vec![Err(CassetteError::Invalid { section: Section::Header, offset: 0, reason })]);
}

#[test]
fn unknown_device_kind_is_fatal() {
    let mut bytes = session().bytes;
    bytes[14] = 9;
    reseal(&mut bytes, 0, header_len());
    let want = CassetteError::UnknownKind { section: Section::Header, what: "device kind", code: 9, offset: 0 };
    assert_eq!(decode(&bytes), vec![Err(want)]);
}

#[test]
fn truncation_at_every_byte_keeps_every_whole_record() {
    let s = session();
    let record_end: Vec<usize> = s.record_at[1..].iter().copied().chain([s.end_at]).collect();
    for cut in 0..s.bytes.len() {
        let results = decode(&s.bytes[..cut]);
        let whole = record_end.iter().filter(|&&end| end <= cut).count();
        let truncated = CassetteError::Truncated { offset: cut as u64, records: whole as u64 };
        if cut < s.record_at[0] {
            assert_eq!(results, vec![Err(truncated)], "cut at {cut}");
            assert_eq!(
                Cassette::recover(&s.bytes[..cut]),
                Err(CassetteError::Truncated { offset: cut as u64, records: 0 })
            );
            continue;
        }
        let mut want = vec![Ok(Frame::Header(s.cassette.header.clone()))];
        want.extend(s.cassette.records[..whole].iter().cloned().map(|r| Ok(Frame::Record(r))));
        want.push(Err(truncated.clone()));
        assert_eq!(results, want, "cut at {cut}");
        let recovered = Cassette::recover(&s.bytes[..cut]).unwrap();
        assert_eq!(recovered.cassette.records, s.cassette.records[..whole]);
        assert_eq!(recovered.errors, vec![truncated.clone()]);
        assert!(!recovered.complete);
        assert_eq!(Cassette::from_bytes(&s.bytes[..cut]), Err(truncated));
    }
    let complete = Cassette::recover(&s.bytes).unwrap();
    assert!(complete.complete && complete.errors.is_empty());
}

#[test]
fn record_checksum_mismatch_skips_that_record_only() {
    let s = session();
    let mut bytes = s.bytes.clone();
    bytes[s.record_at[1] + 25] ^= 1; // a payload byte of record 1
    let results = decode(&bytes);
    let r = &s.cassette.records;
    assert_eq!(results.len(), 6);
    assert_eq!(results[1], Ok(Frame::Record(r[0].clone())));
    assert!(matches!(
        results[2],
        Err(CassetteError::Checksum { section: Section::Record(1), covers: "record", offset, .. })
            if offset == s.record_at[1] as u64
    ));
    assert_eq!(results[3], Ok(Frame::Record(r[2].clone())));
    assert_eq!(results[4], Err(CassetteError::RecordCount { stored: 3, read: 2 }));
    assert_eq!(results[5], Ok(Frame::End { records: 3 }));
}

#[test]
fn record_head_checksum_mismatch_resyncs_at_the_next_record() {
    let s = session();
    let mut bytes = s.bytes.clone();
    bytes[s.record_at[1] + 16] ^= 0x80; // the top of the payload length: trusting it would wait for 2 GiB
    let results = decode_bytewise(&bytes);
    let r = &s.cassette.records;
    assert_eq!(results.len(), 6);
    assert_eq!(results[1], Ok(Frame::Record(r[0].clone())));
    assert!(matches!(
        results[2],
        Err(CassetteError::Checksum { section: Section::Record(1), covers: "record head", offset, .. })
            if offset == s.record_at[1] as u64
    ));
    assert_eq!(results[3], Ok(Frame::Record(r[2].clone())));
    assert_eq!(results[4], Err(CassetteError::RecordCount { stored: 3, read: 2 }));
    assert_eq!(results[5], Ok(Frame::End { records: 3 }));
}

#[test]
fn garbage_between_records_loses_then_regains_sync() {
    let s = session();
    let mut bytes = s.bytes[..s.record_at[1]].to_vec();
    // Includes a lone sync-word start, which must not stop the scan.
    bytes.extend_from_slice(b"xyz\x89RE!");
    bytes.extend_from_slice(&s.bytes[s.record_at[1]..]);
    let want_error = CassetteError::LostSync { offset: s.record_at[1] as u64, found: *b"xyz\x89" };
    for results in [decode(&bytes), decode_bytewise(&bytes)] {
        assert_eq!(errors(&results), vec![want_error.clone()]);
        assert_eq!(records(&results), s.cassette.records);
        assert_eq!(results.last(), Some(&Ok(Frame::End { records: 3 })));
    }
}

#[test]
fn oversize_record_is_refused_and_skipped_without_buffering() {
    let len = MAX_PAYLOAD_LEN + 1;
    let mut oversize = RECORD_SYNC.to_vec();
    oversize.push(1);
    oversize.extend_from_slice(&0u16.to_le_bytes());
    oversize.extend_from_slice(&5u64.to_le_bytes());
    oversize.extend_from_slice(&(len as u32).to_le_bytes());
    let crc = crc32fast::hash(&oversize);
    oversize.extend_from_slice(&crc.to_le_bytes());
    oversize.resize(oversize.len() + len + 4, 0x89); // payload and CRC, full of sync-word starts
    let good = Record { t_ns: 6, endpoint: 1, body: Body::DeviceToHost(b"ok".to_vec()) };
    let mut middle = oversize;
    middle.extend_from_slice(&raw_record(2, 1, 6, b"ok"));
    let bytes = framed(&middle, 1);

    let chunk = 1 << 16;
    let mut decoder = Decoder::new();
    let mut results = Vec::new();
    for piece in bytes.chunks(chunk) {
        decoder.push(piece);
        results.extend(decoder.frames());
        // Skipping keeps nothing: at most one push's worth is ever buffered.
        assert!(decoder.buffered_len() <= chunk);
    }
    decoder.finish();
    results.extend(decoder.frames());
    let want = CassetteError::Oversize {
        section: Section::Record(0),
        what: "payload",
        offset: header_len() as u64,
        len: len as u64,
        max: MAX_PAYLOAD_LEN as u64,
    };
    assert_eq!(results[1..], [Err(want), Ok(Frame::Record(good)), Ok(Frame::End { records: 1 })]);
}

#[test]
fn unknown_kinds_skip_their_record() {
    let h = header_len() as u64;
    let cases: [(Vec<u8>, &str, u8); 3] = [
        (raw_record(9, 0, 1, b"future"), "record kind", 9),
        (raw_record(4, 0, 1, &[7]), "event kind", 7),
        (raw_record(3, 0, 1, &raw_stream(1, 3, 24_000.0, 0, &[0; 8])), "sample format", 3),
    ];
    for (bad, what, code) in cases {
        let mut middle = bad;
        middle.extend_from_slice(&raw_record(4, 0, 2, &[2]));
        let results = decode(&framed(&middle, 1));
        let want = CassetteError::UnknownKind { section: Section::Record(0), what, code, offset: h };
        assert_eq!(errors(&results), vec![want]);
        // The next record is read normally.
        assert_eq!(records(&results), vec![Record { t_ns: 2, endpoint: 0, body: Body::Event(Event::Close) }]);
    }
}

/// The single error a one-record file with this record kind and payload gives.
fn content_error(kind: u8, payload: &[u8]) -> CassetteError {
    let results = decode(&framed(&raw_record(kind, 0, 1, payload), 0));
    let errors = errors(&results);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(records(&results).is_empty());
    errors[0].clone()
}

fn invalid(reason: Invalid) -> CassetteError {
    CassetteError::Invalid { section: Section::Record(0), offset: header_len() as u64, reason }
}

#[test]
fn invalid_stream_blocks_are_refused() {
    let f32s = |x: &[f32]| x.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    assert_eq!(content_error(3, &raw_stream(0, 1, 24e3, 0, &[])), invalid(Invalid::ZeroChannels));
    assert_eq!(
        content_error(3, &raw_stream(2, 1, 24e3, 0, &[0; 6])),
        invalid(Invalid::PartialFrame { samples: 6, channels: 4 })
    );
    assert_eq!(
        content_error(3, &raw_stream(1, 1, 24e3, 0, &[0; 18])[..18]),
        invalid(Invalid::StreamTooShort { len: 18, min: 19 })
    );
    for rate in [0.0, -0.0, -24e3, f64::INFINITY, f64::NEG_INFINITY] {
        let error = content_error(3, &raw_stream(1, 1, rate, 0, &[]));
        assert_eq!(error, invalid(Invalid::SampleRate { sample_rate_hz: rate }));
    }
    let error = content_error(3, &raw_stream(1, 1, f64::NAN, 0, &[]));
    assert!(matches!(error, CassetteError::Invalid { reason: Invalid::SampleRate { sample_rate_hz }, .. }
        if sample_rate_hz.is_nan()));
    assert_eq!(
        content_error(3, &raw_stream(1, 2, 24e3, 0, &f32s(&[0.0, f32::INFINITY]))),
        invalid(Invalid::NonFiniteSample { index: 1, value: f32::INFINITY })
    );
    let error = content_error(3, &raw_stream(2, 2, 24e3, 0, &f32s(&[1.0, 2.0, f32::NAN, 0.0])));
    assert!(matches!(error, CassetteError::Invalid { reason: Invalid::NonFiniteSample { index: 2, value }, .. }
        if value.is_nan()));
}

#[test]
fn invalid_events_are_refused() {
    assert_eq!(content_error(4, &[]), invalid(Invalid::EmptyEvent));
    assert_eq!(content_error(4, &[1, b'x']), invalid(Invalid::EventText { event: "open", len: 1 }));
    assert_eq!(content_error(4, &[6, 0xff, 0xfe]), invalid(Invalid::Utf8 { field: "note" }));
    let mut long = vec![6];
    long.resize(1 + MAX_NOTE_LEN + 1, b'a');
    assert_eq!(
        content_error(4, &long),
        invalid(Invalid::FieldTooLong { field: "note", len: MAX_NOTE_LEN + 1, max: MAX_NOTE_LEN })
    );
}

#[test]
fn out_of_order_records_are_dropped() {
    let h = header_len();
    let times = [100u64, 50, 150, 120, 150];
    let framed_records: Vec<Vec<u8>> = times.iter().map(|&t| raw_record(2, 0, t, b"v")).collect();
    let at: Vec<u64> =
        framed_records.iter().scan(h, |at, r| Some(std::mem::replace(at, *at + r.len()) as u64)).collect();
    let results = decode(&framed(&framed_records.concat(), 5));
    assert_eq!(records(&results).iter().map(|r| r.t_ns).collect::<Vec<_>>(), vec![100, 150, 150]);
    let order = |n: u64, previous_ns, t_ns| CassetteError::OutOfOrder {
        section: Section::Record(n),
        offset: at[n as usize],
        previous_ns,
        t_ns,
    };
    assert_eq!(
        errors(&results),
        vec![order(1, 100, 50), order(3, 150, 120), CassetteError::RecordCount { stored: 5, read: 3 }]
    );
}

#[test]
fn trailing_garbage_is_reported_once() {
    let s = session();
    let mut bytes = s.bytes.clone();
    bytes.extend_from_slice(b"junk after the end");
    let want = CassetteError::TrailingGarbage { offset: s.bytes.len() as u64 };
    for results in [decode(&bytes), decode_bytewise(&bytes)] {
        assert_eq!(errors(&results), vec![want.clone()]);
        assert_eq!(records(&results), s.cassette.records);
    }
    // Garbage pushed on its own, after the end was decoded, is reported the same way, and never buffered.
    let mut decoder = Decoder::new();
    decoder.push(&s.bytes);
    assert_eq!(decoder.frames().count(), 5);
    decoder.push(&[0; 1000]);
    assert_eq!(decoder.buffered_len(), 0);
    assert_eq!(decoder.poll(), Some(Err(want)));
    decoder.push(&[0; 1000]);
    decoder.finish();
    assert_eq!(decoder.poll(), None);
}

#[test]
fn trailer_checksum_mismatch_leaves_the_cassette_truncated() {
    let s = session();
    let mut bytes = s.bytes.clone();
    bytes[s.end_at + 4] ^= 1;
    let results = decode(&bytes);
    assert!(matches!(
        results[4],
        Err(CassetteError::Checksum { section: Section::Trailer, covers: "trailer", offset, .. })
            if offset == s.end_at as u64
    ));
    assert_eq!(results[5..], [Err(CassetteError::Truncated { offset: bytes.len() as u64, records: 3 })]);
    assert_eq!(records(&results), s.cassette.records);
}

#[test]
fn record_count_mismatch_is_reported_before_the_end() {
    let s = session();
    let mut bytes = s.bytes[..s.end_at].to_vec();
    bytes.extend_from_slice(&trailer(5));
    let results = decode(&bytes);
    assert_eq!(results[4..], [Err(CassetteError::RecordCount { stored: 5, read: 3 }), Ok(Frame::End { records: 5 })]);
}

#[test]
fn input_after_finish_is_ignored() {
    let s = session();
    let mut decoder = Decoder::new();
    decoder.push(&s.bytes[..s.end_at]);
    decoder.finish();
    decoder.push(&s.bytes[s.end_at..]);
    let results: Vec<_> = decoder.frames().collect();
    assert_eq!(results.last(), Some(&Err(CassetteError::Truncated { offset: s.end_at as u64, records: 3 })));
}

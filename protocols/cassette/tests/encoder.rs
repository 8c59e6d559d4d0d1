//! The encoder refuses what the format cannot hold, at the edges of every limit, and stays usable after an error.
//! Exact comparisons: limits are byte counts and the format is lossless.
#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{decode, header};
use metaplate_cassette::{
    Body, Cassette, CassetteError, DeviceIdentity, Encoder, Event, Frame, Invalid, MAX_IDENTITY_FIELD_LEN,
    MAX_NOTE_LEN, MAX_PAYLOAD_LEN, Record, Samples, Section, StreamBlock,
};

fn stream(channels: u16, sample_rate_hz: f64, samples: Samples) -> Body {
    Body::Stream(StreamBlock { channels, sample_rate_hz, first_sample_index: 0, samples })
}

fn record(t_ns: u64, body: Body) -> Record {
    Record { t_ns, endpoint: 7, body }
}

/// An encoder with the header written, and its output.
fn started() -> (Encoder, Vec<u8>) {
    let mut encoder = Encoder::new();
    let mut out = Vec::new();
    encoder.header(&header(), &mut out).unwrap();
    (encoder, out)
}

/// Checks that `record` is refused with `want` and that the refusal wrote nothing and changed nothing.
fn assert_refused(record: &Record, want: impl Fn(&CassetteError) -> bool) {
    let (mut encoder, mut out) = started();
    let before = (out.clone(), encoder.records(), encoder.bytes_written());
    let error = encoder.record(record, &mut out).unwrap_err();
    assert!(want(&error), "unexpected {error:?}");
    assert_eq!((out.clone(), encoder.records(), encoder.bytes_written()), before);
}

/// Encodes `records` in one cassette and checks they decode unchanged.
fn assert_round_trip(records: Vec<Record>) {
    let cassette = Cassette { header: header(), records };
    assert_eq!(Cassette::from_bytes(&cassette.to_bytes().unwrap()).unwrap(), cassette);
}

#[test]
fn calls_out_of_order_are_refused() {
    let mut encoder = Encoder::new();
    let mut out = Vec::new();
    let r = record(0, Body::Event(Event::Open));
    assert!(matches!(encoder.record(&r, &mut out), Err(CassetteError::EncoderState { .. })));
    assert!(matches!(encoder.end(&mut out), Err(CassetteError::EncoderState { .. })));
    assert!(out.is_empty());
    encoder.header(&header(), &mut out).unwrap();
    assert!(matches!(encoder.header(&header(), &mut out), Err(CassetteError::EncoderState { .. })));
    encoder.end(&mut out).unwrap();
    let len = out.len();
    assert!(matches!(encoder.end(&mut out), Err(CassetteError::EncoderState { .. })));
    assert!(matches!(encoder.record(&r, &mut out), Err(CassetteError::EncoderState { .. })));
    assert_eq!(out.len(), len);
}

#[test]
fn timestamps_never_decrease_and_span_the_full_range() {
    let (mut encoder, mut out) = started();
    let ev = |t| record(t, Body::Event(Event::Timeout));
    encoder.record(&ev(0), &mut out).unwrap();
    encoder.record(&ev(0), &mut out).unwrap(); // equal is in order
    encoder.record(&ev(u64::MAX - 1), &mut out).unwrap();
    let offset = encoder.bytes_written();
    let error = encoder.record(&ev(5), &mut out).unwrap_err();
    assert_eq!(
        error,
        CassetteError::OutOfOrder { section: Section::Record(3), offset, previous_ns: u64::MAX - 1, t_ns: 5 }
    );
    // Still usable after the refusal.
    encoder.record(&ev(u64::MAX), &mut out).unwrap();
    encoder.end(&mut out).unwrap();
    let times: Vec<u64> = common::records(&decode(&out)).iter().map(|r| r.t_ns).collect();
    assert_eq!(times, vec![0, 0, u64::MAX - 1, u64::MAX]);
}

#[test]
fn identity_fields_are_bounded() {
    let full = "é".repeat(MAX_IDENTITY_FIELD_LEN / 2) + "x"; // 255 bytes, multi-byte chars
    assert_eq!(full.len(), MAX_IDENTITY_FIELD_LEN);
    let mut h = header();
    h.identity = DeviceIdentity { vendor: full.clone(), model: full.clone(), serial: full.clone(), firmware: full };
    let cassette = Cassette::new(h.clone());
    assert_eq!(Cassette::from_bytes(&cassette.to_bytes().unwrap()).unwrap(), cassette);

    h.identity.serial.push('y');
    let mut out = Vec::new();
    let error = Encoder::new().header(&h, &mut out).unwrap_err();
    let reason = Invalid::FieldTooLong { field: "serial", len: 256, max: MAX_IDENTITY_FIELD_LEN };
    assert_eq!(error, CassetteError::Invalid { section: Section::Header, offset: 0, reason });
    assert!(out.is_empty());
}

#[test]
fn payloads_are_bounded_at_16_mib() {
    // Exactly the limit is written and read back; one byte more is refused before anything is written.
    assert_round_trip(vec![record(1, Body::DeviceToHost(vec![0xa5; MAX_PAYLOAD_LEN]))]);
    assert_round_trip(vec![record(1, Body::HostToDevice(Vec::new()))]);
    assert_refused(&record(1, Body::HostToDevice(vec![0; MAX_PAYLOAD_LEN + 1])), |e| {
        matches!(e, CassetteError::Oversize { what: "payload", len, max, .. }
            if *len == MAX_PAYLOAD_LEN as u64 + 1 && *max == MAX_PAYLOAD_LEN as u64)
    });
    // A stream block's size counts its 19-byte sub-header: (MAX - 19) / 2 samples fit, one more does not.
    let fits = (MAX_PAYLOAD_LEN - 19) / 2;
    assert_round_trip(vec![record(1, stream(1, 24e3, Samples::I16(vec![-1; fits])))]);
    assert_refused(&record(1, stream(1, 24e3, Samples::I16(vec![0; fits + 1]))), |e| {
        matches!(e, CassetteError::Oversize { .. })
    });
}

#[test]
fn notes_are_bounded_at_64_kib() {
    assert_round_trip(vec![
        record(1, Body::Event(Event::Note("n".repeat(MAX_NOTE_LEN)))),
        record(2, Body::Event(Event::Note(String::new()))),
    ]);
    let reason = Invalid::FieldTooLong { field: "note", len: MAX_NOTE_LEN + 1, max: MAX_NOTE_LEN };
    assert_refused(
        &record(1, Body::Event(Event::Note("n".repeat(MAX_NOTE_LEN + 1)))),
        |e| matches!(e, CassetteError::Invalid { reason: r, .. } if *r == reason),
    );
}

#[test]
fn stream_blocks_hold_their_extremes() {
    assert_round_trip(vec![
        record(1, stream(1, f64::MIN_POSITIVE, Samples::I16(vec![i16::MIN, i16::MAX, 0]))),
        record(2, stream(1, f64::MAX, Samples::F32(vec![f32::MAX, f32::MIN, f32::MIN_POSITIVE, -0.0, 1e-45]))),
        record(3, stream(u16::MAX, 24e3, Samples::I16(vec![3; usize::from(u16::MAX)]))),
        record(4, stream(8, 24e3, Samples::F32(Vec::new()))),
    ]);
    // -0.0 and the smallest subnormal keep their bits (PartialEq alone would not tell -0.0 from 0.0).
    let cassette =
        Cassette { header: header(), records: vec![record(1, stream(2, 24e3, Samples::F32(vec![-0.0, 1e-45])))] };
    let back = Cassette::from_bytes(&cassette.to_bytes().unwrap()).unwrap();
    let Body::Stream(StreamBlock { samples: Samples::F32(x), .. }) = &back.records[0].body else { panic!() };
    assert_eq!(x.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), vec![(-0.0f32).to_bits(), 1e-45f32.to_bits()]);
}

#[test]
fn invalid_stream_blocks_are_refused() {
    let is =
        |want: Invalid| move |e: &CassetteError| matches!(e, CassetteError::Invalid { reason, .. } if *reason == want);
    assert_refused(&record(1, stream(0, 24e3, Samples::I16(vec![]))), is(Invalid::ZeroChannels));
    assert_refused(
        &record(1, stream(3, 24e3, Samples::I16(vec![1, 2, 3, 4]))),
        is(Invalid::PartialFrame { samples: 4, channels: 3 }),
    );
    for rate in [0.0, -0.0, -1.0, f64::INFINITY, f64::NEG_INFINITY] {
        assert_refused(
            &record(1, stream(1, rate, Samples::I16(vec![]))),
            is(Invalid::SampleRate { sample_rate_hz: rate }),
        );
    }
    assert_refused(
        &record(1, stream(1, f64::NAN, Samples::I16(vec![]))),
        |e| matches!(e, CassetteError::Invalid { reason: Invalid::SampleRate { sample_rate_hz }, .. } if sample_rate_hz.is_nan()),
    );
    for bad in [f32::INFINITY, f32::NEG_INFINITY] {
        assert_refused(
            &record(1, stream(1, 24e3, Samples::F32(vec![0.0, bad]))),
            is(Invalid::NonFiniteSample { index: 1, value: bad }),
        );
    }
    assert_refused(
        &record(1, stream(1, 24e3, Samples::F32(vec![f32::NAN]))),
        |e| matches!(e, CassetteError::Invalid { reason: Invalid::NonFiniteSample { index: 0, value }, .. } if value.is_nan()),
    );
}

#[test]
fn cassettes_are_plain_data_to_edit_and_re_encode() {
    // What a fault injector does: copy a cassette, drop a reply, corrupt another, and encode the result.
    let original = Cassette {
        header: header(),
        records: vec![
            record(1, Body::HostToDevice(b"GET\r".to_vec())),
            record(2, Body::DeviceToHost(b"42\r".to_vec())),
            record(3, Body::DeviceToHost(b"43\r".to_vec())),
        ],
    };
    let mut faulty = original.clone();
    faulty.records.remove(1);
    if let Body::DeviceToHost(bytes) = &mut faulty.records[1].body {
        bytes[0] = b'X';
    }
    let back = Cassette::from_bytes(&faulty.to_bytes().unwrap()).unwrap();
    assert_eq!(back, faulty);
    assert_ne!(back, original);
    assert_eq!(decode(&faulty.to_bytes().unwrap()).last(), Some(&Ok(Frame::End { records: 2 })));
}

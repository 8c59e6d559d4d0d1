//! Byte-exact tests: the documented example and a richer session, against bytes built independently (Python's
//! `struct` and `zlib.crc32`, script in the test comments). Exact equality throughout: the format is lossless.
#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::{decode, decode_bytewise};
use metaplate_cassette::{
    Body, Cassette, DeviceIdentity, DeviceKind, Encoder, Event, Frame, Header, Record, Samples, StreamBlock,
};

fn unhex(lines: &[&str]) -> Vec<u8> {
    let hex: String = lines.concat();
    (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap()).collect()
}

/// The crate documentation's example: an LDV session with one command.
fn doc_example() -> Cassette {
    Cassette {
        header: Header {
            device_kind: DeviceKind::LdvSerial,
            identity: DeviceIdentity { vendor: "Om".into(), model: "8330".into(), ..Default::default() },
            start_unix_ns: 1_000_000_000,
        },
        records: vec![Record { t_ns: 0, endpoint: 0, body: Body::HostToDevice(b"Q\r".to_vec()) }],
    }
}

const DOC_EXAMPLE_HEX: &[&str] = &[
    "4d504341535345540100000025000100ca9a3b00000000024f6d043833333000005d464321895245430100000000000000",
    "000000020000000a130cb2510d0bb1d36c89454e440100000000000000354303ee",
];

#[test]
fn doc_example_encodes_byte_for_byte() {
    let bytes = doc_example().to_bytes().unwrap();
    assert_eq!(bytes.len(), 82);
    assert_eq!(bytes, unhex(DOC_EXAMPLE_HEX));
}

#[test]
fn doc_example_decodes() {
    let bytes = unhex(DOC_EXAMPLE_HEX);
    let expected = doc_example();
    assert_eq!(Cassette::from_bytes(&bytes).unwrap(), expected);
    let frames = decode_bytewise(&bytes);
    assert_eq!(
        frames,
        vec![
            Ok(Frame::Header(expected.header.clone())),
            Ok(Frame::Record(expected.records[0].clone())),
            Ok(Frame::End { records: 1 })
        ]
    );
}

/// A DAQ session with every record kind, both sample formats, two records at the same instant, and a note.
fn rich_session() -> Cassette {
    let rec = |t_ns, endpoint, body| Record { t_ns, endpoint, body };
    Cassette {
        header: Header {
            device_kind: DeviceKind::DaqUsb,
            identity: DeviceIdentity {
                vendor: "NI".into(),
                model: "USB-6211".into(),
                serial: "01ABCDEF".into(),
                firmware: "1.2.3".into(),
            },
            start_unix_ns: 1_700_000_000_123_456_789,
        },
        records: vec![
            rec(0, 0, Body::Event(Event::Open)),
            rec(1000, 1, Body::HostToDevice(b"\x01\x02START".to_vec())),
            rec(2500, 0x81, Body::DeviceToHost(b"OK".to_vec())),
            rec(
                3000,
                0x82,
                Body::Stream(StreamBlock {
                    channels: 2,
                    sample_rate_hz: 24_000.0,
                    first_sample_index: 0,
                    samples: Samples::I16(vec![1, -1, i16::MAX, i16::MIN]),
                }),
            ),
            rec(
                3000,
                3,
                Body::Stream(StreamBlock {
                    channels: 1,
                    sample_rate_hz: 48_000.0,
                    first_sample_index: 12_345,
                    samples: Samples::F32(vec![0.5, -0.25, 1.0]),
                }),
            ),
            rec(4000, 0, Body::Event(Event::Note("drift 12 ppm".into()))),
            rec(5000, 1, Body::Event(Event::Timeout)),
            rec(6000, 0, Body::Event(Event::Close)),
        ],
    }
}

// Built by: header(2, 1_700_000_000_123_456_789, [NI, USB-6211, 01ABCDEF, 1.2.3]) + the eight records framed as
// struct.pack('<4sBHQI') + crc32 + payload + crc32 + the end marker, with zlib.crc32.
const RICH_HEX: &[&str] = &[
    "4d504341535345540100000036000215cd853dfe9c9717024e49085553422d3632313108303141424344454605312e32",
    "2e336c15baf4895245430400000000000000000000010000006f023e93018bc725b189524543010100e8030000000000",
    "00070000005911a6cf01025354415254717b372e89524543028100c409000000000000020000000daae2954f4b716a2d",
    "2789524543038200b80b0000000000001b0000009f394504020001000000000070d74000000000000000000100ffffff",
    "7f008001c8636189524543030300b80b0000000000001f0000005ca05b95010002000000000070e74039300000000000",
    "000000003f000080be0000803f2c5e23a189524543040000a00f0000000000000d00000009fde6320664726966742031",
    "322070706dd47f04fd89524543040100881300000000000001000000cd58ee5f03a7a62b5f8952454304000070170000",
    "0000000001000000d352b9300231962c2889454e4408000000000000001e584cf1",
];

#[test]
fn rich_session_encodes_byte_for_byte() {
    let bytes = rich_session().to_bytes().unwrap();
    assert_eq!(bytes.len(), 369);
    assert_eq!(bytes, unhex(RICH_HEX));
}

#[test]
fn rich_session_encodes_the_same_incrementally() {
    // A recorder writes as it goes: header, each record, end. Same bytes as the one-shot encoding.
    let session = rich_session();
    let mut encoder = Encoder::new();
    let mut out = Vec::new();
    encoder.header(&session.header, &mut out).unwrap();
    for record in &session.records {
        encoder.record(record, &mut out).unwrap();
    }
    encoder.end(&mut out).unwrap();
    assert_eq!(encoder.records(), 8);
    assert_eq!(encoder.bytes_written(), out.len() as u64);
    assert_eq!(out, unhex(RICH_HEX));
}

#[test]
fn rich_session_decodes_whole_and_bytewise() {
    let bytes = unhex(RICH_HEX);
    let expected = rich_session();
    assert_eq!(Cassette::from_bytes(&bytes).unwrap(), expected);
    let mut want = vec![Ok(Frame::Header(expected.header.clone()))];
    want.extend(expected.records.iter().cloned().map(|r| Ok(Frame::Record(r))));
    want.push(Ok(Frame::End { records: 8 }));
    assert_eq!(decode(&bytes), want);
    assert_eq!(decode_bytewise(&bytes), want);
}

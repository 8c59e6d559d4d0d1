//! Property tests: every message type survives encode then decode, with the bytes split at random points.
//! Equality is exact: the format stores every field losslessly (f32 and f64 bit for bit).
#![allow(clippy::unwrap_used)] // tests may unwrap: a panic is the test failing

use crate::common;

use common::decode_split;
use metaplate_cassette::{
    Body, Cassette, DeviceIdentity, DeviceKind, Event, Frame, Header, MAX_IDENTITY_FIELD_LEN, Record, Samples,
    StreamBlock,
};
use proptest::prelude::*;
use proptest::sample::Index;

fn text(max_bytes: usize) -> impl Strategy<Value = String> {
    // Any chars (multi-byte included), cut back to the byte limit on a char boundary.
    prop::collection::vec(any::<char>(), 0..max_bytes.min(80)).prop_map(move |chars| {
        let mut s = String::new();
        for c in chars {
            if s.len() + c.len_utf8() > max_bytes {
                break;
            }
            s.push(c);
        }
        s
    })
}

fn arb_header() -> impl Strategy<Value = Header> {
    let field = || text(MAX_IDENTITY_FIELD_LEN);
    (prop::sample::select(DeviceKind::ALL.to_vec()), field(), field(), field(), field(), any::<u64>()).prop_map(
        |(device_kind, vendor, model, serial, firmware, start_unix_ns)| Header {
            device_kind,
            identity: DeviceIdentity { vendor, model, serial, firmware },
            start_unix_ns,
        },
    )
}

fn arb_bytes() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(any::<u8>(), 0..200)
}

fn arb_rate() -> impl Strategy<Value = f64> {
    // Positive finite rates over many decades, including awkward non-integer ones.
    prop_oneof![Just(24_000.0), Just(48_000.0), 1e-3f64..1e9]
}

fn arb_stream_i16() -> impl Strategy<Value = Body> {
    (1u16..9, 0usize..40, arb_rate(), any::<u64>()).prop_flat_map(|(channels, frames, rate, first)| {
        prop::collection::vec(any::<i16>(), usize::from(channels) * frames).prop_map(move |x| {
            Body::Stream(StreamBlock {
                channels,
                sample_rate_hz: rate,
                first_sample_index: first,
                samples: Samples::I16(x),
            })
        })
    })
}

fn arb_stream_f32() -> impl Strategy<Value = Body> {
    let finite = prop::num::f32::NORMAL | prop::num::f32::SUBNORMAL | prop::num::f32::ZERO;
    (1u16..9, 0usize..40, arb_rate(), any::<u64>()).prop_flat_map(move |(channels, frames, rate, first)| {
        prop::collection::vec(finite, usize::from(channels) * frames).prop_map(move |x| {
            Body::Stream(StreamBlock {
                channels,
                sample_rate_hz: rate,
                first_sample_index: first,
                samples: Samples::F32(x),
            })
        })
    })
}

fn arb_event() -> impl Strategy<Value = Body> {
    prop_oneof![
        Just(Event::Open),
        Just(Event::Close),
        Just(Event::Timeout),
        Just(Event::Disconnect),
        Just(Event::Reconnect),
        text(300).prop_map(Event::Note),
    ]
    .prop_map(Body::Event)
}

fn arb_body() -> impl Strategy<Value = Body> {
    prop_oneof![
        arb_bytes().prop_map(Body::HostToDevice),
        arb_bytes().prop_map(Body::DeviceToHost),
        arb_stream_i16(),
        arb_stream_f32(),
        arb_event(),
    ]
}

/// Records with non-decreasing timestamps (steps of zero included) built from `bodies`.
fn arb_records(body: impl Strategy<Value = Body>, max: usize) -> impl Strategy<Value = Vec<Record>> {
    prop::collection::vec((0u64..1_000_000, any::<u16>(), body), 0..max).prop_map(|steps| {
        let mut t_ns = 0u64;
        steps
            .into_iter()
            .map(|(dt, endpoint, body)| {
                t_ns = t_ns.saturating_add(dt);
                Record { t_ns, endpoint, body }
            })
            .collect()
    })
}

fn arb_cuts() -> impl Strategy<Value = Vec<Index>> {
    prop::collection::vec(any::<Index>(), 0..12)
}

/// Encodes `cassette`, decodes it split at `cuts`, and checks that exactly header, records and end come back.
fn assert_round_trip(cassette: &Cassette, cuts: &[Index]) -> Result<(), TestCaseError> {
    let bytes = cassette.to_bytes().map_err(|e| TestCaseError::fail(e.to_string()))?;
    let cuts: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
    let mut want = vec![Ok(Frame::Header(cassette.header.clone()))];
    want.extend(cassette.records.iter().cloned().map(|r| Ok(Frame::Record(r))));
    want.push(Ok(Frame::End { records: cassette.records.len() as u64 }));
    prop_assert_eq!(decode_split(&bytes, &cuts), want);
    Ok(())
}

proptest! {
    #[test]
    fn header_round_trips(header in arb_header(), cuts in arb_cuts()) {
        assert_round_trip(&Cassette::new(header), &cuts)?;
    }

    #[test]
    fn host_to_device_round_trips(records in arb_records(arb_bytes().prop_map(Body::HostToDevice), 8),
                                  cuts in arb_cuts()) {
        assert_round_trip(&Cassette { header: common::header(), records }, &cuts)?;
    }

    #[test]
    fn device_to_host_round_trips(records in arb_records(arb_bytes().prop_map(Body::DeviceToHost), 8),
                                  cuts in arb_cuts()) {
        assert_round_trip(&Cassette { header: common::header(), records }, &cuts)?;
    }

    #[test]
    fn i16_stream_round_trips(records in arb_records(arb_stream_i16(), 6), cuts in arb_cuts()) {
        assert_round_trip(&Cassette { header: common::header(), records }, &cuts)?;
    }

    #[test]
    fn f32_stream_round_trips(records in arb_records(arb_stream_f32(), 6), cuts in arb_cuts()) {
        assert_round_trip(&Cassette { header: common::header(), records }, &cuts)?;
    }

    #[test]
    fn events_round_trip(records in arb_records(arb_event(), 10), cuts in arb_cuts()) {
        assert_round_trip(&Cassette { header: common::header(), records }, &cuts)?;
    }

    #[test]
    fn mixed_sessions_round_trip(header in arb_header(), records in arb_records(arb_body(), 16),
                                 cuts in arb_cuts()) {
        let cassette = Cassette { header, records };
        assert_round_trip(&cassette, &cuts)?;
        // The whole-file reader agrees with the incremental decoder.
        prop_assert_eq!(Cassette::from_bytes(&cassette.to_bytes().unwrap()).unwrap(), cassette);
    }

    /// Corrupting any one byte never panics, and the decoder's results do not depend on how the input was split.
    #[test]
    fn corruption_is_split_independent(records in arb_records(arb_body(), 6), at in any::<Index>(),
                                       xor in 1u8..=255, cuts in arb_cuts()) {
        let mut bytes = Cassette { header: common::header(), records }.to_bytes().unwrap();
        let at = at.index(bytes.len());
        bytes[at] ^= xor;
        let cuts: Vec<usize> = cuts.iter().map(|i| i.index(bytes.len() + 1)).collect();
        let whole = format!("{:?}", common::decode(&bytes));
        prop_assert_eq!(format!("{:?}", decode_split(&bytes, &cuts)), whole);
        // A flipped byte is always noticed: some error is reported.
        prop_assert!(common::decode(&bytes).iter().any(|r| r.is_err()));
    }
}

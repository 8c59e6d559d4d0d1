//! Hostile input: every decoder returns a typed error or waits, never panics, and holds bounded memory.

use metaplate_polytec_protocol::{MAX_LINE_CONTENT, PolytecProtocolError, ReplyDecoder, Request, RequestDecoder};
use proptest::prelude::*;

#[test]
fn malformed_requests_say_what_is_wrong() {
    for (line, want) in [
        ("Fetch,VeloDec,0,Range", "verb"),
        ("Get,Laser,0,Range", "unknown device"),
        ("Get,VeloDec,x,Range", "index"),
        ("Get,VeloDec,256,Range", "index"),
        ("Get,VeloDec,0", "no attribute"),
        ("Set,VeloDec,0,Range", "without a value"),
        ("Get,VeloDec,0,Range,5mm/s/V", "takes no value"),
        ("Get,VeloDec,0,Ra nge", "letters and digits"),
    ] {
        match Request::parse(line) {
            Err(PolytecProtocolError::MalformedRequest { detail, .. }) => {
                assert!(detail.contains(want), "{line}: {detail}")
            }
            other => panic!("{line}: {other:?}"),
        }
    }
}

proptest! {
    #[test]
    fn any_bytes_decode_without_panic_in_bounded_memory(chunks in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..300), 0..20)) {
        let mut requests = RequestDecoder::new();
        let mut replies = ReplyDecoder::new();
        for chunk in &chunks {
            requests.push(chunk);
            replies.push(chunk);
            while requests.poll().is_some() {}
            while replies.poll().is_some() {}
            prop_assert!(requests.buffered_len() <= MAX_LINE_CONTENT);
            prop_assert!(replies.buffered_len() <= MAX_LINE_CONTENT);
        }
    }

    #[test]
    fn every_valid_request_round_trips(index in any::<u8>(), attr in "[A-Za-z][A-Za-z0-9]{0,20}", value in "[ -+\\--~]{1,30}") {
        prop_assume!(!value.trim().is_empty());
        let request = Request::set(metaplate_polytec_protocol::Device::VeloDec, index, &attr, value.trim()).unwrap();
        let mut decoder = RequestDecoder::new();
        decoder.push(&request.encode());
        prop_assert_eq!(decoder.poll().unwrap().unwrap(), request);
    }
}

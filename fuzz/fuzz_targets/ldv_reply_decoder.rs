//! Host side of the LDV protocol: arbitrary controller bytes, in arbitrary chunks, into `ReplyDecoder`.
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at
//! most one line (`MAX_LINE_CONTENT` bytes); chunking does not change what is decoded; every reply decoded
//! re-encodes within `MAX_LINE_LEN` to bytes that decode back to the same reply.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_ldv_protocol::{MAX_LINE_CONTENT, MAX_LINE_LEN, ReplyDecoder, encode_reply};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut ReplyDecoder::new(),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| d.drain().collect(),
        |d| d.buffered_len() <= MAX_LINE_CONTENT,
    );

    let mut whole = ReplyDecoder::new();
    whole.push(payload);
    let at_once: Vec<_> = whole.drain().collect();
    assert_eq!(chunked, at_once);

    for reply in chunked.into_iter().flatten() {
        let bytes = encode_reply(&reply);
        assert!(bytes.len() <= MAX_LINE_LEN);
        let mut again = ReplyDecoder::new();
        again.push(&bytes);
        assert_eq!(again.poll(), Some(Ok(reply)));
        assert_eq!(again.poll(), None);
    }
});

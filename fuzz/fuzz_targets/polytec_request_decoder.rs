//! Device side of Polytec's RS-232 syntax (the mock controller's): arbitrary host bytes, in arbitrary chunks, into
//! `RequestDecoder`.
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at most one line
//! (`MAX_LINE_CONTENT` bytes); chunking does not change what is decoded; every request decoded re-encodes to one
//! line that decodes back to the same request.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_polytec_protocol::{MAX_LINE_CONTENT, RequestDecoder};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut RequestDecoder::new(),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| std::iter::from_fn(|| d.poll()).collect::<Vec<_>>(),
        |d| d.buffered_len() <= MAX_LINE_CONTENT,
    );

    let mut whole = RequestDecoder::new();
    whole.push(payload);
    let at_once: Vec<_> = std::iter::from_fn(|| whole.poll()).collect();
    assert_eq!(chunked, at_once);

    for request in chunked.into_iter().flatten() {
        let bytes = request.encode();
        assert!(bytes.len() <= MAX_LINE_CONTENT + 1);
        let mut again = RequestDecoder::new();
        again.push(&bytes);
        assert_eq!(again.poll(), Some(Ok(request)));
        assert_eq!(again.poll(), None);
    }
});

//! Host side of Polytec's RS-232 syntax: arbitrary controller bytes, in arbitrary chunks, into `ReplyDecoder`,
//! and every decoded line through the parsers the driver applies (lists, integers, velocity ranges).
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at most one line
//! (`MAX_LINE_CONTENT` bytes); chunking does not change what is decoded; a line decodes to text without control
//! characters; a parsed velocity range is positive and finite.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_polytec_protocol::{MAX_LINE_CONTENT, ReplyDecoder, VelocityRange, parse_count, split_list};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut ReplyDecoder::new(),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| std::iter::from_fn(|| d.poll()).collect::<Vec<_>>(),
        |d| d.buffered_len() <= MAX_LINE_CONTENT,
    );

    let mut whole = ReplyDecoder::new();
    whole.push(payload);
    let at_once: Vec<_> = std::iter::from_fn(|| whole.poll()).collect();
    assert_eq!(chunked, at_once);

    for line in chunked.into_iter().flatten() {
        assert!(!line.chars().any(char::is_control));
        let _ = parse_count(&line);
        for item in split_list(&line) {
            if let Ok(range) = VelocityRange::parse(item) {
                assert!(range.m_s_per_v().is_finite() && range.m_s_per_v() > 0.0);
            }
        }
    }
});

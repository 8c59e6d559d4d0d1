//! Device side of the LDV protocol: arbitrary host bytes, in arbitrary chunks, into `CommandDecoder`.
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at
//! most one line (`MAX_LINE_CONTENT` bytes); chunking does not change what is decoded; every command decoded
//! re-encodes within `MAX_LINE_LEN` to bytes that decode back to the same command; every error becomes an `ERR`
//! reply that encodes within `MAX_LINE_LEN` and decodes back to itself (what the mock controller would send).

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_ldv_protocol::{
    CommandDecoder, MAX_LINE_CONTENT, MAX_LINE_LEN, Reply, ReplyDecoder, encode_command, encode_reply,
};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let chunked = chunks::feed(
        &mut CommandDecoder::new(),
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| d.drain().collect(),
        |d| d.buffered_len() <= MAX_LINE_CONTENT,
    );

    let mut whole = CommandDecoder::new();
    whole.push(payload);
    let at_once: Vec<_> = whole.drain().collect();
    assert_eq!(chunked, at_once);

    for result in chunked {
        match result {
            Ok(command) => {
                let bytes = encode_command(&command);
                assert!(bytes.len() <= MAX_LINE_LEN);
                let mut again = CommandDecoder::new();
                again.push(&bytes);
                assert_eq!(again.poll(), Some(Ok(command)));
                assert_eq!(again.poll(), None);
            }
            Err(error) => {
                let reply = Reply::from_error(&error);
                let bytes = encode_reply(&reply);
                assert!(bytes.len() <= MAX_LINE_LEN);
                let mut host = ReplyDecoder::new();
                host.push(&bytes);
                assert_eq!(host.poll(), Some(Ok(reply)));
            }
        }
    }
});

//! Helpers shared by the integration tests.
#![allow(dead_code)]

use metaplate_daq_protocol::{DaqError, Decoder, Frame, Message};

/// Bytes from space-separated hex pairs.
pub fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace().map(|b| u8::from_str_radix(b, 16).unwrap()).collect()
}

/// Pushes `bytes` cut at the (sorted, deduplicated, clamped) positions `cuts`, polling dry after every push, and
/// checks the buffer bound after each drain. Returns every result in order.
pub fn decode_split<M: Message>(bytes: &[u8], cuts: &[usize]) -> Vec<Result<Frame<M>, DaqError>> {
    let mut cuts: Vec<usize> = cuts.iter().map(|&c| c.min(bytes.len())).collect();
    cuts.push(bytes.len());
    cuts.sort_unstable();
    cuts.dedup();
    let mut decoder = Decoder::<M>::new();
    let mut out = Vec::new();
    let mut from = 0;
    for cut in cuts {
        decoder.push(&bytes[from..cut]);
        from = cut;
        out.extend(decoder.decoded());
        assert!(decoder.buffered_len() < metaplate_daq_protocol::MAX_FRAME_LEN);
    }
    out
}

/// Decodes `bytes` pushed in one piece.
pub fn decode_all<M: Message>(bytes: &[u8]) -> Vec<Result<Frame<M>, DaqError>> {
    decode_split(bytes, &[])
}

//! Host side of the DAQ protocol: arbitrary device bytes (bulk IN), in arbitrary chunks, into `HostDecoder`.
//!
//! Input layout: byte 0 gives the number of cuts (0 to 15), the next bytes give each cut's position as a fraction
//! of the payload (byte / 256), the rest is the payload. Asserts: no panic; after draining, the decoder holds less
//! than one maximum frame (`MAX_FRAME_LEN`); chunking does not change what is decoded (errors included); every
//! message decoded re-encodes, within `MAX_FRAME_LEN`, to bytes that decode back to the same frame.

#![no_main]

use libfuzzer_sys::fuzz_target;
use metaplate_daq_protocol::{HostDecoder, MAX_FRAME_LEN, encode};

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else { return };
    let cut_count = usize::from(head % 16).min(rest.len());
    let (cut_bytes, payload) = rest.split_at(cut_count);
    let mut cuts: Vec<usize> = cut_bytes.iter().map(|&b| usize::from(b) * payload.len() / 256).collect();
    cuts.push(payload.len());
    cuts.sort_unstable();

    let mut decoder = HostDecoder::new();
    let mut chunked = Vec::new();
    let mut start = 0;
    for cut in cuts {
        decoder.push(&payload[start..cut]);
        start = cut;
        chunked.extend(decoder.decoded());
        assert!(decoder.buffered_len() < MAX_FRAME_LEN);
    }

    let mut whole = HostDecoder::new();
    whole.push(payload);
    let at_once: Vec<_> = whole.decoded().collect();
    assert_eq!(chunked, at_once);

    for frame in chunked.into_iter().flatten() {
        let bytes = encode(frame.seq, &frame.message).expect("a decoded message re-encodes");
        assert!(bytes.len() <= MAX_FRAME_LEN);
        let mut again = HostDecoder::new();
        again.push(&bytes);
        assert_eq!(again.poll(), Some(Ok(frame)));
        assert_eq!(again.poll(), None);
    }
});

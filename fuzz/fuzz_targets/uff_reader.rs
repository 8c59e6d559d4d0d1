//! Universal files: arbitrary bytes, in arbitrary chunks, into the UFF `UffDecoder`.
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at most one line
//! (`max_line_bytes` + its line end); chunking does not change what is decoded; every record decoded (but
//! datasets stepped over) is accepted by the encoder, and decoding what it writes gives the same record (units and
//! nodes exactly; functions exactly but for record 7's numbers, which the encoder writes with 6 digits) and
//! writes the same bytes again.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_uff::{ByteOrder, UffDecoder, UffEncoder, Format, Limits, Precision, UffRecord};

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let max_line = Limits::default().max_line_bytes;
    let mut decoder = UffDecoder::new();
    let mut chunked = chunks::feed(
        &mut decoder,
        payload,
        &cuts,
        |d, bytes| d.push(bytes),
        |d| d.records().collect::<Vec<_>>(),
        |d| d.buffered_len() <= max_line + 1,
    );
    decoder.finish();
    chunked.extend(decoder.records());

    let mut whole = UffDecoder::new();
    whole.push(payload);
    whole.finish();
    let at_once: Vec<_> = whole.records().collect();
    // Compared as text: a non-finite value reported in an error is NaN, not equal to itself.
    assert_eq!(format!("{chunked:?}"), format!("{at_once:?}"));

    let encoder = UffEncoder::new(Format::Binary { byte_order: ByteOrder::LittleEndian }, Precision::Double);
    for record in at_once.into_iter().flatten() {
        if matches!(record, UffRecord::Other(_)) {
            continue;
        }
        let mut bytes = Vec::new();
        encoder.encode(&record, &mut bytes).expect("the encoder accepts every decoded record");
        let mut again = UffDecoder::new();
        again.push(&bytes);
        again.finish();
        let decoded: Vec<_> = again.records().collect();
        assert_eq!(decoded.len(), 1, "{decoded:?}");
        let Ok(decoded) = &decoded[0] else { panic!("{decoded:?}") };
        match (&record, decoded) {
            (UffRecord::Function(before), UffRecord::Function(after)) => {
                assert_eq!(before.ordinate, after.ordinate);
                let mut header = after.header.clone();
                header.abscissa_start = before.header.abscissa_start;
                header.abscissa_step = before.header.abscissa_step;
                header.z_axis_value = before.header.z_axis_value;
                assert_eq!(header, before.header);
            }
            (before, after) => assert_eq!(before, after),
        }
        let mut bytes_again = Vec::new();
        encoder.encode(decoded, &mut bytes_again).expect("re-encoding");
        let mut third = UffDecoder::new();
        third.push(&bytes_again);
        third.finish();
        let mut bytes_third = Vec::new();
        for r in third.records() {
            encoder.encode(&r.expect("decodes"), &mut bytes_third).expect("encodes");
        }
        assert_eq!(bytes_again, bytes_third);
    }
});

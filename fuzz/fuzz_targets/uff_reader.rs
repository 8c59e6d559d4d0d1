//! Universal files: arbitrary bytes, in arbitrary chunks, into the UFF `UffDecoder`.
//!
//! Input layout: `common/chunks.rs`. Asserts: no panic; after draining, the decoder holds at most one line
//! (`max_line_bytes` + its line end); chunking does not change what is decoded, by the plain decoder and by one
//! decoding only responses (`only_functions`, as an import reads: other datasets 58 stepped over after record 6),
//! which gives no function of another type; every record decoded (but
//! datasets stepped over) is accepted by the encoder, and decoding what it writes gives the same record (units and
//! nodes exactly; functions exactly but for record 7's numbers, which the encoder writes with 6 digits) and
//! writes the same bytes again.

#![no_main]

#[path = "common/chunks.rs"]
mod chunks;

use libfuzzer_sys::fuzz_target;
use metaplate_uff::{ByteOrder, Format, FunctionType, Limits, Precision, UffDecoder, UffEncoder, UffRecord};

/// What `make()`'s decoder gives from `payload`, fed at `cuts` and whole, asserted equal; its buffer bounded.
fn decode(
    make: impl Fn() -> UffDecoder,
    payload: &[u8],
    cuts: &[usize],
) -> Vec<Result<UffRecord, metaplate_uff::DecodeError>> {
    let max_line = Limits::default().max_line_bytes;
    let mut decoder = make();
    let mut chunked = chunks::feed(
        &mut decoder,
        payload,
        cuts,
        |d, bytes| d.push(bytes),
        |d| d.records().collect::<Vec<_>>(),
        |d| d.buffered_len() <= max_line + 1,
    );
    decoder.finish();
    chunked.extend(decoder.records());
    let mut whole = make();
    whole.push(payload);
    whole.finish();
    let at_once: Vec<_> = whole.records().collect();
    // Compared as text: a non-finite value reported in an error is NaN, not equal to itself.
    assert_eq!(format!("{chunked:?}"), format!("{at_once:?}"));
    at_once
}

fuzz_target!(|data: &[u8]| {
    let Some((payload, cuts)) = chunks::split(data) else { return };
    let at_once = decode(UffDecoder::new, payload, &cuts);
    // As an import reads: responses only (CR, CRLF and LF line ends, padding and Latin-1 reach both decoders).
    let responses = [FunctionType::TimeResponse, FunctionType::FrequencyResponse];
    let filtered_at_once = decode(|| UffDecoder::new().only_functions(&responses), payload, &cuts);
    for record in filtered_at_once.iter().flatten() {
        match record {
            UffRecord::Function(f) => assert!(responses.contains(&f.header.function_type), "{f:?}"),
            UffRecord::Other(other) if other.function_type.is_some() => assert_eq!(other.dataset_number, 58),
            _ => {}
        }
    }

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

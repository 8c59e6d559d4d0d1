//! Malformed input: every defect gives a typed error naming the record and line, the decoder goes on with the
//! next dataset, never panics, and results do not depend on how the input is split. And the encoder's refusals.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{complex_values, decode, decode_in_chunks, function, nodes, real_values, units};
use metaplate_uff::{
    ByteOrder, Complex64, DecodeError, EncodeError, Format, FunctionType, Limits, Location, Malformed, Ordinate,
    OrdinateRef, Precision, UffDecoder, UffEncoder, UffRecord,
};
use proptest::prelude::*;

const LE: Format = Format::Binary { byte_order: ByteOrder::LittleEndian };

/// Units, nodes, then a function in `format` and `precision` (`complex`: a frequency response), then nodes again
/// (so that recovery after a bad function shows).
fn file(format: Format, precision: Precision, complex: bool) -> Vec<u8> {
    let encoder = UffEncoder::new(format, precision);
    let function = if complex {
        function(FunctionType::FrequencyResponse, Ordinate::Complex(complex_values()))
    } else {
        function(FunctionType::TimeResponse, Ordinate::Real(real_values()))
    };
    let mut out = Vec::new();
    for record in [
        UffRecord::Units(units()),
        UffRecord::Nodes(nodes()),
        UffRecord::Function(Box::new(function)),
        UffRecord::Nodes(nodes()),
    ] {
        encoder.encode(&record, &mut out).unwrap();
    }
    out
}

fn replace(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let at = bytes.windows(from.len()).position(|w| w == from.as_bytes()).unwrap_or_else(|| panic!("no {from:?}"));
    [&bytes[..at], to.as_bytes(), &bytes[at + from.len()..]].concat()
}

/// The one error among the results, after checking that the same results come whatever the split.
fn the_error(bytes: &[u8]) -> (DecodeError, Vec<Result<UffRecord, DecodeError>>) {
    let whole = decode(bytes);
    for chunk in [1, 3, 64] {
        // Compared as text: NaN is not equal to itself.
        let split = decode_in_chunks(bytes, chunk);
        assert_eq!(format!("{split:?}"), format!("{whole:?}"), "split into {chunk}-byte pieces");
    }
    let errors: Vec<DecodeError> = whole.iter().filter_map(|r| r.clone().err()).collect();
    assert_eq!(errors.len(), 1, "{whole:#?}");
    (errors[0].clone(), whole)
}

fn at(record: u64, dataset_number: u32, line: u64) -> Location {
    Location { record, dataset_number: Some(dataset_number), line }
}

/// The good records around the bad function: units, nodes, and the nodes after it.
fn assert_recovered(results: &[Result<UffRecord, DecodeError>]) {
    let good: Vec<&UffRecord> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    assert_eq!(good, [&UffRecord::Units(units()), &UffRecord::Nodes(nodes()), &UffRecord::Nodes(nodes())]);
}

// Line numbers in `file`: units 1-6, nodes 7-15, the function's delimiter 16, identifier 17, records 1-11 on
// lines 18-28, values from 29.

#[test]
fn a_file_cut_short_is_truncated_after_the_good_records() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let text = String::from_utf8(bytes.clone()).unwrap();
    let record7 = text.find("         4         7").unwrap();
    let (error, results) = the_error(&bytes[..record7 + 5]);
    assert_eq!(error.kind, Malformed::Truncated { expected: "the header records of dataset 58" });
    assert_eq!(error.location, at(3, 58, 24));
    assert_eq!(results.iter().filter(|r| r.is_ok()).count(), 2);
    // In binary data.
    let bytes = file(LE, Precision::Single, true);
    let cut = bytes.len() - nodes_len() - 20;
    let (error, _) = the_error(&bytes[..cut]);
    assert_eq!(error.kind, Malformed::Truncated { expected: "the binary bytes the identifier line states" });
    assert_eq!(error.location, at(3, 58, 28));
}

#[test]
fn a_wrong_delimiter_is_reported_with_its_line() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    // The function's opening delimiter.
    let bad = replace(&bytes, "    -1\n    -1\n    58 ", "    -1\n    -2\n    58 ");
    let (error, results) = the_error(&bad);
    assert_eq!(error.location, Location { record: 2, dataset_number: Some(2411), line: 16 });
    assert!(matches!(
        error.kind,
        Malformed::Unexpected { expected: "the delimiter `    -1` that opens a dataset", .. }
    ));
    assert_eq!(results.iter().filter(|r| r.is_ok()).count(), 3, "the datasets around it are read");
    // The function's closing delimiter.
    let bad = replace(&bytes, "1.00000000000e-30\n    -1\n", "1.00000000000e-30\n    -9\n");
    let (error, results) = the_error(&bad);
    assert_eq!(error.location, at(3, 58, 31));
    assert!(matches!(
        error.kind,
        Malformed::Unexpected { expected: "the delimiter `    -1` that closes the dataset", .. }
    ));
    assert_recovered(&results);
}

#[test]
fn counts_that_disagree_with_the_values_are_reported() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let (error, results) = the_error(&replace(&bytes, "         4         7", "         4         9"));
    assert_eq!(error.kind, Malformed::TooFewValues { expected: 9, found: 7 });
    assert_eq!(error.location, at(3, 58, 31));
    assert_recovered(&results);
    let (error, results) = the_error(&replace(&bytes, "         4         7", "         4         5"));
    assert_eq!(error.kind, Malformed::TooManyValues { expected: 5 });
    assert_eq!(error.location, at(3, 58, 30));
    assert_recovered(&results);
    // More values than the limit: refused before any is read or allocated.
    let (error, _) = the_error(&replace(&bytes, "         4         7", "         49999999999"));
    assert_eq!(error.kind, Malformed::TooLarge { what: "values in dataset 58", count: 9_999_999_999, max: 1 << 24 });
}

#[test]
fn a_58b_byte_count_too_small_or_too_large_is_reported_and_the_data_skipped() {
    // Single-precision complex: 5 values × 2 × 4 bytes = 40.
    let bytes = file(LE, Precision::Single, true);
    let header = "    58b     1     2          11          40     0";
    for stated in [36u64, 44, 80] {
        let bad = replace(&bytes, header, &format!("    58b     1     2          11{stated:>12}     0"));
        let (error, results) = the_error(&bad);
        assert_eq!(error.kind, Malformed::ByteCount { stated, expected: 40 }, "stated {stated}");
        assert_eq!(error.location, at(3, 58, 28));
        assert_recovered(&results);
    }
    // pyuff's count for complex values (the real parts only) is accepted.
    let pyuff = replace(&bytes, header, "    58b     1     2          11          20     0");
    assert!(decode(&pyuff).iter().all(Result::is_ok));
}

#[test]
fn a_line_end_between_binary_data_and_the_delimiter_is_accepted_and_crlf_too() {
    let bytes = file(Format::Binary { byte_order: ByteOrder::BigEndian }, Precision::Double, false);
    let tail = bytes.len() - nodes_len() - "    -1\n".len();
    let with_line_end = [&bytes[..tail], b"\r\n", &bytes[tail..]].concat();
    let results = decode(&with_line_end);
    assert!(results.iter().all(Result::is_ok), "{results:?}");
    assert_eq!(results, decode(&bytes));
    let ascii = file(Format::Ascii, Precision::Single, true);
    let crlf = String::from_utf8(ascii.clone()).unwrap().replace('\n', "\r\n");
    assert_eq!(decode(crlf.as_bytes()), decode(&ascii));
    // No line end after the last delimiter.
    assert_eq!(decode(&ascii[..ascii.len() - 1]), decode(&ascii));
}

fn nodes_len() -> usize {
    let mut out = Vec::new();
    UffEncoder::new(Format::Ascii, Precision::Double).encode(&UffRecord::Nodes(nodes()), &mut out).unwrap();
    out.len()
}

#[test]
fn an_overlong_line_is_reported_once_with_its_number() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let long = format!("{}\n", "x".repeat(5000));
    let bad = replace(&bytes, "NONE    ", &long);
    let (error, results) = the_error(&bad);
    assert_eq!(error.kind, Malformed::LineTooLong { max_bytes: 1024 });
    assert_eq!(error.location, at(3, 58, 19));
    assert_recovered(&results);
    // Between datasets, without a line end before the input ends.
    let mut bad = bytes.clone();
    bad.extend(std::iter::repeat_n(b'x', 3000));
    let (error, _) = the_error(&bad);
    assert_eq!(error.kind, Malformed::LineTooLong { max_bytes: 1024 });
}

#[test]
fn non_finite_values_are_reported() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let (error, results) = the_error(&replace(&bytes, "  -2.25000000000e-07", "                 NaN"));
    assert_eq!(error.kind.to_string(), "value 2 is not finite (NaN)");
    assert_eq!(error.location, at(3, 58, 29));
    assert_recovered(&results);
    let bytes = file(LE, Precision::Double, false);
    let at_value = bytes.windows(8).position(|w| w == 1.5e-3f64.to_le_bytes()).unwrap();
    let mut bad = bytes.clone();
    bad[at_value..at_value + 8].copy_from_slice(&f64::INFINITY.to_le_bytes());
    let (error, results) = the_error(&bad);
    assert_eq!(error.kind, Malformed::NonFinite { index: 1, value: f64::INFINITY });
    assert_recovered(&results);
}

#[test]
fn bad_fields_name_their_columns() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let (error, results) = the_error(&replace(&bytes, "  0.00000e+00  2.08333e-05", "  0.00000e+00  2.08333x-05"));
    assert_eq!(error.location, at(3, 58, 24));
    assert_eq!(
        error.to_string(),
        "record 3 (dataset 58), line 24: abscissa increment (columns 44-56, E13.5, finite): found \"  2.08333x-05\""
    );
    assert_recovered(&results);
    let (error, _) = the_error(&replace(&bytes, "   3.14159265359e+00", "   3.14159265359e+0!"));
    assert_eq!(error.location, at(3, 58, 29));
    assert!(matches!(error.kind, Malformed::Field { field: "data value", first_column: 61, last_column: 80, .. }));
    let (error, _) = the_error(&replace(
        &bytes,
        "         2         0         0         0\n",
        "         x         0         0         0\n",
    ));
    assert!(matches!(error.kind, Malformed::Field { field: "node label", first_column: 1, last_column: 10, .. }));
    assert_eq!(error.location, Location { record: 2, dataset_number: Some(2411), line: 11 });
}

#[test]
fn unsupported_variants_are_named() {
    let bytes = file(Format::Ascii, Precision::Double, false);
    let (error, results) =
        the_error(&replace(&bytes, "         4         7         1", "         4         7         0"));
    assert_eq!(
        error.kind,
        Malformed::Unsupported {
            what: "uneven abscissa spacing (record 7, columns 21-30: 0); an even abscissa (1) is read".to_owned()
        }
    );
    assert_eq!(error.location, at(3, 58, 24));
    assert_recovered(&results);
    let bytes = file(LE, Precision::Double, false);
    let (error, results) = the_error(&replace(&bytes, "    58b     1     2", "    58b     1     3"));
    assert!(matches!(error.kind, Malformed::Unsupported { .. }), "{error}");
    assert_eq!(error.location, at(3, 58, 17));
    assert_recovered(&results);
}

#[test]
fn other_datasets_are_stepped_over() {
    let mut bytes = b"    -1\n  2412\nelement\n    -1\n".to_vec();
    // A binary dataset of another number, skipped by its byte count although its bytes hold line ends and `-1`.
    bytes.extend_from_slice(
        b"    -1\n  2414b     1     2           1           9     0     0           0           0\nhead\n",
    );
    bytes.extend_from_slice(b"\n    -1\n\n");
    bytes.extend_from_slice(b"    -1\n");
    bytes.extend(file(Format::Ascii, Precision::Single, false));
    let results = decode(&bytes);
    assert_eq!(decode_in_chunks(&bytes, 1), results);
    let others: Vec<(u32, bool, u64)> = results
        .iter()
        .filter_map(|r| match r {
            Ok(UffRecord::Other(other)) => Some((other.dataset_number, other.binary, other.line)),
            _ => None,
        })
        .collect();
    assert_eq!(others, [(2412, false, 1), (2414, true, 5)]);
    assert_eq!(results.iter().filter(|r| r.is_ok()).count(), 6, "{results:?}");
}

#[test]
fn the_decoder_holds_one_line_beyond_the_last_push() {
    let limits = Limits { max_line_bytes: 100, ..Limits::default() };
    let mut decoder = UffDecoder::with_limits(limits);
    for _ in 0..1000 {
        decoder.push(&[b'x'; 37]);
        while decoder.poll().is_some() {}
        assert!(decoder.buffered_len() <= 100 + 37 + 1, "{}", decoder.buffered_len());
    }
}

#[test]
fn the_encoder_refuses_what_it_cannot_write_and_appends_nothing() {
    let encoder = UffEncoder::new(Format::Ascii, Precision::Single);
    let mut out = b"kept".to_vec();
    let base = function(FunctionType::TimeResponse, Ordinate::Real(vec![1.0, 2.0]));
    let refuse = |values: OrdinateRef<'_>, header: &metaplate_uff::FunctionHeader, out: &mut Vec<u8>| {
        encoder.encode_function(header, values, out).unwrap_err()
    };
    let h = &base.header;
    assert!(matches!(refuse(OrdinateRef::Real(&[1.0, f64::NAN]), h, &mut out), EncodeError::Value { index: 1, .. }));
    assert!(matches!(refuse(OrdinateRef::Real(&[1e39]), h, &mut out), EncodeError::Value { index: 0, .. }));
    let complex = [Complex64::new(0.0, f64::INFINITY)];
    assert!(matches!(refuse(OrdinateRef::Complex(&complex), h, &mut out), EncodeError::Value { index: 1, .. }));
    assert_eq!(refuse(OrdinateRef::Real(&[]), h, &mut out), EncodeError::Empty);
    let mut header = base.header.clone();
    header.abscissa_step = 0.0;
    assert!(matches!(refuse(OrdinateRef::Real(&[1.0]), &header, &mut out), EncodeError::Header { .. }));
    let mut header = base.header.clone();
    header.id_lines[2] = "€ is not Latin-1".to_owned();
    assert!(matches!(refuse(OrdinateRef::Real(&[1.0]), &header, &mut out), EncodeError::Text { field: "ID line", .. }));
    let mut header = base.header.clone();
    header.response.entity = "ELEVENCHARS".to_owned();
    assert!(matches!(refuse(OrdinateRef::Real(&[1.0]), &header, &mut out), EncodeError::Text { max_len: 10, .. }));
    let mut header = base.header.clone();
    header.reference.direction = 7;
    assert!(matches!(refuse(OrdinateRef::Real(&[1.0]), &header, &mut out), EncodeError::Integer { .. }));
    // A line of text reading `-1` would close the dataset where it stands.
    let mut header = base.header.clone();
    header.id_lines[4] = "  -1".to_owned();
    assert_eq!(refuse(OrdinateRef::Real(&[1.0]), &header, &mut out), EncodeError::Delimiter { field: "ID line" });
    let stamp = || ["NONE".to_owned(), "NONE".to_owned()];
    let header151 = metaplate_uff::Header151 {
        model_name: "-1".into(),
        description: String::new(),
        db_program: String::new(),
        db_created: stamp(),
        db_saved: stamp(),
        program: String::new(),
        file_written: stamp(),
    };
    let refused = encoder.encode(&metaplate_uff::UffRecord::Header(Box::new(header151)), &mut out).unwrap_err();
    assert_eq!(refused, EncodeError::Delimiter { field: "model file name" });
    assert_eq!(out, b"kept");
    // Double precision takes what single cannot.
    UffEncoder::new(Format::Ascii, Precision::Double).encode_function(h, OrdinateRef::Real(&[1e39]), &mut out).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Hostile bytes: no panic, the same results at any split, and corrupting a good file costs at most the
    /// datasets the corruption touches.
    #[test]
    fn hostile_bytes_never_panic_and_do_not_depend_on_the_split(
        seed_format in 0usize..4,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
        cut in any::<prop::sample::Index>(),
        chunk in 1usize..100,
    ) {
        let formats = [Format::Ascii, LE, Format::Binary { byte_order: ByteOrder::BigEndian }, Format::Ascii];
        let mut bytes = file(formats[seed_format], if seed_format == 3 { Precision::Single } else { Precision::Double }, seed_format % 2 == 1);
        for (index, byte) in edits {
            let i = index.index(bytes.len());
            bytes[i] = byte;
        }
        bytes.truncate(cut.index(bytes.len() + 1));
        let whole = decode(&bytes);
        prop_assert_eq!(decode_in_chunks(&bytes, chunk), whole);
    }

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000), chunk in 1usize..50) {
        prop_assert_eq!(decode_in_chunks(&bytes, chunk), decode(&bytes));
    }
}

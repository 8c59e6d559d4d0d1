//! What other writers write, read as they write it: each departure from the description below was seen in a
//! public file (the corpus of `metaplate-interchange`, `crates/interchange/tests/corpus/README.md`, lists them),
//! and each is read the same whatever the split of the input.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{decode, decode_in_chunks, function, nodes, real_values, units};
use metaplate_uff::{
    ByteOrder, DecodeError, Format, FunctionType, Malformed, Ordinate, Precision, UffDecoder, UffEncoder, UffRecord,
};

/// Decodes `bytes` whole and at several splits, asserts the splits agree, and returns the results.
fn read(bytes: &[u8]) -> Vec<Result<UffRecord, DecodeError>> {
    let whole = decode(bytes);
    for chunk in [1, 2, 7, 64] {
        assert_eq!(format!("{:?}", decode_in_chunks(bytes, chunk)), format!("{whole:?}"), "{chunk}-byte pieces");
    }
    whole
}

fn only_function(results: &[Result<UffRecord, DecodeError>]) -> &metaplate_uff::Function58 {
    let functions: Vec<_> = results
        .iter()
        .map(|r| r.as_ref().unwrap_or_else(|e| panic!("{e}")))
        .filter_map(|r| if let UffRecord::Function(f) = r { Some(f) } else { None })
        .collect();
    assert_eq!(functions.len(), 1, "{results:?}");
    functions[0]
}

/// A dataset 58 as catman and LMS Test.Lab write it: record 6 with reference node `reference`, six values
/// announced, the values in `values_lines`.
fn ascii58(reference: &str, values_lines: &str) -> String {
    format!(
        "    -1\n    58\nx : m/s\u{b2}\nUFF58 file created by HBM catman\n30-Apr-20 19:12:52\nNONE\nNONE\n\
         \x20   1         0    0         0 NONE               1   3 NONE      {reference:>10}   3\n\
         \x20        2         6         1 0.00000E+000 5.00000E-005 0.00000E+000\n\
         \x20       17    0    0    0 Time                 s\n\
         \x20        1    0    0    0 1x                   m/s\u{b2}\n\
         \x20        0    0    0    0 NONE                 NONE\n\
         \x20        0    0    0    0 NONE                 NONE\n\
         {values_lines}    -1\n"
    )
}

#[test]
fn headers_are_read_as_their_writers_filled_them() {
    // LMS Test.Lab (TestLab_161_164_18_15_82.uff of the corpus): the identifier line padded to 80 columns, dates
    // and times in one field, a trailing blank.
    let lms = "    -1\n   151                                                                          \nAME_Test\nNONE\n\
               LMS Test.Lab Rev project-15A\n11-Oct-17 09:34:21\n11-Oct-17 09:34:21\nLMS Test.Lab Rev project-15A\n\
               17-Oct-17 13:50:13 \n    -1\n";
    let results = read(lms.as_bytes());
    let Ok(UffRecord::Header(header)) = &results[0] else { panic!("{results:?}") };
    assert_eq!((header.model_name.as_str(), header.description.as_str()), ("AME_Test", "NONE"));
    assert_eq!(header.db_program, "LMS Test.Lab Rev project-15A");
    assert_eq!(header.db_created, ["11-Oct-17".to_owned(), "09:34:21".to_owned()]);
    assert_eq!(header.file_written, ["17-Oct-17".to_owned(), "13:50:13".to_owned()]);
    // A VKI writer (heat_engine_housing.uff): blank names, no dates but a version on record 4, the program's name
    // with a date, record 7 shifted by a column; and a header of one record, one of nine, and one with a line past
    // 80 columns: read, never refused.
    let vki = "    -1\n   151\n \nNONE\nNONE\n                             0\n                    \n\
               VKI 453 24-Feb-23 22:10:15\n 24-Feb-23  22:10:15  453\n    -1\n";
    let long = format!("    -1\n   151\n{}\n    -1\n", "x".repeat(300));
    let nine = format!("    -1\n   151\n{}    -1\n", "line\n".repeat(9));
    for text in [vki, "    -1\n   151\nonly a name\n    -1\n", &long, &nine] {
        let results = read(text.as_bytes());
        let [Ok(UffRecord::Header(header))] = &results[..] else { panic!("{text}: {results:?}") };
        // What was read is what the encoder writes, and reads back the same.
        let mut out = Vec::new();
        UffEncoder::new(Format::Ascii, Precision::Single).encode(&results[0].clone().unwrap(), &mut out).unwrap();
        assert_eq!(read(&out), results, "{text}");
        assert!(header.model_name.len() <= 80);
    }
    let results = read(vki.as_bytes());
    let Ok(UffRecord::Header(header)) = &results[0] else { panic!("{results:?}") };
    assert_eq!((header.model_name.as_str(), header.db_program.as_str()), ("NONE", "NONE"));
    assert_eq!(header.db_created, ["NONE".to_owned(), "NONE".to_owned()]);
    assert_eq!(header.program, "VKI 453 24-Feb-23 22:10:15");
    assert_eq!(header.file_written, ["24-Feb-23".to_owned(), "22:10:15".to_owned()]);
    let results = read(b"    -1\n   151\nonly a name\n    -1\n");
    let Ok(UffRecord::Header(header)) = &results[0] else { panic!("{results:?}") };
    assert_eq!((header.model_name.as_str(), header.program.as_str()), ("only a name", "NONE"), "records missing");
    let results = read(long.as_bytes());
    let Ok(UffRecord::Header(header)) = &results[0] else { panic!("{results:?}") };
    assert_eq!(header.model_name, "x".repeat(80), "cut to record 1's 80 columns");
}

#[test]
fn lms_units_without_temperature_mode_are_read() {
    let text = "    -1\n   164\n         9USER_DEFINED\n  1.00000000000000000D+00  1.00000000000000000D+00  \
                1.00000000000000000D+00\n -2.73149999999999960D+02\n    -1\n";
    let results = read(text.as_bytes());
    let Ok(UffRecord::Units(units)) = &results[0] else { panic!("{results:?}") };
    assert_eq!((units.units_code, units.description.as_str(), units.temperature_mode), (9, "USER_DEFINED", None));
    assert_eq!(units.temperature_offset, -273.15);
    // And written back without the mode, read again the same.
    let mut out = Vec::new();
    UffEncoder::new(Format::Ascii, Precision::Double).encode(&results[0].clone().unwrap(), &mut out).unwrap();
    assert_eq!(read(&out), results);
}

#[test]
fn zero_padding_past_the_count_and_negative_or_zero_reference_nodes_are_read() {
    // Zeros past the count on the line that completes it are padding (catman, DT9837 software).
    let on_last_line =
        ascii58("-1", " 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00\n 5.00000E+00 6.00000E+00 0.00000E+00\n");
    let results = read(on_last_line.as_bytes());
    let f = only_function(&results);
    assert_eq!(f.ordinate, Ordinate::Real(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]));
    assert_eq!((f.header.reference.node, f.header.response.node), (-1, 1));
    // A value past the count that is not zero is still too many.
    let extra =
        ascii58("0", " 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00\n 5.00000E+00 6.00000E+00 7.00000E+00\n");
    let results = read(extra.as_bytes());
    assert!(
        matches!(results[0], Err(DecodeError { kind: Malformed::TooManyValues { expected: 6 }, .. })),
        "{results:?}"
    );
}

#[test]
fn cr_lf_and_crlf_line_ends_read_alike() {
    let text = ascii58("0", " 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00 5.00000E+00 6.00000E+00\n");
    let lf = read(text.as_bytes());
    only_function(&lf);
    assert_eq!(read(text.replace('\n', "\r").as_bytes()), lf, "CR");
    assert_eq!(read(text.replace('\n', "\r\n").as_bytes()), lf, "CRLF");
    // A CR-only 58b whose binary data begins with a line feed byte: the byte is data, not part of a line end.
    let encoder = UffEncoder::new(Format::Binary { byte_order: ByteOrder::LittleEndian }, Precision::Single);
    let f =
        function(FunctionType::TimeResponse, Ordinate::Real(vec![f64::from(f32::from_le_bytes([b'\n', 0, 0, 0x3f]))]));
    let mut bytes = Vec::new();
    encoder.encode(&UffRecord::Function(Box::new(f.clone())), &mut bytes).unwrap();
    let data_at = bytes.len() - 4 - "    -1\n".len();
    let (head, tail) = bytes.split_at(data_at);
    let cr_head: Vec<u8> = head.iter().map(|&b| if b == b'\n' { b'\r' } else { b }).collect();
    let cr_tail = [&tail[..4], b"\r    -1\r"].concat();
    let results = read(&[cr_head, cr_tail].concat());
    assert_eq!(only_function(&results).ordinate, f.ordinate);
}

#[test]
fn numbers_with_no_space_between_them_and_other_widths_are_read() {
    // 13 columns filled by 7 significant digits: no blank between negative numbers (pyuff reads these by columns
    // too); and space-separated numbers of other widths.
    let run_together = ascii58("0", "-1.000000E+00-2.000000E+00-3.000000E+00-4.000000E+00-5.000000E+00-6.000000E+00\n");
    let results = read(run_together.as_bytes());
    assert_eq!(only_function(&results).ordinate, Ordinate::Real(vec![-1.0, -2.0, -3.0, -4.0, -5.0, -6.0]));
    let words = ascii58("0", "1.0 2.5e0 3\n4.000000000E+00   5.0D+00 6.\n");
    let results = read(words.as_bytes());
    assert_eq!(only_function(&results).ordinate, Ordinate::Real(vec![1.0, 2.5, 3.0, 4.0, 5.0, 6.0]));
    // What is neither is named by its columns.
    let bad = ascii58("0", " 1.00000E+00 2.0000xE+00\n");
    let results = read(bad.as_bytes());
    let Err(DecodeError { kind: Malformed::Field { field: "data value", first_column: 14, .. }, .. }) = &results[0]
    else {
        panic!("{results:?}")
    };
}

#[test]
fn latin1_text_is_read_one_character_a_byte_and_written_back_the_same() {
    let text = ascii58("0", " 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00 5.00000E+00 6.00000E+00\n");
    // The file's `²` in Latin-1 (one byte 0xb2), as the I-DEAS era writes it.
    let latin1: Vec<u8> = text.chars().map(|c| u8::try_from(u32::from(c)).unwrap()).collect();
    let results = read(&latin1);
    let f = only_function(&results);
    assert_eq!(f.header.ordinate.units_label, "m/s\u{b2}");
    assert_eq!(f.header.id_lines[0], "x : m/s\u{b2}");
    let mut out = Vec::new();
    UffEncoder::new(Format::Ascii, Precision::Single).encode(&results[0].clone().unwrap(), &mut out).unwrap();
    assert!(out.windows(4).any(|w| w == b"m/s\xb2"), "written back in Latin-1");
    assert_eq!(read(&out), results);
    // UTF-8 (catman) reads as its bytes: `m/sÂ²`, which a user of the label turns back into UTF-8.
    let results = read(text.as_bytes());
    assert_eq!(only_function(&results).header.ordinate.units_label, "m/s\u{c2}\u{b2}");
}

#[test]
fn functions_of_other_types_are_stepped_over_unchecked_when_asked() {
    // A PSD as VibControl writes it (type 9, uneven abscissa: the decoder does not read those) around a response.
    let psd = "    -1\n    58\nPower Spectral Density (PSD)\nVibControl Random\n13-Apr-23 09:57:51\nChannel 1\nNONE\n\
               \x20   9         0    0         0 Pilot 1            0   0 NONE               0   0\n\
               \x20        5         2         0 0.000000E+00 0.000000E+00 0.000000E+00\n\
               \x20        0    0    0    0 Hz                   Hz\n\
               \x20        0    0    0    0 g\u{b2}/Hz                g\u{b2}/Hz\n\
               \x20        0    0    0    0 NONE                 NONE\n\
               \x20        0    0    0    0 NONE                 NONE\n\
               \x200.000000E+00 0.000000E+00 0.000000E+00 1.000000E+00 1.255863E-06 0.000000E+00\n    -1\n";
    let response = ascii58("0", " 1.00000E+00 2.00000E+00 3.00000E+00 4.00000E+00 5.00000E+00 6.00000E+00\n");
    let mut bytes = psd.as_bytes().to_vec();
    bytes.extend_from_slice(response.as_bytes());
    // A 58b coherence (type 6) too, stepped over by its byte count.
    let encoder = UffEncoder::new(Format::Binary { byte_order: ByteOrder::BigEndian }, Precision::Double);
    let mut coherence = function(FunctionType::Other(6), Ordinate::Real(real_values()));
    coherence.header.reference.node = 0;
    encoder.encode(&UffRecord::Function(Box::new(coherence)), &mut bytes).unwrap();
    encoder.encode(&UffRecord::Nodes(nodes()), &mut bytes).unwrap();

    // Read whole, the PSD's uneven abscissa is an error.
    assert!(decode(&bytes).iter().any(Result::is_err));
    for chunk in [1, 5, 4096] {
        let mut decoder =
            UffDecoder::new().only_functions(&[FunctionType::TimeResponse, FunctionType::FrequencyResponse]);
        let mut results = Vec::new();
        for piece in bytes.chunks(chunk) {
            decoder.push(piece);
            results.extend(decoder.records());
        }
        decoder.finish();
        results.extend(decoder.records());
        let results: Vec<UffRecord> = results.into_iter().map(|r| r.unwrap_or_else(|e| panic!("{e}"))).collect();
        let [UffRecord::Other(psd), UffRecord::Function(f), UffRecord::Other(coherence), UffRecord::Nodes(n)] =
            &results[..]
        else {
            panic!("{results:?}")
        };
        assert_eq!((psd.dataset_number, psd.function_type, psd.binary, psd.line), (58, Some(9), false, 1));
        assert_eq!((coherence.function_type, coherence.binary), (Some(6), true));
        assert_eq!(f.ordinate.len(), 6);
        assert_eq!(n, &nodes());
    }
    let _ = units();
}

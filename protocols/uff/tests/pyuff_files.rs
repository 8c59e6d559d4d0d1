//! Byte-exact examples: files pyuff 2.5.8 wrote (`tests/fixtures/make_fixtures.py`) against the same records
//! encoded here, and pyuff's files decoded here.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::{complex_values, decode, decode_in_chunks, function, nodes, real_values, units};
use metaplate_uff::{ByteOrder, Format, FunctionType, Ordinate, Precision, UffEncoder, UffRecord};

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// The fixture `name`, encoded here: units, nodes, then the function in `format` and `precision`.
fn encoded(format: Format, precision: Precision, function_type: FunctionType, ordinate: Ordinate) -> Vec<u8> {
    let encoder = UffEncoder::new(format, precision);
    let mut out = Vec::new();
    encoder.encode(&UffRecord::Units(units()), &mut out).unwrap();
    encoder.encode(&UffRecord::Nodes(nodes()), &mut out).unwrap();
    encoder.encode(&UffRecord::Function(Box::new(function(function_type, ordinate))), &mut out).unwrap();
    out
}

fn assert_same_text(ours: &[u8], theirs: &[u8]) {
    if ours != theirs {
        panic!("ours:\n{}\npyuff's:\n{}", String::from_utf8_lossy(ours), String::from_utf8_lossy(theirs));
    }
}

const LE: Format = Format::Binary { byte_order: ByteOrder::LittleEndian };

fn single_values() -> Vec<f64> {
    real_values()[..6].iter().map(|v| v * 1e-20).collect()
}

#[test]
fn a_header_is_pyuffs_byte_for_byte() {
    // pyuff 2.5.8's `write_sets` of this dataset 151 (versions and file type 0, its defaults).
    let pyuff = "    -1\n   151                                                                          \n\
                 scan                                                                            \n\
                 m/s per full-scale drive, through the calibration's inverse filters             \n\
                 metaplate cal=abababababababababababababababababababababababababababababababab  \n\
                 28-Nov-26 06:30:00           0         0         0\n\
                 28-Nov-26 06:31:00  \n\
                 metaplate 0.9.0                                                                 \n\
                 29-Nov-26 07:00:00  \n    -1\n";
    let stamp = |date: &str, time: &str| [date.to_owned(), time.to_owned()];
    let header = metaplate_uff::Header151 {
        model_name: "scan".into(),
        description: "m/s per full-scale drive, through the calibration's inverse filters".into(),
        db_program: format!("metaplate cal={}", "ab".repeat(32)),
        db_created: stamp("28-Nov-26", "06:30:00"),
        db_saved: stamp("28-Nov-26", "06:31:00"),
        program: "metaplate 0.9.0".into(),
        file_written: stamp("29-Nov-26", "07:00:00"),
    };
    let mut ours = Vec::new();
    UffEncoder::new(Format::Ascii, Precision::Double)
        .encode(&UffRecord::Header(Box::new(header.clone())), &mut ours)
        .unwrap();
    assert_same_text(&ours, pyuff.as_bytes());
    assert_eq!(decode(pyuff.as_bytes()), vec![Ok(UffRecord::Header(Box::new(header)))]);
}

#[test]
fn ascii_files_are_pyuffs_byte_for_byte() {
    let cases = [
        ("time_real_double_ascii.uff", Precision::Double, FunctionType::TimeResponse, Ordinate::Real(real_values())),
        ("time_real_single_ascii.uff", Precision::Single, FunctionType::TimeResponse, Ordinate::Real(single_values())),
        (
            "frf_complex_double_ascii.uff",
            Precision::Double,
            FunctionType::FrequencyResponse,
            Ordinate::Complex(complex_values()),
        ),
        (
            "frf_complex_single_ascii.uff",
            Precision::Single,
            FunctionType::FrequencyResponse,
            Ordinate::Complex(complex_values()),
        ),
    ];
    for (name, precision, function_type, ordinate) in cases {
        assert_same_text(&encoded(Format::Ascii, precision, function_type, ordinate), &fixture(name));
    }
}

#[test]
fn a_real_binary_file_is_pyuffs_byte_for_byte() {
    let ours = encoded(LE, Precision::Double, FunctionType::TimeResponse, Ordinate::Real(real_values()));
    assert_eq!(ours, fixture("time_real_double_binary.uff"));
}

/// pyuff states the bytes of the real parts only for complex 58b (80 bytes follow; it says 40): everything
/// else is the same, and the decoder reads pyuff's file.
#[test]
fn a_complex_binary_file_differs_from_pyuffs_only_in_the_byte_count() {
    let ours = encoded(LE, Precision::Double, FunctionType::FrequencyResponse, Ordinate::Complex(complex_values()));
    let theirs = fixture("frf_complex_double_binary.uff");
    let ours_fixed = String::from_utf8_lossy(&ours).replace(
        "    58b     1     2          11          80     0",
        "    58b     1     2          11          40     0",
    );
    assert_eq!(ours_fixed.as_bytes(), String::from_utf8_lossy(&theirs).as_bytes());
    let records = decode(&theirs);
    let Ok(UffRecord::Function(read)) = &records[2] else { panic!("{records:?}") };
    assert_eq!(read.ordinate, Ordinate::Complex(complex_values()));
}

#[test]
fn pyuffs_files_decode_to_the_records_they_hold() {
    let single = |v: f64| format!("{v:.5e}").parse::<f64>().unwrap();
    let double = |v: f64| format!("{v:.11e}").parse::<f64>().unwrap();
    let cases: [(&str, FunctionType, Ordinate); 6] = [
        (
            "time_real_double_ascii.uff",
            FunctionType::TimeResponse,
            Ordinate::Real(real_values().into_iter().map(double).collect()),
        ),
        (
            "time_real_single_ascii.uff",
            FunctionType::TimeResponse,
            Ordinate::Real(single_values().into_iter().map(single).collect()),
        ),
        (
            "frf_complex_double_ascii.uff",
            FunctionType::FrequencyResponse,
            Ordinate::Complex(
                complex_values()
                    .into_iter()
                    .map(|c| metaplate_uff::Complex64::new(double(c.re), double(c.im)))
                    .collect(),
            ),
        ),
        (
            "frf_complex_single_ascii.uff",
            FunctionType::FrequencyResponse,
            Ordinate::Complex(
                complex_values()
                    .into_iter()
                    .map(|c| metaplate_uff::Complex64::new(single(c.re), single(c.im)))
                    .collect(),
            ),
        ),
        ("time_real_double_binary.uff", FunctionType::TimeResponse, Ordinate::Real(real_values())),
        ("frf_complex_double_binary.uff", FunctionType::FrequencyResponse, Ordinate::Complex(complex_values())),
    ];
    for (name, function_type, ordinate) in cases {
        let bytes = fixture(name);
        for chunk in [1, 7, 80, bytes.len()] {
            let records: Vec<UffRecord> = decode_in_chunks(&bytes, chunk).into_iter().map(|r| r.unwrap()).collect();
            assert_eq!(records.len(), 3, "{name}");
            assert_eq!(records[0], UffRecord::Units(units()), "{name}");
            assert_eq!(records[1], UffRecord::Nodes(nodes()), "{name}");
            let mut expected = function(function_type, ordinate.clone());
            // UffRecord 7 keeps 6 significant digits of the step.
            expected.header.abscissa_step = single(expected.header.abscissa_step);
            assert_eq!(records[2], UffRecord::Function(Box::new(expected)), "{name}, chunks of {chunk}");
        }
    }
}

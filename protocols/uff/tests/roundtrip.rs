//! Round trips through the encoder and decoder for every combination: ASCII 58 and binary 58b in both byte
//! orders, single and double precision, real and complex ordinates, function types 1 and 4; and datasets 164
//! and 2411. The bounds are the formats' (see the crate documentation):
//!
//! - ASCII single (`%13.5e`, 6 significant digits): relative error ≤ 5 × 10⁻⁶;
//! - ASCII double (`%20.11e`, 12 significant digits): relative error ≤ 5 × 10⁻¹² (plus half an `f64` ulp);
//! - binary single: the value rounded to `f32` (relative error ≤ 2⁻²⁴), exactly;
//! - binary double: exact;
//! - record 7 (abscissa start and step, `%13.5e`): relative error ≤ 5 × 10⁻⁶;
//! - 164 factors and 2411 coordinates (`%25.16e`, 17 digits): exact.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use common::decode_in_chunks;
use metaplate_uff::{
    AxisCharacteristics, ByteOrder, Complex64, Dof, Format, Function58, FunctionHeader, FunctionType, Header151, Node,
    Nodes2411, Ordinate, Precision, UffEncoder, UffRecord, Units164,
};
use proptest::prelude::*;

/// Finite values of every magnitude `precision` can hold (normal range), with zero and both signs.
fn value(precision: Precision) -> BoxedStrategy<f64> {
    let max_exponent = match precision {
        Precision::Single => 37,
        Precision::Double => 300,
    };
    prop_oneof![
        1 => Just(0.0),
        1 => Just(-0.0),
        12 => (1.0f64..10.0, -max_exponent..=max_exponent, any::<bool>())
            .prop_map(|(m, e, negative)| if negative { -m } else { m } * 10f64.powi(e)),
    ]
    .boxed()
}

fn text(max_len: usize) -> impl Strategy<Value = String> {
    // Printable Latin-1 (one byte a character in the file: `²`, `°`, `µ` as the I-DEAS era writes them) without
    // leading or trailing blanks, which reading trims; never `-1`, which a line of text cannot hold (it reads as the
    // closing delimiter: the encoder refuses it, `EncodeError::Delimiter`).
    prop::string::string_regex(&format!("[!-~¡-ÿ]([ -~\\x{{a0}}-ÿ]{{0,{}}}[!-~¡-ÿ])?", max_len - 2))
        .unwrap()
        .prop_filter("reads as the closing delimiter", |t| t != "-1")
}

fn axis() -> impl Strategy<Value = AxisCharacteristics> {
    (0u32..30, -3i32..4, -3i32..4, -1i32..2, text(20), text(20)).prop_map(
        |(data_type, length_exponent, force_exponent, temperature_exponent, label, units_label)| AxisCharacteristics {
            data_type,
            length_exponent,
            force_exponent,
            temperature_exponent,
            label,
            units_label,
        },
    )
}

fn dof() -> impl Strategy<Value = Dof> {
    // Any I10 label: writers use 0 and negative ones (LMS: reference node -1).
    (text(10), -999_999_999i64..=9_999_999_999, -6i8..=6).prop_map(|(entity, node, direction)| Dof {
        entity,
        node,
        direction,
    })
}

fn header() -> impl Strategy<Value = FunctionHeader> {
    (
        [text(80), text(80), text(80), text(80), text(80)],
        prop_oneof![Just(FunctionType::TimeResponse), Just(FunctionType::FrequencyResponse)],
        (any::<u32>(), 0u32..100_000, any::<u32>()),
        (dof(), dof()),
        (-1e3f64..1e3, 1e-9f64..1e3, -1e3f64..1e3),
        (axis(), axis(), axis(), axis()),
    )
        .prop_map(
            |(id_lines, function_type, (function_id, version, load_case), (response, reference), abscissa, axes)| {
                FunctionHeader {
                    id_lines,
                    function_type,
                    function_id,
                    version,
                    load_case,
                    response,
                    reference,
                    abscissa_start: abscissa.0,
                    abscissa_step: abscissa.1,
                    z_axis_value: abscissa.2,
                    abscissa: axes.0,
                    ordinate: axes.1,
                    denominator: axes.2,
                    z_axis: axes.3,
                }
            },
        )
}

const FORMATS: [Format; 3] = [
    Format::Ascii,
    Format::Binary { byte_order: ByteOrder::LittleEndian },
    Format::Binary { byte_order: ByteOrder::BigEndian },
];

/// A header, single- and double-precision values, a chunk size.
type Case = (FunctionHeader, Vec<(f64, f64)>, Vec<(f64, f64)>, usize);

/// A header, values for each precision (as complex pairs; the real case takes the real parts), and a chunk
/// size to split the encoded bytes at.
fn case() -> impl Strategy<Value = Case> {
    let pairs = |precision| prop::collection::vec((value(precision), value(precision)), 1..40);
    (header(), pairs(Precision::Single), pairs(Precision::Double), 1usize..200)
}

/// Whether `read` is `written` within the format's bound.
fn within(written: f64, read: f64, format: Format, precision: Precision) -> bool {
    match (format, precision) {
        (Format::Ascii, Precision::Single) => (read - written).abs() <= 5e-6 * written.abs() * (1.0 + 1e-9),
        (Format::Ascii, Precision::Double) => {
            (read - written).abs() <= 5e-12 * written.abs() * (1.0 + 1e-9) + f64::EPSILON * written.abs()
        }
        (Format::Binary { .. }, Precision::Single) => read.to_bits() == f64::from(written as f32).to_bits(),
        (Format::Binary { .. }, Precision::Double) => read.to_bits() == written.to_bits(),
    }
}

fn reals(ordinate: &Ordinate) -> Vec<f64> {
    match ordinate {
        Ordinate::Real(values) => values.clone(),
        Ordinate::Complex(values) => values.iter().flat_map(|v| [v.re, v.im]).collect(),
    }
}

fn round_trip(written: &Function58, format: Format, precision: Precision, chunk: usize) -> Result<(), TestCaseError> {
    let mut bytes = Vec::new();
    UffEncoder::new(format, precision).encode(&UffRecord::Function(Box::new(written.clone())), &mut bytes).unwrap();
    let mut records = decode_in_chunks(&bytes, chunk);
    prop_assert_eq!(records.len(), 1);
    let Ok(UffRecord::Function(read)) = records.remove(0) else { panic!("{records:?}") };
    let (w, r) = (&written.header, &read.header);
    prop_assert!(six_digits(w.abscissa_start, r.abscissa_start), "{} {}", w.abscissa_start, r.abscissa_start);
    prop_assert!(six_digits(w.abscissa_step, r.abscissa_step), "{} {}", w.abscissa_step, r.abscissa_step);
    prop_assert!(six_digits(w.z_axis_value, r.z_axis_value));
    let same_header = FunctionHeader {
        abscissa_start: w.abscissa_start,
        abscissa_step: w.abscissa_step,
        z_axis_value: w.z_axis_value,
        ..r.clone()
    };
    prop_assert_eq!(&same_header, w);
    prop_assert_eq!(matches!(read.ordinate, Ordinate::Complex(_)), matches!(written.ordinate, Ordinate::Complex(_)));
    let (w, r) = (reals(&written.ordinate), reals(&read.ordinate));
    prop_assert_eq!(w.len(), r.len());
    for (i, (&w, &r)) in w.iter().zip(&r).enumerate() {
        prop_assert!(within(w, r, format, precision), "value {i}: wrote {w:e}, read {r:e} ({format:?}, {precision:?})");
    }
    Ok(())
}

fn six_digits(written: f64, read: f64) -> bool {
    (read - written).abs() <= 5e-6 * written.abs() * (1.0 + 1e-9)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Every combination for each case: 3 formats × 2 precisions × 2 function types × real or complex.
    #[test]
    fn functions_round_trip_within_the_formats_precision((header, single, double, chunk) in case()) {
        for format in FORMATS {
            for (precision, pairs) in [(Precision::Single, &single), (Precision::Double, &double)] {
                for function_type in [FunctionType::TimeResponse, FunctionType::FrequencyResponse] {
                    for complex in [false, true] {
                        let ordinate = if complex {
                            Ordinate::Complex(pairs.iter().map(|&(re, im)| Complex64::new(re, im)).collect())
                        } else {
                            Ordinate::Real(pairs.iter().map(|&(re, _)| re).collect())
                        };
                        let header = FunctionHeader { function_type, ..header.clone() };
                        round_trip(&Function58 { header, ordinate }, format, precision, chunk)?;
                    }
                }
            }
        }
    }

    #[test]
    fn headers_round_trip_exactly(
        names in prop::array::uniform4(text(80)),
        stamps in prop::array::uniform6(text(10)),
        chunk in 1usize..300,
    ) {
        let [model_name, description, db_program, program] = names;
        let [a, b, c, d, e, f] = stamps;
        let written = UffRecord::Header(Box::new(Header151 {
            model_name,
            description,
            db_program,
            db_created: [a, b],
            db_saved: [c, d],
            program,
            file_written: [e, f],
        }));
        let mut bytes = Vec::new();
        UffEncoder::new(Format::Ascii, Precision::Single).encode(&written, &mut bytes).unwrap();
        let read: Vec<UffRecord> = decode_in_chunks(&bytes, chunk).into_iter().map(|r| r.unwrap()).collect();
        prop_assert_eq!(read, vec![written]);
    }

    #[test]
    fn units_and_nodes_round_trip_exactly(
        factors in prop::array::uniform4(any::<f64>().prop_filter("finite", |v| v.is_finite())),
        code in 1u32..10,
        temperature_mode in prop::option::of(1u32..3),
        description in text(20),
        positions in prop::collection::vec((any::<u32>(), prop::array::uniform3(any::<f64>().prop_filter("finite", |v| v.is_finite()))), 0..20),
        chunk in 1usize..300,
    ) {
        let units = Units164 {
            units_code: code,
            description,
            temperature_mode,
            length_per_m: factors[0],
            force_per_n: factors[1],
            temperature_per_k: factors[2],
            temperature_offset: factors[3],
        };
        let nodes = Nodes2411 {
            nodes: positions
                .into_iter()
                .map(|(label, position_m)| Node { label, export_coordinate_system: 1, displacement_coordinate_system: 2, color: 11, position_m })
                .collect(),
        };
        let written = vec![UffRecord::Units(units), UffRecord::Nodes(nodes)];
        let mut bytes = Vec::new();
        let encoder = UffEncoder::new(Format::Ascii, Precision::Double);
        for record in &written {
            encoder.encode(record, &mut bytes).unwrap();
        }
        let read: Vec<UffRecord> = decode_in_chunks(&bytes, chunk).into_iter().map(|r| r.unwrap()).collect();
        prop_assert_eq!(read, written);
    }
}

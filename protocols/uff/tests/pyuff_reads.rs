//! pyuff reads what this crate writes: every format combination in one file, checked value by value by
//! `tests/python/read_uff.py`. Needs a Python with pyuff: `$METAPLATE_PYTHON`, else the project's
//! `.venv/bin/python` that `scripts/install-deps.sh` makes. Run:
//! `cargo test -p metaplate-uff --test pyuff_reads -- --ignored`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common;

use std::fmt::Write as _;
use std::process::Command;

use common::{nodes, units};
use metaplate_uff::{
    ByteOrder, Complex64, Format, Function58, FunctionHeader, FunctionType, Ordinate, Precision, UffEncoder, UffRecord,
};

/// Deterministic values of every sign and a range of magnitudes within single precision.
fn values(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let unit = (state >> 11) as f64 / (1u64 << 53) as f64;
            let exponent = ((state >> 3) % 21) as i32 - 10;
            (unit - 0.5) * 10f64.powi(exponent)
        })
        .collect()
}

#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with pyuff: run by .ci/run"]
fn pyuff_reads_every_variant_we_write() {
    let dir = tempfile::tempdir().unwrap();
    let mut file = Vec::new();
    let plain = UffEncoder::new(Format::Ascii, Precision::Double);
    plain.encode(&UffRecord::Units(units()), &mut file).unwrap();
    plain.encode(&UffRecord::Nodes(nodes()), &mut file).unwrap();
    let mut functions = Vec::new();
    let formats = [
        (Format::Ascii, "ascii"),
        (Format::Binary { byte_order: ByteOrder::LittleEndian }, "binary"),
        (Format::Binary { byte_order: ByteOrder::BigEndian }, "binary"),
    ];
    let mut seed = 0;
    for (format, format_name) in formats {
        for (precision, precision_name) in [(Precision::Single, "single"), (Precision::Double, "double")] {
            for function_type in [FunctionType::TimeResponse, FunctionType::FrequencyResponse] {
                for complex in [false, true] {
                    seed += 1;
                    let n = 5 + seed as usize;
                    let re = values(n, seed);
                    let (ordinate, json_values) = if complex {
                        let im = values(n, seed + 1000);
                        let json: Vec<String> = re.iter().zip(&im).map(|(r, i)| format!("[{r:?},{i:?}]")).collect();
                        (Ordinate::Complex(re.iter().zip(&im).map(|(&r, &i)| Complex64::new(r, i)).collect()), json)
                    } else {
                        (Ordinate::Real(re.clone()), re.iter().map(|v| format!("{v:?}")).collect())
                    };
                    let step = if function_type == FunctionType::TimeResponse { 1.0 / 48000.0 } else { 0.5 };
                    let header = FunctionHeader::velocity_over_force(function_type, 2, 1001, 0.0, step, "pyuff check");
                    let function = Function58 { header, ordinate };
                    UffEncoder::new(format, precision)
                        .encode(&UffRecord::Function(Box::new(function)), &mut file)
                        .unwrap();
                    let mut json = String::new();
                    write!(
                        json,
                        r#"{{"format":"{format_name}","precision":"{precision_name}","function_type":{},"response_node":2,"reference_node":1001,"abscissa_step":{step:?},"values":[{}]}}"#,
                        function_type.code(),
                        json_values.join(",")
                    )
                    .unwrap();
                    functions.push(json);
                }
            }
        }
    }
    let uff = dir.path().join("all.uff");
    std::fs::write(&uff, &file).unwrap();
    let nodes = nodes();
    let labels: Vec<String> = nodes.nodes.iter().map(|n| n.label.to_string()).collect();
    let positions: Vec<String> = nodes
        .nodes
        .iter()
        .map(|n| format!("[{:?},{:?},{:?}]", n.position_m[0], n.position_m[1], n.position_m[2]))
        .collect();
    let expected = format!(
        r#"{{"node_labels":[{}],"node_positions_m":[{}],"functions":[{}]}}"#,
        labels.join(","),
        positions.join(","),
        functions.join(",")
    );
    let expected_path = dir.path().join("expected.json");
    std::fs::write(&expected_path, expected).unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_uff.py");
    let out = Command::new(metaplate_fixtures::python()).arg(script).arg(&uff).arg(&expected_path).output().unwrap();
    assert!(out.status.success(), "{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
}

//! pyuff reads what an imported dataset exports: a scan mesh on a tilted, rotated plate, imported (its lattice
//! fitted) and exported without a scene in ASCII single precision, reads back in pyuff equal to the dataset within
//! the format's 6 significant digits, at the lattice's positions. Needs a Python with pyuff: `$METAPLATE_PYTHON`,
//! else the project's `.venv/bin/python` that `scripts/install-deps.sh` makes. Run:
//! `cargo test -p metaplate-interchange --test tests pyuff_reads -- --ignored`.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::process::Command;

use metaplate_interchange::{ExportOptions, ImportOptions};
use metaplate_store::Dataset;
use metaplate_uff::{Format, Precision};
use serde_json::Value;

use crate::common;
use crate::foreign::tilted_mesh;

#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with pyuff: run by .ci/run"]
fn pyuff_reads_an_imported_scan_mesh_exported_without_a_scene() {
    let tmp = tempfile::tempdir().unwrap();
    let (mesh, _) = tilted_mesh(tmp.path());
    let data = tmp.path().join("mesh");
    common::import(std::slice::from_ref(&mesh), &data, ImportOptions::default()).unwrap();
    let sites = metaplate_interchange::actuator_sites(&data, None).unwrap();
    let file = tmp.path().join("again.uff");
    let options = ExportOptions { format: Format::Ascii, precision: Precision::Single, frequency: false, points: None };
    metaplate_interchange::export(&data, &file, &options, &sites, |_| {}).unwrap();

    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_uff_values.py");
    let out = Command::new(metaplate_fixtures::python()).arg(script).arg(&file).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let read: Value = serde_json::from_slice(&out.stdout).unwrap();
    let dataset = Dataset::open(&data).unwrap();
    let grid = dataset.manifest().meta.grid;
    let functions = read["functions"].as_array().unwrap();
    assert_eq!(functions.len(), dataset.len());
    for f in functions {
        // Export labels: point_index + 1 for the responses, nx * ny + 1 + actuator for the references.
        let point = f["rsp_node"].as_u64().unwrap() as u32 - 1;
        let actuator = (f["ref_node"].as_u64().unwrap() as usize - grid.len() - 1) as u16;
        assert_eq!(f["ordinate_spec_data_type"], 11, "velocity");
        let want = dataset.ir(point, actuator).unwrap();
        let got: Vec<f64> = f["values"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(got.len(), want.len());
        // `%13.5e`: 6 significant digits, a relative error of at most 5e-6 of each value.
        for (w, g) in want.iter().zip(&got) {
            assert!(
                (f64::from(*w) - g).abs() <= 5e-6 * f64::from(w.abs()),
                "point {point} actuator {actuator}: {w} vs {g}"
            );
        }
        let node = &read["nodes"][(point + 1).to_string()];
        let (x, y) = grid.position_m(point as usize);
        assert_eq!((node[0].as_f64().unwrap(), node[1].as_f64().unwrap()), (x, y), "point {point}");
    }
}

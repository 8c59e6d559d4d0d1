//! pyuff reads what an imported dataset exports: a scan mesh on a tilted, rotated plate, imported (its lattice
//! fitted) and exported without a scene in ASCII single precision, reads back in pyuff equal to the dataset within
//! the format's 6 significant digits, at the nodes' original positions, with its header (dataset 151: the dataset's
//! name and unit); and a PSV scan mesh on no lattice, imported and exported, reads back equal to the PSV export
//! (labels, directions, positions, FRFs). Needs a Python with pyuff: `$METAPLATE_PYTHON`, else the project's
//! `.venv/bin/python` that `scripts/install-deps.sh` makes. Run:
//! `cargo test -p metaplate-interchange --test tests pyuff_reads -- --ignored`.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::process::Command;

use metaplate_interchange::{ExportOptions, ImportOptions};
use metaplate_store::Dataset;
use metaplate_uff::{Complex64, Format, Ordinate, Precision, UffRecord};
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

    let read = pyuff_read(&file);
    let original: std::collections::HashMap<u32, [f64; 3]> = common::decode_nodes(&mesh);
    let dataset = Dataset::open(&data).unwrap();
    // The header as pyuff reads it: the dataset's name and unit, metaplate's programs.
    let unit = &dataset.manifest().meta.description.as_ref().unwrap().ir_unit;
    let header = &read["headers"][0];
    assert_eq!((header["model_name"].as_str(), header["description"].as_str()), (Some("mesh"), Some(unit.as_str())));
    assert_eq!(header["db_app"], "metaplate");
    assert!(header["program"].as_str().unwrap().starts_with("metaplate "), "{header}");
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
        // The node where the mesh put it (in 3-D), as the export keeps an import's nodes.
        let node = &read["nodes"][(point + 1).to_string()];
        let want = original[&(point + 1)];
        for (k, w) in want.iter().enumerate() {
            assert!((node[k].as_f64().unwrap() - w).abs() < 1e-12, "point {point}: {node} vs {want:?}");
        }
    }
}

#[test]
#[ignore = "needs the project's .venv (scripts/install-deps.sh) with pyuff: run by .ci/run"]
fn pyuff_reads_an_imported_psv_scan_mesh_exported_as_the_psv_export() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, data) = crate::scattered::imported(tmp.path());
    let sites = metaplate_interchange::actuator_sites(&data, None).unwrap();
    let file = tmp.path().join("again.uff");
    let options = ExportOptions { format: Format::Ascii, precision: Precision::Single, frequency: true, points: None };
    metaplate_interchange::export(&data, &file, &options, &sites, |_| {}).unwrap();
    let read = pyuff_read(&file);
    let original = crate::scattered::psv_records(usize::MAX);
    for record in &original {
        match record {
            UffRecord::Nodes(nodes) => {
                for n in &nodes.nodes {
                    let got = &read["nodes"][n.label.to_string()];
                    for (k, w) in n.position_m.iter().enumerate() {
                        assert!((got[k].as_f64().unwrap() - w).abs() < 1e-12, "node {}: {got} vs {w}", n.label);
                    }
                }
            }
            UffRecord::Function(f) => {
                let node = f.header.response.node;
                let got = read["functions"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .find(|g| g["func_type"] == 4 && g["rsp_node"] == node)
                    .unwrap();
                assert_eq!(
                    (&got["rsp_dir"], &got["ref_node"], &got["ref_dir"]),
                    (&Value::from(3), &Value::from(crate::scattered::REFERENCE_NODE), &Value::from(3)),
                    "node {node}"
                );
                let Ordinate::Complex(want) = &f.ordinate else { panic!("complex") };
                let values = got["values"].as_array().unwrap();
                assert_eq!(values.len(), want.len());
                // As the crate's own reading (scattered.rs): 6 digits after the f32 response's FFT.
                let peak = want.iter().fold(0.0f64, |m, v| m.max(v.norm()));
                for (w, g) in want.iter().zip(values) {
                    let g = Complex64::new(g[0].as_f64().unwrap(), g[1].as_f64().unwrap());
                    assert!((w - g).norm() <= 2e-5 * peak, "node {node}: {w} vs {g}");
                }
            }
            _ => {}
        }
    }
}

/// What pyuff reads from `file` (`tests/python/read_uff_values.py`).
fn pyuff_read(file: &std::path::Path) -> Value {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/python/read_uff_values.py");
    let out = Command::new(metaplate_fixtures::python()).arg(script).arg(file).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

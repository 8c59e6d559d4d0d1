//! Files as other tools write them, built from an export: records the import does not use (coherence, PSD,
//! geometry) around the responses, actuators numbered from the references whatever the order, and responses of
//! acceleration and displacement converted to the velocity they came from.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::path::Path;

use metaplate_interchange::{ActuatorRef, ImportOptions};
use metaplate_store::{Dataset, IR_UNIT_M_S_PER_N};
use metaplate_uff::{Complex64, Format, FunctionType, Ordinate, Precision, UffDecoder, UffEncoder, UffRecord};

use crate::common;

/// The records of an export of a 2-actuator dataset in ASCII double precision, with frequency responses; the
/// dataset's directory.
fn exported(dir: &Path) -> (Vec<UffRecord>, std::path::PathBuf) {
    let data = common::dataset(dir, 2, 0, IR_UNIT_M_S_PER_N);
    let file = dir.join("all.uff");
    let options = metaplate_interchange::ExportOptions {
        format: Format::Ascii,
        precision: Precision::Double,
        frequency: true,
        points: None,
    };
    common::export(&data, &file, &options).unwrap();
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(&file).unwrap());
    decoder.finish();
    (decoder.records().map(Result::unwrap).collect(), data)
}

fn write(path: &Path, records: &[UffRecord]) {
    let encoder =
        UffEncoder::new(Format::Binary { byte_order: metaplate_uff::ByteOrder::BigEndian }, Precision::Double);
    let mut out = Vec::new();
    for r in records {
        encoder.encode(r, &mut out).unwrap();
    }
    std::fs::write(path, out).unwrap();
}

/// As another tool writes: no metaplate header or ID lines (so the grid comes from the nodes and the actuators from the
/// references), and only the frequency responses.
fn foreign(records: &[UffRecord]) -> Vec<UffRecord> {
    records
        .iter()
        .filter(|r| !matches!(r, UffRecord::Function(f) if f.header.function_type == FunctionType::TimeResponse))
        .filter(|r| !matches!(r, UffRecord::Header(_)))
        .cloned()
        .map(|mut r| {
            if let UffRecord::Function(f) = &mut r {
                f.header.id_lines = std::array::from_fn(|_| "NONE".to_owned());
            }
            r
        })
        .collect()
}

#[test]
fn records_that_are_no_response_are_skipped_listed_and_shift_no_actuator() {
    let tmp = tempfile::tempdir().unwrap();
    let (records, data) = exported(tmp.path());
    let mut records = foreign(&records);
    let plain = tmp.path().join("plain.uff");
    write(&plain, &records);
    let first =
        common::import(std::slice::from_ref(&plain), &tmp.path().join("plain"), ImportOptions::default()).unwrap();

    // A coherence with reference node 0 and a response node no dataset lists, before every response, and a PSD with
    // a reference the responses do not have after them: neither may number an actuator nor need a position.
    let UffRecord::Function(template) = records.iter().find(|r| matches!(r, UffRecord::Function(_))).unwrap().clone()
    else {
        unreachable!()
    };
    let mut coherence = template.clone();
    coherence.header.function_type = FunctionType::Other(6);
    (coherence.header.reference.node, coherence.header.response.node) = (0, 999_999);
    let mut psd = template.clone();
    psd.header.function_type = FunctionType::Other(9);
    psd.header.reference.node = -7;
    let at = records.iter().position(|r| matches!(r, UffRecord::Function(_))).unwrap();
    records.insert(at, UffRecord::Function(coherence));
    records.push(UffRecord::Function(psd));
    let cluttered = tmp.path().join("cluttered.uff");
    write(&cluttered, &records);
    let out = tmp.path().join("cluttered");
    let summary = common::import(std::slice::from_ref(&cluttered), &out, ImportOptions::default()).unwrap();
    assert_eq!(summary.rows, first.rows);
    let kinds: Vec<&str> = summary.skipped.iter().map(|s| s.what.as_str()).collect();
    assert_eq!(
        kinds,
        ["dataset 58, function type 6 (coherence)", "dataset 58, function type 9 (power spectral density)"]
    );
    assert_eq!(summary.skipped[0].record, 3, "after units and nodes");
    // The actuators are the responses' references (labels nx * ny + 1 + actuator in an export), in order.
    let want = [
        ActuatorRef { actuator: 0, reference_node: 13, direction: 3 },
        ActuatorRef { actuator: 1, reference_node: 14, direction: 3 },
    ];
    assert_eq!(summary.actuators, want);
    assert_eq!(first.actuators, want);
    let (a, b) = (Dataset::open(tmp.path().join("plain")).unwrap(), Dataset::open(&out).unwrap());
    common::assert_same(&a, &b, 0.0, "with the clutter");
    common::assert_same(&Dataset::open(&data).unwrap(), &b, 1e-6, "against the original");
    let config = &b.manifest().meta.config;
    assert_eq!(config["actuators"][1]["reference_node"], 14);
    assert!(config["skipped"].as_str().unwrap().starts_with("1 x dataset 58, function type 6 (coherence) (first: "));

    // Responses in the reverse order number the actuators the same.
    let mut reversed = foreign(&exported(&tmp.path().join("again")).0);
    reversed.reverse();
    let headers = reversed.len() - 2;
    reversed.rotate_left(headers);
    let path = tmp.path().join("reversed.uff");
    write(&path, &reversed);
    let summary =
        common::import(std::slice::from_ref(&path), &tmp.path().join("rev"), ImportOptions::default()).unwrap();
    assert_eq!(summary.actuators, want);
    common::assert_same(&a, &Dataset::open(tmp.path().join("rev")).unwrap(), 0.0, "reversed");
}

#[test]
fn acceleration_and_displacement_come_back_as_the_velocity_they_were_made_from() {
    let tmp = tempfile::tempdir().unwrap();
    let (records, _) = exported(tmp.path());
    let velocity = foreign(&records);
    let plain = tmp.path().join("velocity.uff");
    write(&plain, &velocity);
    common::import(std::slice::from_ref(&plain), &tmp.path().join("velocity"), ImportOptions::default()).unwrap();
    let reference = Dataset::open(tmp.path().join("velocity")).unwrap();
    // (data type, units label, factor of jω): acceleration = jω v in mm/s² (label on a general type), displacement =
    // v / jω in data type 8.
    for (data_type, label, power, scale) in [(1, "mm/s^2", 1, 1e3), (8, "m", -1, 1.0), (12, "g", 1, 1.0 / 9.806_65)] {
        let converted: Vec<UffRecord> = velocity
            .iter()
            .cloned()
            .map(|mut r| {
                if let UffRecord::Function(f) = &mut r {
                    f.header.ordinate.data_type = data_type;
                    f.header.ordinate.units_label = label.to_owned();
                    let df = f.header.abscissa_step;
                    let Ordinate::Complex(values) = &mut f.ordinate else { panic!("FRF") };
                    for (k, v) in values.iter_mut().enumerate() {
                        let jw = Complex64::new(0.0, 2.0 * std::f64::consts::PI * k as f64 * df);
                        *v = if k == 0 { Complex64::new(0.0, 0.0) } else { *v * jw.powi(power) * scale };
                    }
                }
                r
            })
            .collect();
        let path = tmp.path().join(format!("{data_type}.uff"));
        write(&path, &converted);
        let out = tmp.path().join(format!("{data_type}"));
        let summary = common::import(std::slice::from_ref(&path), &out, ImportOptions::default()).unwrap();
        assert_eq!(summary.ir_unit, IR_UNIT_M_S_PER_N);
        assert!(summary.conversion.contains("converted to velocity"), "{}", summary.conversion);
        // Bins 1 up come back (within the f32 of the stored responses); 0 Hz cannot (set to zero in both ways), so
        // each response differs from the velocity import by its mean at most.
        let imported = Dataset::open(&out).unwrap();
        for meta in reference.rows() {
            let (want, got) = (
                reference.ir(meta.point_index, meta.actuator).unwrap(),
                imported.ir(meta.point_index, meta.actuator).unwrap(),
            );
            let mean = want.iter().map(|&v| f64::from(v)).sum::<f64>() / want.len() as f64;
            let peak = want.iter().fold(0.0f64, |m, &v| m.max(f64::from(v).abs()));
            for (w, g) in want.iter().zip(got) {
                let err = (f64::from(*w) - mean - f64::from(*g)).abs();
                assert!(err <= 1e-5 * peak, "data type {data_type}: {w} vs {g} (mean {mean})");
            }
        }
    }
}

/// A foreign file (FRFs, no metaplate ID lines) of a 2-actuator dataset whose nodes a scan head on a tilted,
/// rotated plate reports: rotated 20° about z, tilted 30° about x, moved; responses and references alike. The file
/// and the original dataset's directory.
pub fn tilted_mesh(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (records, data) = exported(dir);
    let (rot, tilt) = (20f64.to_radians(), 30f64.to_radians());
    let moved: Vec<UffRecord> = foreign(&records)
        .into_iter()
        .map(|mut r| {
            if let UffRecord::Nodes(nodes) = &mut r {
                for node in &mut nodes.nodes {
                    let [x, y, _] = node.position_m;
                    let (xr, yr) = (x * rot.cos() - y * rot.sin(), x * rot.sin() + y * rot.cos());
                    node.position_m = [0.5 + xr, -0.2 + yr * tilt.cos(), 1.0 + yr * tilt.sin()];
                }
            }
            r
        })
        .collect();
    let path = dir.join("mesh.uff");
    write(&path, &moved);
    (path, data)
}

#[test]
fn a_tilted_rotated_scan_mesh_is_placed_on_its_lattice_and_exports_without_a_scene() {
    let tmp = tempfile::tempdir().unwrap();
    let (path, data) = tilted_mesh(tmp.path());
    let out = tmp.path().join("mesh");
    let summary = common::import(std::slice::from_ref(&path), &out, ImportOptions::default()).unwrap();
    let original = Dataset::open(&data).unwrap();
    assert_eq!(
        (summary.grid.nx, summary.grid.ny),
        (original.manifest().meta.grid.nx, original.manifest().meta.grid.ny)
    );
    assert!((summary.grid.spacing_m - original.manifest().meta.grid.spacing_m).abs() < 1e-12);
    assert!(
        summary.grid_from.starts_with("nodes on a lattice: plane normal (0.000, -0.500, 0.866)"),
        "{}",
        summary.grid_from
    );
    assert!(summary.grid_from.contains("rotated 20.000°"), "{}", summary.grid_from);
    let imported = Dataset::open(&out).unwrap();
    // The same responses at the same points (the lattice's frame differs from the original's by a shift only), as
    // from the FRFs: within 10^-6 of each response's peak (f32 storage through an FFT and back).
    for meta in original.rows() {
        let (p, a) = meta.key();
        let (want, got) = (original.ir(p, a).unwrap(), imported.ir(p, a).unwrap());
        let peak = want.iter().fold(0.0f32, |m, &v| m.max(v.abs()));
        assert!(want.iter().zip(got).all(|(w, g)| (w - g).abs() <= 1e-6 * peak), "point {p} actuator {a}");
    }

    // Exported without a scene: the references the import placed, in the lattice's frame; back, the same.
    let sites = metaplate_interchange::actuator_sites(&out, None).unwrap();
    assert_eq!(sites.len(), 2);
    let (x0, y0) = (
        summary.grid.origin_x_m - original.manifest().meta.grid.origin_x_m,
        summary.grid.origin_y_m - original.manifest().meta.grid.origin_y_m,
    );
    for (site, want) in sites.iter().zip(common::sites()) {
        assert!((site.0 - x0 - want.0).abs() < 1e-9 && (site.1 - y0 - want.1).abs() < 1e-9, "{site:?} vs {want:?}");
    }
    let again = tmp.path().join("again.uff");
    metaplate_interchange::export(&out, &again, &common::binary_double(), &sites, |_| {}).unwrap();
    let back = tmp.path().join("back");
    let summary = common::import(std::slice::from_ref(&again), &back, ImportOptions::default()).unwrap();
    assert_eq!(summary.ir_unit, IR_UNIT_M_S_PER_N);
    // Responses exactly; positions as the export writes them, the lattice's nodes (the import kept each point's
    // measured in-plane position, here on its node but for rounding).
    let back = Dataset::open(&back).unwrap();
    for meta in imported.rows() {
        let (p, a) = meta.key();
        assert_eq!(back.ir(p, a).unwrap(), imported.ir(p, a).unwrap());
        let m = back.meta(p, a).unwrap();
        assert!((m.x_m - meta.x_m).abs() < 1e-12 && (m.y_m - meta.y_m).abs() < 1e-12, "point {p}");
    }
}

//! A scan mesh as a Polytec PSV export writes it: dataset 2411 nodes in 3-D (a tilted, rotated plate) on no
//! lattice, one frequency response function (dataset 58, velocity over force) per node against one reference
//! node. It imports as scattered points, `analyze` reports what they allow (the lattice analyses on an interpolated
//! lattice, saying so), `focus` renders drive signals from it, and it exports with its node labels, directions and
//! positions. The responses are an analytic point-source field (no plate is simulated).

#![allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use metaplate_analysis::dataset_report::analyse_dataset;
use metaplate_control::ControlError;
use metaplate_control::focus::{PixelSpec, RenderOptions, render};
use metaplate_interchange::{ActuatorRef, ExportOptions, ImportOptions};
use metaplate_store::Dataset;
use metaplate_uff::{
    AxisCharacteristics, ByteOrder, Complex64, Dof, Format, Function58, FunctionHeader, FunctionType, Node, Nodes2411,
    Ordinate, Precision, UffDecoder, UffEncoder, UffRecord, Units164,
};

use crate::common;

/// The field's phase speed, m/s: 4 cm at 300 Hz, three wavelengths across the 12 cm mesh.
pub const SPEED_M_S: f64 = 12.0;
/// Frequency step of the FRFs, Hz, and their last bin (0 to 640 Hz: 256-sample responses at 1280 Hz).
const DF_HZ: f64 = 5.0;
const LAST_BIN: usize = 128;
/// The reference node's label, as PSV numbers a reference channel apart from the scan points.
pub const REFERENCE_NODE: i64 = 9001;

/// In-plane positions (m) of a 13 x 11 triangular mesh at 1 cm with rows shifted by half a step and 1.5 mm of
/// jitter: on no lattice (the lattice fit's tolerance is a tenth of a spacing).
fn mesh_in_plane() -> Vec<(f64, f64)> {
    let mut state = 2024u64;
    let mut jitter = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 3e-3
    };
    let mut points = Vec::new();
    for j in 0..11 {
        for i in 0..13 {
            let shift = if j % 2 == 1 { 0.005 } else { 0.0 };
            points.push((i as f64 * 0.01 + shift + jitter(), j as f64 * 0.01 + jitter()));
        }
    }
    points
}

/// The plane's frame in 3-D: tilted 25° about x, rotated 35° about z, moved.
fn to_3d((u, v): (f64, f64)) -> [f64; 3] {
    let (rot, tilt) = (35f64.to_radians(), 25f64.to_radians());
    let (x, y) = (u * rot.cos() - v * rot.sin(), u * rot.sin() + v * rot.cos());
    [0.3 + x, -0.1 + y * tilt.cos(), 0.8 + y * tilt.sin()]
}

/// The source, in the plane: 5 cm beside the mesh.
const SOURCE: (f64, f64) = (-0.05, 0.05);

/// The FRF at distance `r_m` from the source: an outgoing cylindrical wave, `e^{-jkr} / sqrt(1 + r / 1 cm)`,
/// zero at 0 Hz and at the last bin (which an import takes as Nyquist: a real response's is real).
fn frf(r_m: f64) -> Vec<Complex64> {
    (0..=LAST_BIN)
        .map(|b| {
            if b == 0 || b == LAST_BIN {
                return Complex64::new(0.0, 0.0);
            }
            let k = 2.0 * PI * b as f64 * DF_HZ / SPEED_M_S;
            Complex64::from_polar(1.0 / (1.0 + r_m / 0.01).sqrt(), -k * r_m)
        })
        .collect()
}

/// The records of the synthetic PSV export: units, nodes (3-D), one FRF per scan point (velocity over force,
/// +Z over +Z against the reference node), with PSV-like ID lines; `points` limits the scan points.
pub fn psv_records(points: usize) -> Vec<UffRecord> {
    let mesh = mesh_in_plane();
    let mut nodes: Vec<Node> = mesh
        .iter()
        .take(points)
        .enumerate()
        .map(|(i, &p)| Node {
            label: i as u32 + 1,
            export_coordinate_system: 0,
            displacement_coordinate_system: 0,
            color: 8,
            position_m: to_3d(p),
        })
        .collect();
    nodes.push(Node {
        label: REFERENCE_NODE as u32,
        export_coordinate_system: 0,
        displacement_coordinate_system: 0,
        color: 8,
        position_m: to_3d(SOURCE),
    });
    let mut records = vec![UffRecord::Units(Units164::si()), UffRecord::Nodes(Nodes2411 { nodes })];
    for (i, &(u, v)) in mesh.iter().take(points).enumerate() {
        let mut header = FunctionHeader::velocity_over_force(FunctionType::FrequencyResponse, 0, 0, 0.0, DF_HZ, "");
        header.response = Dof { entity: "NONE".into(), node: i as i64 + 1, direction: 3 };
        header.reference = Dof { entity: "NONE".into(), node: REFERENCE_NODE, direction: 3 };
        header.abscissa = AxisCharacteristics::new(18, "Frequency", "Hz");
        header.id_lines = [
            format!("Point {} Vib Velocity / Ref1 Force", i + 1),
            "PSV 10.0 scan".into(),
            "28-Nov-26 10:00:00".into(),
            "Vib Velocity".into(),
            "NONE".into(),
        ];
        let r = (u - SOURCE.0).hypot(v - SOURCE.1);
        records.push(UffRecord::Function(Box::new(Function58 { header, ordinate: Ordinate::Complex(frf(r)) })));
    }
    records
}

/// `records` written as one file in `format`, double precision.
fn write(path: &Path, records: &[UffRecord], format: Format) {
    let encoder = UffEncoder::new(format, Precision::Double);
    let mut out = Vec::new();
    for r in records {
        encoder.encode(r, &mut out).unwrap();
    }
    std::fs::write(path, out).unwrap();
}

fn decode(path: &Path) -> Vec<UffRecord> {
    let mut decoder = UffDecoder::new();
    decoder.push(&std::fs::read(path).unwrap());
    decoder.finish();
    decoder.records().map(Result::unwrap).collect()
}

/// The synthetic PSV export imported into `dir/psv`; its file and the dataset.
pub fn imported(dir: &Path) -> (PathBuf, PathBuf) {
    let file = dir.join("psv.uff");
    write(&file, &psv_records(usize::MAX), Format::Binary { byte_order: ByteOrder::LittleEndian });
    let out = dir.join("psv");
    let summary = common::import(std::slice::from_ref(&file), &out, ImportOptions::default()).unwrap();
    assert!(
        summary.grid_from.starts_with("scattered points: the 143 response nodes are not a grid as they are"),
        "{}",
        summary.grid_from
    );
    assert!(summary.grid_from.contains("least-squares plane"), "{}", summary.grid_from);
    assert_eq!(summary.actuators, [ActuatorRef { actuator: 0, reference_node: REFERENCE_NODE, direction: 3 }]);
    assert_eq!((summary.rows, summary.from_frf, summary.ir_len, summary.sample_rate_hz), (143, 143, 256, 1280.0));
    (file, out)
}

#[test]
fn a_psv_scan_mesh_imports_as_scattered_points_kept_where_they_are() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, out) = imported(tmp.path());
    let dataset = Dataset::open(&out).unwrap();
    let meta = &dataset.manifest().meta;
    let scattered = meta.scattered.as_ref().unwrap();
    assert_eq!((meta.grid.nx, meta.grid.ny, scattered.positions_m.len()), (143, 1, 143));
    // In the plane fitted to the nodes, distances are the mesh's (the plane is exact, to rounding), and each row
    // is at its point's position.
    let mesh = mesh_in_plane();
    for (i, j) in [(0, 1), (0, 142), (17, 90), (60, 61)] {
        let (a, b) = (scattered.positions_m[i], scattered.positions_m[j]);
        let want = (mesh[i].0 - mesh[j].0).hypot(mesh[i].1 - mesh[j].1);
        assert!(((a.0 - b.0).hypot(a.1 - b.1) - want).abs() < 1e-12, "points {i} and {j}");
    }
    for row in dataset.rows() {
        assert_eq!((row.x_m, row.y_m), scattered.positions_m[row.point_index as usize]);
    }
}

#[test]
fn analyze_reports_on_scattered_points_and_interpolates_only_for_the_lattice_analyses() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, out) = imported(tmp.path());
    let (analysis, _) = analyse_dataset(&out, None).unwrap();
    let scattered = analysis.scattered.as_ref().unwrap();
    assert_eq!((analysis.points, scattered.points, analysis.actuators), (143, 143, 1));
    assert!(scattered.on_points.starts_with("POD, authority"), "{}", scattered.on_points);
    assert!(
        scattered.lattice_analyses.contains("interpolated within the points' convex hull: linear on their Delaunay")
            && scattered.lattice_analyses.contains("none extrapolated"),
        "{}",
        scattered.lattice_analyses
    );
    assert!(analysis.pod_components_99.is_some() && analysis.driven_response.is_some(), "{:?}", analysis.errors);
    assert!(!analysis.errors.contains_key("wavelength"), "{:?}", analysis.errors);
    assert!(analysis.table_text().contains("scattered points (143): POD, authority"), "{}", analysis.table_text());
    // The wave's own wavelength, c / f, where the interpolated lattice resolves it: the k-space estimate on a
    // 12 x 10 cm aperture sampled at 1 cm reads within 10 % (its aperture resolution 2π/L is a third of k at
    // 300 Hz; the 8x zero padding puts the peak within a tenth of that; the linear interpolant's error at a
    // quarter wavelength is an amplitude loss, not a phase shift).
    let resolved: Vec<_> = analysis.wavelength.iter().filter(|w| w.in_range).collect();
    assert!(!resolved.is_empty(), "{:?}", analysis.wavelength);
    for w in resolved {
        let want = SPEED_M_S / w.freq_hz;
        let got = w.median_m.unwrap();
        assert!((got - want).abs() <= 0.1 * want, "{} Hz: {got} m against {want} m", w.freq_hz);
    }
}

#[test]
fn focus_renders_drive_signals_on_scattered_points_and_refuses_a_pixel_off_them() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, out) = imported(tmp.path());
    let dataset = Dataset::open(&out).unwrap();
    let at = dataset.manifest().meta.scattered.as_ref().unwrap().positions_m[70];
    // A pixel 1 mm from point 70 (well within its cell) snaps to it.
    let pixel = PixelSpec::from_text(at.0 + 1e-3, at.1, "impulse").unwrap();
    let rendered = render(&dataset, &[pixel], None, &RenderOptions::default()).unwrap();
    assert_eq!(rendered.points, [70]);
    assert_eq!(rendered.signals.len(), 1);
    assert!(rendered.peak > 0.0 && rendered.signals[0].iter().all(|v| v.is_finite() && v.abs() <= 1.0));
    // The predicted field at the pixel peaks at the focus time (one sample of 1/1280 s either way).
    let field = rendered.field_at_pixels().unwrap();
    let peak_at = field[0].iter().enumerate().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).unwrap().0;
    let focus_sample = rendered.focus_s * 1280.0;
    assert!((peak_at as f64 - focus_sample).abs() <= 1.0, "peak at sample {peak_at}, focus at {focus_sample}");
    // 5 cm beyond the mesh's corner: outside the points, refused by name.
    let far = PixelSpec::from_text(-0.5, -0.5, "impulse").unwrap();
    let e = render(&dataset, &[far], None, &RenderOptions::default()).unwrap_err();
    assert!(matches!(e, ControlError::PixelOffPoints { .. }), "{e}");
    assert!(e.to_string().contains("outside the scattered points"), "{e}");
}

#[test]
fn an_imported_scan_mesh_exports_with_its_labels_directions_and_positions_and_imports_again() {
    let tmp = tempfile::tempdir().unwrap();
    let (_, out) = imported(tmp.path());
    let sites = metaplate_interchange::actuator_sites(&out, None).unwrap();
    let file = tmp.path().join("again.uff");
    let options = ExportOptions { format: Format::Ascii, precision: Precision::Single, frequency: true, points: None };
    metaplate_interchange::export(&out, &file, &options, &sites, |_| {}).unwrap();
    let original = psv_records(usize::MAX);
    let records = decode(&file);
    let nodes = |records: &[UffRecord]| -> Vec<(u32, [f64; 3])> {
        let mut all: Vec<(u32, [f64; 3])> = records
            .iter()
            .filter_map(|r| if let UffRecord::Nodes(n) = r { Some(n.nodes.clone()) } else { None })
            .flatten()
            .map(|n| (n.label, n.position_m))
            .collect();
        all.sort_by_key(|n| n.0);
        all
    };
    let (want, got) = (nodes(&original), nodes(&records));
    assert_eq!(got.len(), want.len());
    for ((wl, wp), (gl, gp)) in want.iter().zip(&got) {
        assert_eq!(wl, gl);
        // Dataset 2411 writes coordinates with 16 significant digits.
        assert!(wp.iter().zip(gp).all(|(a, b)| (a - b).abs() < 1e-12), "node {wl}: {wp:?} vs {gp:?}");
    }
    let frfs = |records: &[UffRecord]| -> Vec<Function58> {
        records
            .iter()
            .filter_map(|r| match r {
                UffRecord::Function(f) if f.header.function_type == FunctionType::FrequencyResponse => Some(*f.clone()),
                _ => None,
            })
            .collect()
    };
    let (want, mut got) = (frfs(&original), frfs(&records));
    got.sort_by_key(|f| f.header.response.node);
    assert_eq!(got.len(), 143);
    for (w, g) in want.iter().zip(&got) {
        let node = w.header.response.node;
        assert_eq!((&g.header.response, &g.header.reference), (&w.header.response, &w.header.reference));
        assert_eq!((g.header.abscissa_start, g.header.abscissa_step), (0.0, DF_HZ));
        let (Ordinate::Complex(w), Ordinate::Complex(g)) = (&w.ordinate, &g.ordinate) else { panic!("complex") };
        assert_eq!(w.len(), g.len());
        // ASCII single: 6 significant digits (5e-6 of a value), after the f32 impulse response's FFT (at most
        // 256 x 2^-24, 1.5e-5, of the FRF's peak, which bounds the response's).
        let peak = w.iter().fold(0.0f64, |m, v| m.max(v.norm()));
        for (a, b) in w.iter().zip(g) {
            assert!((a - b).norm() <= 2e-5 * peak, "node {node}: {a} vs {b}");
        }
    }
    // Imported again: the same scattered points, the same reference, the same responses (single precision).
    let back = tmp.path().join("back");
    let summary = common::import(&[file], &back, ImportOptions::default()).unwrap();
    assert!(summary.grid_from.starts_with("scattered points"), "{}", summary.grid_from);
    assert_eq!(summary.actuators, [ActuatorRef { actuator: 0, reference_node: REFERENCE_NODE, direction: 3 }]);
    let (a, b) = (Dataset::open(&out).unwrap(), Dataset::open(&back).unwrap());
    let (pa, pb) = (&a.manifest().meta.scattered, &b.manifest().meta.scattered);
    for (p, q) in pa.as_ref().unwrap().positions_m.iter().zip(&pb.as_ref().unwrap().positions_m) {
        assert!((p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9, "{p:?} vs {q:?}");
    }
    assert_eq!(a.len(), b.len());
    for row in a.rows() {
        let (want, got) = (a.ir(row.point_index, 0).unwrap(), b.ir(row.point_index, 0).unwrap());
        let peak = want.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        // ASCII single: 6 significant digits, 5e-6 of each value.
        assert!(want.iter().zip(got).all(|(w, g)| (w - g).abs() <= 5e-6 * peak), "point {}", row.point_index);
    }
}

#[test]
fn one_point_and_points_on_a_line_are_named_by_analyze() {
    let tmp = tempfile::tempdir().unwrap();
    // One point: analyze says so.
    let one = tmp.path().join("one.uff");
    write(&one, &psv_records(1), Format::Ascii);
    let out = tmp.path().join("one");
    let summary = common::import(std::slice::from_ref(&one), &out, ImportOptions::default()).unwrap();
    assert_eq!(summary.grid_from, "one point");
    let Err(e) = analyse_dataset(&out, None) else { panic!("one point analysed") };
    let e = e.to_string();
    assert!(e.contains("it holds one point, at ("), "{e}");
    // Points on a line, unevenly spaced: scattered, and the lattice analyses name why they have no lattice.
    let mut records = psv_records(6);
    if let UffRecord::Nodes(nodes) = &mut records[1] {
        // Along a line rising at 45° (no grid in a plane z = const), 13 to 29 mm apart (no lattice).
        for (node, d) in nodes.nodes.iter_mut().zip([0.0, 0.013, 0.0291, 0.047, 0.0717, 0.1003]) {
            node.position_m = [d / 2f64.sqrt(), 0.02, d / 2f64.sqrt()];
        }
    }
    let line = tmp.path().join("line.uff");
    write(&line, &records, Format::Ascii);
    let out = tmp.path().join("line");
    let summary = common::import(std::slice::from_ref(&line), &out, ImportOptions::default()).unwrap();
    assert!(summary.grid_from.starts_with("scattered points"), "{}", summary.grid_from);
    let (analysis, _) = analyse_dataset(&out, None).unwrap();
    for key in ["wavelength", "pixel_area"] {
        let why = &analysis.errors[key];
        assert!(why.contains("needs a lattice") && why.contains("lie on one line"), "{key}: {why}");
    }
    assert!(analysis.driven_response.is_some(), "{:?}", analysis.errors);
}

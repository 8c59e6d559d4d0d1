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

/// `records` with each FRF's ID line 2 as PSV writes it for the estimator `estimator`, its ordinate times `scale`.
fn as_estimate(records: &[UffRecord], estimator: &str, scale: f64) -> Vec<UffRecord> {
    records
        .iter()
        .filter_map(|r| match r {
            UffRecord::Function(f) => {
                let mut f = f.clone();
                f.header.id_lines[1] = format!("Vib  Ref1  {estimator} Velocity / Force");
                if let Ordinate::Complex(values) = &mut f.ordinate {
                    values.iter_mut().for_each(|v| *v *= scale);
                }
                Some(UffRecord::Function(f))
            }
            _ => None,
        })
        .collect()
}

/// The first `points` nodes and FRFs of the synthetic PSV export, and the import of those records into `dir/name`.
fn import_records(dir: &Path, name: &str, records: &[UffRecord], estimator: Option<&str>) -> Result<PathBuf, String> {
    let file = dir.join(format!("{name}.uff"));
    write(&file, records, Format::Ascii);
    let out = dir.join(name);
    let options = ImportOptions { estimator: estimator.map(str::to_owned), ..ImportOptions::default() };
    let summary = common::import(&[file], &out, options).map_err(|e| common::message(&e))?;
    let rows = summary.rows;
    let estimate = summary.estimator.map(str::to_owned);
    let skipped: Vec<String> = summary.skipped.iter().map(|s| s.what.clone()).collect();
    std::fs::write(
        out.join("summary.txt"),
        format!("{rows} {estimate:?} {:?} {skipped:?}", summary.response_direction),
    )
    .unwrap();
    Ok(out)
}

fn summary_of(out: &Path) -> String {
    std::fs::read_to_string(out.join("summary.txt")).unwrap()
}

#[test]
fn frfs_by_several_estimators_import_the_one_chosen_and_list_the_others() {
    // As PSV exports H1 and H2 of every point against the reference: each an FRF of the same pair, told apart by
    // ID line 2 only.
    let tmp = tempfile::tempdir().unwrap();
    let base = psv_records(20);
    let head: Vec<UffRecord> = base.iter().filter(|r| !matches!(r, UffRecord::Function(_))).cloned().collect();
    let (h1, h2) = (as_estimate(&base, "H1", 1.0), as_estimate(&base, "H2", 1.25));
    let both: Vec<UffRecord> =
        head.iter().cloned().chain(h1.iter().zip(&h2).flat_map(|(a, b)| [a.clone(), b.clone()])).collect();
    let only_h1: Vec<UffRecord> = head.iter().cloned().chain(h1.iter().cloned()).collect();

    let reference = Dataset::open(import_records(tmp.path(), "h1", &only_h1, None).unwrap()).unwrap();
    // By default the first of H1, H2, ... present: H1, the others listed as skipped.
    let default = import_records(tmp.path(), "both", &both, None).unwrap();
    let summary = summary_of(&default);
    assert!(summary.starts_with("20 Some(\"H1\") None"), "{summary}");
    assert_eq!(summary.matches("H2 estimate (not chosen: the H1 estimate is imported)").count(), 20, "{summary}");
    let default = Dataset::open(&default).unwrap();
    for row in reference.rows() {
        let (p, a) = row.key();
        assert_eq!(default.ir(p, a), reference.ir(p, a), "point {p}");
    }
    assert_eq!(default.manifest().meta.config["estimator"], "H1");

    // Asked for H2: the responses 1.25 times H1's (to the f32 rounding of the stored values).
    let h2_data = Dataset::open(import_records(tmp.path(), "h2", &both, Some("H2")).unwrap()).unwrap();
    for row in reference.rows() {
        let (p, a) = row.key();
        for (&x, &y) in reference.ir(p, a).unwrap().iter().zip(h2_data.ir(p, a).unwrap()) {
            assert!((f64::from(y) - 1.25 * f64::from(x)).abs() <= 1e-6 * f64::from(x).abs().max(1e-3), "point {p}");
        }
    }

    // An estimator the files lack, and a name that is none.
    let why = import_records(tmp.path(), "h3", &both, Some("H3")).unwrap_err();
    assert!(why.contains("by the estimators H1, H2 (ID line 2), none by H3; --estimator takes one of H1"), "{why}");
    let why = import_records(tmp.path(), "h5", &both, Some("H5")).unwrap_err();
    assert!(why.contains("--estimator H5: accepted are H1, H2, H3, Hv, FRF"), "{why}");
}

/// The synthetic PSV records of `points` points with every FRF given again in directions x and y (the in-plane
/// components a 3-D scan head measures, a tenth and a fifth of the normal one), the nodes at `place(u, v)`.
fn three_d(points: usize, place: impl Fn((f64, f64)) -> [f64; 3]) -> (Vec<UffRecord>, Vec<UffRecord>) {
    let mesh = mesh_in_plane();
    let mut z_only = psv_records(points);
    for r in &mut z_only {
        if let UffRecord::Nodes(nodes) = r {
            for node in &mut nodes.nodes {
                let i = node.label as usize - 1;
                node.position_m = if i < mesh.len() { place(mesh[i]) } else { place(SOURCE) };
            }
        }
    }
    let mut all = Vec::new();
    for r in &z_only {
        all.push(r.clone());
        if let UffRecord::Function(f) = r {
            for (direction, scale) in [(1, 0.1), (2, 0.2)] {
                let mut g = f.clone();
                g.header.response.direction = direction;
                if let Ordinate::Complex(values) = &mut g.ordinate {
                    values.iter_mut().for_each(|v| *v *= scale);
                }
                all.push(UffRecord::Function(g));
            }
        }
    }
    (z_only, all)
}

#[test]
fn a_3d_heads_directions_keep_the_plates_normal_or_are_refused_on_a_tilted_plate() {
    let tmp = tempfile::tempdir().unwrap();
    // The plate in a plane z = const: the z responses are its normal velocity, x and y listed as skipped.
    let (z_only, all) = three_d(20, |(u, v)| [u, v, 0.8]);
    let reference = Dataset::open(import_records(tmp.path(), "z", &z_only, None).unwrap()).unwrap();
    let out = import_records(tmp.path(), "xyz", &all, None).unwrap();
    let summary = summary_of(&out);
    assert!(summary.starts_with("20 None Some(3)"), "{summary}");
    for direction in [1, 2] {
        let what = format!("response direction {direction} (not chosen: the plate's normal is ±3)");
        assert_eq!(summary.matches(&what).count(), 20, "{summary}");
    }
    let data = Dataset::open(&out).unwrap();
    for row in reference.rows() {
        let (p, a) = row.key();
        assert_eq!(data.ir(p, a), reference.ir(p, a), "point {p}");
    }
    assert_eq!(data.manifest().meta.config["response_direction"], 3);

    // Tilted 3° about x: z is still within 5° of the normal. Tilted 25° (the PSV mesh's plane): refused by name.
    let tilted = |deg: f64| move |(u, v): (f64, f64)| [u, v * deg.to_radians().cos(), v * deg.to_radians().sin()];
    let (_, all) = three_d(20, tilted(3.0));
    assert!(summary_of(&import_records(tmp.path(), "tilt3", &all, None).unwrap()).starts_with("20 None Some(3)"));
    let (_, all) = three_d(20, tilted(25.0));
    let why = import_records(tmp.path(), "tilt25", &all, None).unwrap_err();
    assert!(why.contains("hold responses in the directions 1, 2, 3 (record 6)"), "{why}");
    assert!(why.contains("is 25.0° from the nearest axis"), "{why}");
}

//! Every figure renders from small synthetic data into a valid PNG and an SVG that carries its axis labels, with the
//! bundled font only.

#![allow(clippy::unwrap_used)] // helpers outside #[test] functions unwrap too: a failure is a failed test

use std::path::Path;

use metaplate_core::grid::GridSpec;
use metaplate_figures::{
    BandFigure, Curve, FigureError, PlateOverlay, SingularValueSeries, WavelengthReferences, WavelengthSeries, Written,
    band_structure, condition_numbers, driven_response, focus_animation, focus_snapshots, pixel_area_map, pod_energy,
    singular_value_energy, wavelength,
};

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Checks both files: PNG signature and a decodable image of non-trivial size with more than one colour (something
/// was drawn); SVG text that opens and closes an `<svg` element and contains every expected label.
fn check(written: &Written, labels: &[&str]) {
    let png = std::fs::read(&written.png).unwrap();
    assert!(png.starts_with(PNG_MAGIC), "{} is not a PNG", written.png.display());
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert!(info.width >= 300 && info.height >= 300);
    let first = &buf[..3];
    assert!(buf.chunks(3).any(|px| px != first), "the PNG is a single colour");
    let svg = std::fs::read_to_string(&written.svg).unwrap();
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"), "{} is not an SVG", written.svg.display());
    for label in labels {
        assert!(svg.contains(label), "{} lacks the label {label:?}", written.svg.display());
    }
}

fn curve(label: &str, f: impl Fn(f64) -> f64, xs: impl Iterator<Item = f64>) -> Curve {
    Curve { label: label.to_owned(), points: xs.map(|x| (x, f(x))).collect() }
}

#[test]
fn line_figures_render_to_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let freqs: Vec<f64> = (0..10).map(|i| 75.0 + 50.0 * i as f64).collect();
    let wl = WavelengthSeries {
        label: "metamaterial".into(),
        median_m: freqs.iter().map(|f| 0.1 * (75.0 / f).sqrt()).collect(),
        iqr_m: freqs.iter().map(|f| (0.09 * (75.0 / f).sqrt(), 0.11 * (75.0 / f).sqrt())).collect(),
        in_range: freqs.iter().map(|&f| f > 100.0).collect(),
        freqs_hz: freqs.clone(),
    };
    let references = WavelengthReferences {
        curves: vec![curve("A0 (analytic)", |f| 0.2 * (75.0 / f).sqrt(), freqs.iter().copied())],
        marks: vec![Curve { label: "paper".into(), points: vec![(75.0, 0.113), (600.0, 0.025)] }],
        resolvable_m: Some((0.02, 0.125)),
    };
    check(
        &wavelength(d, "wavelength", "lattice 25 x 13 at 1 cm", &[wl], &references).unwrap(),
        &[
            "frequency (Hz)",
            "wavelength (cm)",
            "metamaterial",
            "A0 (analytic)",
            "paper",
            "resolvable range",
            "lattice 25 x 13",
        ],
    );

    let pod = [
        curve("metamaterial", |n| 0.5f64.powf(n), (1..=30).map(f64::from)),
        curve("homogeneous", |n| 0.3f64.powf(n), (1..=30).map(f64::from)),
    ];
    check(&pod_energy(d, "pod", &pod).unwrap(), &["component", "normalised energy", "cumulative energy (%)"]);

    let sv = SingularValueSeries {
        label: "3.5 cm".into(),
        mean_db: (0..8).map(|i| -4.0 * i as f64).collect(),
        std_db: vec![2.0; 8],
    };
    check(&singular_value_energy(d, "sv", &[sv]).unwrap(), &["singular value index", "3.5 cm"]);

    let kappa = [curve("homogeneous", |d| 500.0 / d, [3.5, 6.5, 9.5].into_iter())];
    let paper = [Curve { label: "paper".into(), points: vec![(3.5, 236.0), (9.5, 51.5)] }];
    check(
        &condition_numbers(d, "kappa", "lattice at 1 cm", &kappa, &paper).unwrap(),
        &["domain edge (cm)", "condition number", "paper", "lattice at 1 cm"],
    );

    let response = [curve("metamaterial", |f| 1e-3 / f, freqs.iter().copied())];
    check(&driven_response(d, "response", &response).unwrap(), &["frequency (Hz)", "mean |G|"]);

    // The band diagram's axis names the path's corners, Γ at both ends.
    let path: Vec<f64> = (0..=34).map(|i| f64::from(i) * 0.1).collect();
    let band = BandFigure {
        title: "Band structure of a cell".into(),
        branches: vec![curve("m = 1", |x| 100.0 * x, path.iter().copied())],
        a0_folded: vec![curve("A0, homogeneous plate (folded)", |x| 300.0 * x, path.iter().copied())],
        resonator_hz: Some(500.0),
        phase_velocity: vec![curve("m = 1", |f| f / 50.0, freqs.iter().copied())],
        wavelength: vec![curve("m = 1", |f| 10.0 / f, freqs.iter().copied())],
        a0_phase_velocity: None,
        a0_wavelength: None,
    };
    let written = band_structure(d, "band", &band).unwrap();
    check(&written, &["wave vector along Γ-X-M-Γ (π/a)", "phase velocity (m/s)", "clamped-cell resonator mode"]);
    let svg = std::fs::read_to_string(&written.svg).unwrap();
    // Each tick label is a text element of its own line.
    let count = |label: &str| svg.lines().filter(|l| *l == label).count();
    assert_eq!((count("Γ"), count("X"), count("M")), (2, 1, 1), "the path's corners");
}

#[test]
fn map_figures_render_to_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let grid = GridSpec::centred(9, 5, 0.005);
    let field = |t: f64| -> Vec<Option<f64>> {
        (0..grid.len())
            .map(|i| {
                let (x, y) = grid.position_m(i);
                (i != 0).then(|| (-(x * x + y * y) / 1e-4).exp() * (t + 100.0 * x).cos())
            })
            .collect()
    };
    let snaps = vec![("t = -1 ms".to_owned(), field(-1.0)), ("t = 0".to_owned(), field(0.0))];
    let overlay = overlay();
    check(
        &focus_snapshots(dir.path(), "focus", &grid, &snaps, "focus, 75 to 400 Hz", &overlay).unwrap(),
        &["x (cm)", "y (cm)", "t = 0", "75 to 400 Hz", "half maximum", "resonator region", "focus target"],
    );

    let area: Vec<Option<f64>> = (0..grid.len()).map(|i| (i % 7 != 0).then_some(1.0 + i as f64 / 10.0)).collect();
    let measured: Vec<bool> = (0..grid.len()).map(|i| i != 3).collect();
    check(
        &pixel_area_map(dir.path(), "area", &grid, &area, &measured, "median 2.7 cm^2", &overlay).unwrap(),
        &["x (cm)", "pixel area (cm²)", "median 2.7 cm^2", "no closed contour", "off the plate"],
    );
}

/// A 20 x 12 cm rectangular plate with two actuators, a support, a few rods and a focus at the centre.
fn overlay() -> PlateOverlay {
    PlateOverlay {
        actuators_m: vec![(-0.09, 0.0), (0.09, 0.0)],
        supports_m: vec![(0.0, 0.05)],
        outline_m: vec![(-0.1, -0.06), (0.1, -0.06), (0.1, 0.06), (-0.1, 0.06)],
        resonator_sites_m: (0..15).map(|i| (f64::from(i % 5 - 2) * 0.01, f64::from(i / 5 - 1) * 0.01)).collect(),
        focus_m: Some((0.0, 0.0)),
    }
}

#[test]
fn the_focus_animation_is_an_apng_of_the_frames_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let grid = GridSpec::centred(9, 5, 0.02);
    let frames: Vec<(f64, Vec<Option<f64>>)> = (-3..=3)
        .map(|k| {
            let t_s = f64::from(k) * 1e-3;
            let field = (0..grid.len())
                .map(|i| {
                    let (x, y) = grid.position_m(i);
                    Some((-(x * x + y * y) / 1e-3).exp() * (2e3 * t_s + 30.0 * x).cos())
                })
                .collect();
            (t_s, field)
        })
        .collect();
    let path = focus_animation(dir.path(), "anim", &grid, &frames, "focusing", &overlay(), 100).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.windows(4).any(|w| w == b"acTL"), "no acTL chunk: not an animated PNG");
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
    let control = reader.info().animation_control().copied().unwrap();
    assert_eq!(control.num_frames, 7);
    assert_eq!(control.num_plays, 0, "loops forever");
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let mut decoded = 0;
    while decoded < 7 {
        reader.next_frame(&mut buf).unwrap();
        decoded += 1;
    }
    let (w, h) = (reader.info().width, reader.info().height);
    assert!(w >= 600 && h >= 300, "{w} x {h}");
    // A time that is not finite is refused before anything is written.
    let bad = vec![(f64::NAN, frames[0].1.clone())];
    assert!(matches!(
        focus_animation(dir.path(), "bad", &grid, &bad, "", &overlay(), 100),
        Err(FigureError::InvalidData { .. })
    ));
    assert!(!dir.path().join("bad.png").exists());
}

#[test]
fn unplottable_data_is_a_typed_error() {
    let d = Path::new("/nonexistent-never-written");
    assert!(matches!(pod_energy(d, "x", &[]), Err(FigureError::InvalidData { .. })));
    let nan = [Curve { label: "nan".into(), points: vec![(f64::NAN, 1.0), (1.0, f64::INFINITY)] }];
    assert!(matches!(condition_numbers(d, "x", "", &nan, &[]), Err(FigureError::Draw { .. })));
    let grid = GridSpec::centred(3, 3, 0.005);
    assert!(matches!(
        pixel_area_map(d, "x", &grid, &[None; 9], &[true; 9], "t", &PlateOverlay::default()),
        Err(FigureError::InvalidData { .. })
    ));
    assert!(matches!(
        pixel_area_map(d, "x", &grid, &[Some(1.0); 4], &[true; 4], "t", &PlateOverlay::default()),
        Err(FigureError::InvalidData { .. })
    ));
    assert!(matches!(
        pixel_area_map(d, "x", &grid, &[Some(1.0); 9], &[true; 8], "t", &PlateOverlay::default()),
        Err(FigureError::InvalidData { .. })
    ));
    assert!(matches!(
        focus_snapshots(d, "x", &grid, &[], "", &PlateOverlay::default()),
        Err(FigureError::InvalidData { .. })
    ));
}

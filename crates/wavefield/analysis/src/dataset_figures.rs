//! The figures of a dataset's analysis ([`crate::dataset_report`]): one plate's (wavelength, focus snapshots and
//! animation, pixel-area map, POD energy, singular-value energy, condition numbers, driven response), and the two
//! plates' on shared axes with the paper's values.

use std::path::{Path, PathBuf};

use metaplate_control::PropagationMatrices;
use metaplate_core::error_chain;
use metaplate_core::grid::GridSpec;
use metaplate_core::scene::{Outline, Scene};
use metaplate_figures as figures;

use crate::authority::DomainAuthority;
use crate::dataset_report::{DOMAIN_EDGE_KEYS, DatasetAnalysis, DatasetAnalysisParts, edge_key};
use crate::error::AnalysisError;
use crate::focus::focus_snapshot;
use crate::lattice::MIN_LATTICE_FILL;
use crate::report::ReportOptions;

/// Instants of the focus snapshots relative to the focus time, s.
const SNAPSHOT_TAUS_S: [f64; 5] = [-0.004, -0.002, 0.0, 0.002, 0.004];

/// Frames of the focusing animation: times relative to the focus time from -`ANIMATION_FRAMES / 2` to
/// +`ANIMATION_FRAMES / 2` steps of `ANIMATION_STEP_S` (most of a 75 Hz period each side of the focus), each shown
/// `ANIMATION_FRAME_MS`.
const ANIMATION_FRAMES: i32 = 21;
const ANIMATION_STEP_S: f64 = 0.001;
const ANIMATION_FRAME_MS: u16 = 160;

/// Vertices of the outline polygon drawn on the maps (fine enough that a 25 cm plate's edge is off by < 0.1 mm).
const OUTLINE_VERTICES: usize = 360;

/// The paper's measured wavelengths (Fig. 4A, metamaterial): 11.3 cm at 75 Hz and 2.5 cm at 600 Hz, (Hz, m).
const PAPER_WAVELENGTHS: [(f64, f64); 2] = [(75.0, 0.113), (600.0, 0.025)];

/// The paper's mean condition numbers (Fig. 6C) against domain edge, (cm, kappa): metamaterial, homogeneous.
const PAPER_CONDITION_NUMBERS: [[(f64, f64); 3]; 2] =
    [[(9.5, 5.0), (6.5, 10.1), (3.5, 35.9)], [(9.5, 51.5), (6.5, 110.6), (3.5, 236.0)]];

/// A figure's error as [`AnalysisError::Figure`].
fn drawn<T>(name: &'static str, result: Result<T, figures::FigureError>) -> Result<T, AnalysisError> {
    result.map_err(|e| AnalysisError::Figure { name, reason: error_chain::message(&e) })
}

/// One plate's wavelengths, as the figure takes them (frequencies without an estimate left out).
fn wavelength_series(label: &str, analysis: &DatasetAnalysis) -> figures::WavelengthSeries {
    let rows: Vec<_> = analysis.wavelength.iter().filter(|w| w.median_m.is_some_and(f64::is_finite)).collect();
    figures::WavelengthSeries {
        label: label.to_owned(),
        freqs_hz: rows.iter().map(|w| w.freq_hz).collect(),
        median_m: rows.iter().map(|w| w.median_m.unwrap_or(f64::NAN)).collect(),
        iqr_m: rows.iter().map(|w| w.iqr_m.map_or((f64::NAN, f64::NAN), |[lo, hi]| (lo, hi))).collect(),
        in_range: rows.iter().map(|w| w.in_range).collect(),
    }
}

/// The references of a wavelength figure: the analytic A0 (from the first analysis that has it), the paper's
/// measured end points, the resolvable range of the first analysis's lattice.
fn wavelength_references(analyses: &[&DatasetAnalysis], with_paper: bool) -> figures::WavelengthReferences {
    let a0: Vec<(f64, f64)> = analyses
        .iter()
        .map(|a| {
            a.wavelength
                .iter()
                .filter_map(|w| Some((w.freq_hz, w.a0_wavelength_m.flatten().filter(|v| v.is_finite())?)))
                .collect::<Vec<_>>()
        })
        .find(|points| !points.is_empty())
        .unwrap_or_default();
    let finite = |v: f64| v.is_finite().then_some(v);
    let range = analyses.first().map(|a| &a.wavelength_resolvable);
    figures::WavelengthReferences {
        curves: if a0.is_empty() {
            Vec::new()
        } else {
            vec![figures::Curve { label: "A0, homogeneous plate (analytic)".to_owned(), points: a0 }]
        },
        marks: if with_paper {
            vec![figures::Curve {
                label: "paper, metamaterial (measured)".to_owned(),
                points: PAPER_WAVELENGTHS.to_vec(),
            }]
        } else {
            Vec::new()
        },
        resolvable_m: range.and_then(|r| finite(r.shortest_m).zip(finite(r.longest_m))),
    }
}

/// Title of a wavelength figure: the lattice, and why an estimate is drawn hollow (outside the resolvable range, or
/// every estimate when the lattice is filled below [`MIN_LATTICE_FILL`]).
fn wavelength_title(analysis: &DatasetAnalysis) -> String {
    let lattice = analysis.lattice_text();
    let fill = analysis.lattice.fill;
    if fill < MIN_LATTICE_FILL {
        return format!(
            "Wavelength (k-space, median and IQR), {lattice}; hollow: lattice {:.0} % filled, under {:.0} %",
            (fill * 100.0).floor(),
            MIN_LATTICE_FILL * 100.0
        );
    }
    format!(
        "Wavelength (k-space, median and IQR), {lattice}; hollow: outside {:.0} to {:.1} cm",
        analysis.wavelength_resolvable.shortest_m * 100.0,
        analysis.wavelength_resolvable.longest_m * 100.0,
    )
}

/// Figures comparing plates on shared axes, from their analyses (`(label, analysis)`, metamaterial first): the
/// wavelengths with the analytic A0 and the paper's measured points, and the condition numbers against domain edge
/// with the paper's values. Returns the files written (PNG and SVG).
///
/// # Errors
/// A figure that cannot be drawn or written.
pub fn write_comparison_figures(
    dir: &Path,
    analyses: &[(&str, &DatasetAnalysis)],
) -> Result<Vec<PathBuf>, AnalysisError> {
    let mut written = Vec::new();
    let Some((_, first)) = analyses.first() else { return Ok(written) };
    let series: Vec<_> = analyses.iter().map(|(label, a)| wavelength_series(label, a)).collect();
    let all: Vec<&DatasetAnalysis> = analyses.iter().map(|(_, a)| *a).collect();
    if series.iter().any(|s| !s.freqs_hz.is_empty()) {
        let references = wavelength_references(&all, true);
        let w = drawn(
            "wavelength",
            figures::wavelength(dir, "wavelength", &wavelength_title(first), &series, &references),
        )?;
        written.extend([w.png, w.svg]);
    }
    if let Some(w) = condition_figure(dir, analyses)? {
        written.extend([w.png, w.svg]);
    }
    Ok(written)
}

/// The condition numbers of `analyses` against domain edge, with the paper's values for the plates it measured
/// (matched by label); `None` when no analysis has one.
fn condition_figure(
    dir: &Path,
    analyses: &[(&str, &DatasetAnalysis)],
) -> Result<Option<figures::Written>, AnalysisError> {
    let Some((_, first)) = analyses.first() else { return Ok(None) };
    let curves: Vec<figures::Curve> = analyses
        .iter()
        .map(|(label, a)| figures::Curve {
            label: format!("{label} ({})", a.domain_points_text()),
            points: DOMAIN_EDGE_KEYS
                .iter()
                .filter_map(|k| {
                    let kappa = a.condition_number.get(*k).copied().flatten().filter(|v| v.is_finite())?;
                    Some((k.parse::<f64>().ok()?, kappa))
                })
                .collect(),
        })
        .collect();
    if curves.iter().all(|c| c.points.is_empty()) {
        return Ok(None);
    }
    // One set of marks per plate, in the plates' order, so that each takes its plate's colour.
    let marks: Vec<figures::Curve> = analyses
        .iter()
        .map(|(label, _)| figures::Curve {
            label: format!("paper, {label} (361 / 169 / 49 points at 0.5 cm)"),
            points: match *label {
                "metamaterial" => PAPER_CONDITION_NUMBERS[0].to_vec(),
                "homogeneous" => PAPER_CONDITION_NUMBERS[1].to_vec(),
                _ => Vec::new(),
            },
        })
        .collect();
    let title = format!("Mean condition number of G_D, 75 to 400 Hz, {}", first.lattice_text());
    drawn("condition_numbers", figures::condition_numbers(dir, "condition_numbers", &title, &curves, &marks)).map(Some)
}

/// Writes every figure of one plate's analysis into `dir` (`label`: the scene's name) and returns the files
/// written, PNG and SVG, the animation (APNG) last. Maps are drawn on the points' own lattice (a regular subset
/// fills its cells; no holes between them).
///
/// # Errors
/// A figure that cannot be drawn or written, a focus snapshot that cannot be computed.
pub fn write_dataset_figures(
    dir: &Path,
    label: &str,
    analysis: &DatasetAnalysis,
    parts: &DatasetAnalysisParts,
) -> Result<Vec<PathBuf>, AnalysisError> {
    let (g, report) = (&parts.g, &parts.report);
    let overlay = parts.scene.as_ref().map_or_else(figures::PlateOverlay::default, plate_overlay);
    let mut written = Vec::new();
    // The animation is one file (APNG, no SVG): kept apart and listed after the maps.
    let mut animation = None;
    let mut add = |w: figures::Written| written.extend([w.png, w.svg]);
    let lattice = &report.lattice;
    let series = wavelength_series(label, analysis);
    if !series.freqs_hz.is_empty() {
        let references = wavelength_references(&[analysis], label == "metamaterial");
        let title = wavelength_title(analysis);
        add(drawn("wavelength", figures::wavelength(dir, "wavelength", &title, &[series], &references))?);
    }
    let opts = ReportOptions::default().refresh;
    if let Some(row) = centre_row(g, &lattice.grid, &lattice.indices) {
        let mut snaps = Vec::new();
        for tau in SNAPSHOT_TAUS_S {
            let field = focus_snapshot(g, row, &opts.band, opts.method, tau)?;
            snaps.push((format!("t = {:+.0} ms", tau * 1e3), on_grid(&lattice.grid, &lattice.indices, &field)));
        }
        let (x, y) = lattice.grid.position_m(lattice.indices[row] as usize);
        let title = format!(
            "{label}: focus at ({:.1}, {:.1}) cm, {:.0} to {:.0} Hz, {}",
            x * 100.0,
            y * 100.0,
            opts.band.lo_hz,
            opts.band.hi_hz,
            analysis.lattice_text(),
        );
        let overlay = figures::PlateOverlay { focus_m: Some((x, y)), ..overlay.clone() };
        let snapshots = figures::focus_snapshots(dir, "focus_snapshots", &lattice.grid, &snaps, &title, &overlay);
        add(drawn("focus_snapshots", snapshots)?);
        let mut frames = Vec::new();
        for step in -(ANIMATION_FRAMES / 2)..=ANIMATION_FRAMES / 2 {
            let tau = f64::from(step) * ANIMATION_STEP_S;
            let field = focus_snapshot(g, row, &opts.band, opts.method, tau)?;
            frames.push((tau, on_grid(&lattice.grid, &lattice.indices, &field)));
        }
        let frames = figures::focus_animation(
            dir,
            "focus_animation",
            &lattice.grid,
            &frames,
            &title,
            &overlay,
            ANIMATION_FRAME_MS,
        );
        animation = Some(drawn("focus_animation", frames)?);
    }
    if let Ok(p) = &parts.pixels
        && let Some(median) = p.median_area_cm2()
    {
        let values: Vec<f64> = p.area_cm2.iter().map(|a| a.unwrap_or(f64::NAN)).collect();
        let title = format!(
            "{label}: virtual-pixel area, median {median:.2} cm² ({} of {} points closed), 75 to 400 Hz, {}",
            p.area_cm2.iter().flatten().count(),
            p.area_cm2.len(),
            analysis.lattice_text(),
        );
        let measured = on_grid(&lattice.grid, &lattice.indices, &vec![0.0; lattice.indices.len()]);
        add(drawn(
            "pixel_area",
            figures::pixel_area_map(
                dir,
                "pixel_area",
                &lattice.grid,
                &on_grid(&lattice.grid, &lattice.indices, &values),
                &measured.iter().map(Option::is_some).collect::<Vec<_>>(),
                &title,
                &overlay,
            ),
        )?);
    }
    if let Ok(pod) = &report.pod {
        let points = pod.energy.iter().take(64).enumerate().map(|(i, &e)| ((i + 1) as f64, e)).collect();
        let label = format!("{label}: {} components for 99 %, {}", pod.components, analysis.lattice_text());
        add(drawn("pod_energy", figures::pod_energy(dir, "pod_energy", &[figures::Curve { label, points }]))?);
    }
    let domains: Vec<&DomainAuthority> = report.authority.iter().filter_map(|(_, a)| a.as_ref().ok()).collect();
    if !domains.is_empty() {
        let series: Vec<figures::SingularValueSeries> = domains
            .iter()
            .map(|a| {
                let (mean_db, std_db) = a.relative_energy_db_stats().into_iter().unzip();
                figures::SingularValueSeries {
                    label: format!("{label}, d = {} cm ({} points)", edge_key(a.edge_m), a.points.len()),
                    mean_db,
                    std_db,
                }
            })
            .collect();
        add(drawn("singular_value_energy", figures::singular_value_energy(dir, "singular_value_energy", &series))?);
    }
    if let Some(w) = condition_figure(dir, &[(label, analysis)])? {
        add(w);
    }
    if let Ok(r) = &report.driven_response {
        let points = r.freqs_hz.iter().copied().zip(r.mean_magnitude.iter().copied()).collect();
        let curves = [figures::Curve { label: label.to_owned(), points }];
        add(drawn("driven_response", figures::driven_response(dir, "driven_response", &curves))?);
    }
    written.extend(animation);
    Ok(written)
}

/// What the maps draw of `scene`: its outline, resonator rods, actuators and supports.
fn plate_overlay(scene: &Scene) -> figures::PlateOverlay {
    figures::PlateOverlay {
        actuators_m: scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect(),
        supports_m: scene.supports.iter().map(|p| (p.x_m, p.y_m)).collect(),
        outline_m: outline_polygon_m(&scene.plate.outline),
        // A lattice that cannot be laid (a scene that did not validate) is left undrawn rather than failing figures.
        resonator_sites_m: scene.resonators.lattice_sites_m(&scene.plate.outline).unwrap_or_default(),
        focus_m: None,
    }
}

/// The outline as a polygon, m: where rays from the centre at [`OUTLINE_VERTICES`] even angles (and through the
/// bounding box's corners, so a rectangle keeps its corners) cross the edge, found by bisection on the outline's
/// signed distance. Valid for both built-in shapes: convex and centred on the origin.
fn outline_polygon_m(outline: &Outline) -> Vec<(f64, f64)> {
    let (x_min, x_max, y_min, y_max) = outline.bounding_box_m();
    let reach = x_min.abs().max(x_max).hypot(y_min.abs().max(y_max));
    if !(reach.is_finite() && reach > 0.0) {
        return Vec::new();
    }
    let mut angles: Vec<f64> =
        (0..OUTLINE_VERTICES).map(|i| std::f64::consts::TAU * i as f64 / OUTLINE_VERTICES as f64).collect();
    angles.extend([(x_max, y_max), (x_min, y_max), (x_min, y_min), (x_max, y_min)].map(|(x, y)| {
        let a = f64::atan2(y, x);
        if a < 0.0 { a + std::f64::consts::TAU } else { a }
    }));
    angles.sort_by(f64::total_cmp);
    angles
        .iter()
        .map(|&a| {
            let (c, s) = (a.cos(), a.sin());
            let (mut inside, mut outside) = (0.0, reach);
            // 50 halvings of at most a few decimetres: far below a nanometre.
            for _ in 0..50 {
                let r = 0.5 * (inside + outside);
                if outline.distance_inside_m(r * c, r * s) >= 0.0 { inside = r } else { outside = r }
            }
            (inside * c, inside * s)
        })
        .collect()
}

/// Row of `g` nearest the frame origin (the plate centre); `indices[row]` is that row's index on `grid`.
fn centre_row(g: &PropagationMatrices, grid: &GridSpec, indices: &[u32]) -> Option<usize> {
    let dist = |p: u32| {
        let (x, y) = grid.position_m(p as usize);
        x * x + y * y
    };
    (0..g.n_points().min(indices.len())).min_by(|&a, &b| dist(indices[a]).total_cmp(&dist(indices[b])))
}

/// Per-point values laid on the grid, `None` where unmeasured or not finite.
fn on_grid(grid: &GridSpec, points: &[u32], values: &[f64]) -> Vec<Option<f64>> {
    let mut out = vec![None; grid.len()];
    for (&p, &v) in points.iter().zip(values) {
        if let Some(slot) = out.get_mut(p as usize) {
            *slot = v.is_finite().then_some(v);
        }
    }
    out
}

//! `metaplate analyze`: the paper's Wave Field Analysis on a dataset (wavelength, pixel area, POD, authority,
//! refresh, driven response), as one JSON object or a short table, and optionally its figures.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use metaplate_analysis::AnalysisError;
use metaplate_analysis::authority::DomainAuthority;
use metaplate_analysis::focus::focus_snapshot;
use metaplate_analysis::pixel::{PixelAreaMap, PixelAreaOptions, pixel_area_map};
use metaplate_analysis::report::{PlateReport, ReportOptions, analyse};
use metaplate_control::PropagationMatrices;
use metaplate_control::pixels::PointSelection;
use metaplate_core::grid::GridSpec;
use metaplate_core::scene::{Outline, Scene};
use metaplate_figures as figures;
use metaplate_store::Dataset;
use serde_json::{Value, json};

/// Band of the propagation matrices, Hz: the refresh pulse's skirts (50 Hz) up to the wavelength's 600 Hz.
const G_BAND_HZ: (f64, f64) = (50.0, 625.0);

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

/// Arguments of `metaplate analyze`.
#[derive(Args)]
pub struct AnalyzeArgs {
    /// Dataset directory (a scan or `metaplate simulate greens`).
    #[arg(long)]
    data: PathBuf,
    /// Print one JSON object on stdout instead of a table.
    #[arg(long)]
    json: bool,
    /// Write the figures (PNG and SVG) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
    /// Analyse only the points whose every row's estimated error (the dataset's `estimated_error_db`, from the
    /// spread of repetitions) is at most this, dB; the others are left out as if unmeasured (rows without an
    /// estimate are kept). Default: every point.
    #[arg(long, allow_hyphen_values = true)]
    max_error_db: Option<f64>,
}

/// Runs `metaplate analyze`.
pub fn run(args: &AnalyzeArgs) -> anyhow::Result<()> {
    let out = analyse_dataset(&args.data, args.figures.as_deref(), args.max_error_db)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_table(&out);
    }
    Ok(())
}

/// The whole analysis of the dataset in `data` as the JSON object `metaplate analyze --json` prints, with its
/// figures written into `figures` when given (their paths under the key `figures`). `metaplate demo` calls this too.
///
/// # Errors
/// An unreadable dataset, propagation matrices that cannot be built, a figure that cannot be written. An analysis
/// that fails on this dataset is not an error: it is listed under `errors` and its value is null.
pub fn analyse_dataset(data: &Path, figures: Option<&Path>, max_error_db: Option<f64>) -> anyhow::Result<Value> {
    let dataset = Dataset::open(data).with_context(|| format!("opening dataset {}", data.display()))?;
    let grid = dataset.manifest().meta.grid;
    let selection = max_error_db.map(|db| PointSelection::by_estimated_error(&dataset, db)).transpose()?;
    let kept = selection.as_ref().map(|s| s.kept.as_slice());
    let g = PropagationMatrices::from_dataset(&dataset, G_BAND_HZ, kept).context("building G(omega)")?;
    let report = analyse(&g, &grid, &ReportOptions::default())?;
    let mut mask = vec![false; grid.len()];
    for &p in g.points() {
        if let Some(m) = mask.get_mut(p as usize) {
            *m = true;
        }
    }
    let pixels = pixel_area_map(&g, &grid, &mask, &PixelAreaOptions::default());
    let mut out = to_json(&report, pixels.as_ref());
    // The analytic A0 wavelength of the scene's (host) plate, where the dataset's scene is a built-in one.
    let scene_id = &dataset.manifest().meta.scene;
    let scene = Scene::builtin(&scene_id.name).ok().filter(|s| s.id().hash == scene_id.hash);
    if let (Some(scene), Some(rows)) = (&scene, out["wavelength"].as_array_mut()) {
        for row in rows {
            let a0 = row["freq_hz"].as_f64().and_then(|f| scene.plate.a0_wavelength_m(f).ok());
            row["a0_wavelength_m"] = json!(a0);
        }
    }
    out["dataset"] = json!(data.display().to_string());
    out["scene"] = json!(dataset.manifest().meta.scene.name);
    out["points"] = json!(g.n_points());
    if let Some(s) = &selection {
        out["excluded_points"] = json!({
            "max_error_db": s.max_error_db,
            "excluded": s.excluded.iter().map(|(p, e)| json!({ "point_index": p, "estimated_error_db": e })).collect::<Vec<_>>(),
            "kept_without_estimate": s.without_estimate,
        });
    }
    out["actuators"] = json!(g.n_actuators());
    if let Some(dir) = figures {
        let overlay = scene.as_ref().map_or_else(figures::PlateOverlay::default, plate_overlay);
        let written = write_figures(dir, &scene_id.name, &g, &report, pixels.as_ref(), &out, &overlay)?;
        out["figures"] = json!(written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>());
    }
    Ok(out)
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

/// Domain edge as the JSON key, in cm with one decimal ("9.5").
fn edge_key(edge_m: f64) -> String {
    format!("{:.1}", edge_m * 100.0)
}

fn to_json(report: &PlateReport, pixels: Result<&PixelAreaMap, &AnalysisError>) -> Value {
    let mut errors = serde_json::Map::new();
    let mut keep = |key: String, e: &AnalysisError| {
        errors.insert(key, json!(e.to_string()));
    };
    let wavelength: Vec<Value> = report
        .wavelength
        .iter()
        .map(|w| match &w.summary {
            Ok(s) => json!({"freq_hz": w.freq_hz, "median_m": s.median_m, "iqr_m": [s.iqr_m.0, s.iqr_m.1],
                "in_range": w.in_range, "actuators_flagged": s.flagged}),
            Err(e) => json!({"freq_hz": w.freq_hz, "median_m": null, "iqr_m": null, "in_range": false,
                "error": e.to_string()}),
        })
        .collect();
    let (mut rank, mut kappa, mut domain_points) =
        (serde_json::Map::new(), serde_json::Map::new(), serde_json::Map::new());
    for (edge_m, a) in &report.authority {
        let key = edge_key(*edge_m);
        match a {
            Ok(a) => {
                domain_points.insert(key.clone(), json!(a.points.len()));
                rank.insert(key.clone(), json!(a.mean_effective_rank()));
                kappa.insert(key, json!(a.mean_condition_number()));
            }
            Err(e) => {
                keep(format!("authority {key} cm"), e);
                rank.insert(key.clone(), Value::Null);
                kappa.insert(key, Value::Null);
            }
        }
    }
    let pod = report.pod.as_ref().map_err(|e| keep("pod".into(), e)).ok();
    let refresh = report.refresh.as_ref().map_err(|e| keep("refresh".into(), e)).ok();
    let response = report.driven_response.as_ref().map_err(|e| keep("driven_response".into(), e)).ok();
    let pixels = pixels.map_err(|e| keep("pixel_area".into(), e)).ok();
    let (lattice, range) = (&report.lattice, &report.resolvable);
    json!({
        "lattice": {
            "nx": lattice.grid.nx,
            "ny": lattice.grid.ny,
            "spacing_m": range.spacing_m,
            "stride": lattice.stride,
            "fill": range.fill,
        },
        "wavelength_resolvable": {
            "nyquist_k_rad_m": range.nyquist_k_rad_m,
            "shortest_m": range.shortest_wavelength_m,
            "aperture_m": range.aperture_m,
            "longest_m": range.longest_wavelength_m,
            "note": "k-space estimates outside [shortest_m, longest_m], or on a lattice filled below 50 %, have \
                     in_range false: the lattice aliases shorter waves, the aperture biases longer ones short",
        },
        "wavelength": wavelength,
        "median_pixel_area_cm2": pixels.and_then(PixelAreaMap::median_area_cm2),
        "pixel_area_flagged_fraction": pixels.map(PixelAreaMap::flagged_fraction),
        "pod_components_99": pod.map(|p| p.components),
        "pod_energy": pod.map(|p| p.energy.iter().take(64).collect::<Vec<_>>()),
        "effective_rank": rank,
        "condition_number": kappa,
        "points_per_domain": domain_points,
        "refresh_ms": refresh.map(|r| r.refresh_s * 1e3),
        "driven_response": response.map(|r| r.freqs_hz.iter().zip(&r.mean_magnitude)
            .map(|(f, m)| json!({"freq_hz": f, "mean_abs": m})).collect::<Vec<_>>()),
        "errors": errors,
    })
}

fn print_table(out: &Value) {
    let show = |v: &Value| v.as_f64().map_or_else(|| "-".to_owned(), |x| format!("{x:.2}"));
    println!("dataset {} ({}, {} points)", out["dataset"], out["scene"], out["points"]);
    let lattice = &out["lattice"];
    let range = &out["wavelength_resolvable"];
    let cm = |v: &Value| v.as_f64().map_or_else(|| "-".to_owned(), |x| format!("{:.1}", x * 100.0));
    println!(
        "lattice {} x {} at {} cm (every {} grid point(s), {:.0} % filled): wavelengths {} to {} cm resolvable",
        lattice["nx"],
        lattice["ny"],
        cm(&lattice["spacing_m"]),
        lattice["stride"],
        lattice["fill"].as_f64().unwrap_or(f64::NAN) * 100.0,
        cm(&range["shortest_m"]),
        cm(&range["longest_m"]),
    );
    println!("median pixel area (cm^2)   {}", show(&out["median_pixel_area_cm2"]));
    println!("POD components (99 %)      {}", out["pod_components_99"]);
    for key in ["9.5", "6.5", "3.5"] {
        println!(
            "d = {key} cm ({} points): effective rank {}, condition number {}",
            out["points_per_domain"][key],
            show(&out["effective_rank"][key]),
            show(&out["condition_number"][key])
        );
    }
    println!("refresh (ms)               {}", show(&out["refresh_ms"]));
    for w in out["wavelength"].as_array().into_iter().flatten() {
        let outside = if w["in_range"] == true { "" } else { "  (outside the resolvable range)" };
        println!("wavelength at {:>5} Hz: {} cm{outside}", w["freq_hz"], cm(&w["median_m"]));
    }
    if let Some(errors) = out["errors"].as_object() {
        for (k, e) in errors {
            println!("not computed: {k}: {e}");
        }
    }
}

/// The paper's measured wavelengths (Fig. 4A, metamaterial): 11.3 cm at 75 Hz and 2.5 cm at 600 Hz, (Hz, m).
const PAPER_WAVELENGTHS: [(f64, f64); 2] = [(75.0, 0.113), (600.0, 0.025)];

/// The paper's mean condition numbers (Fig. 6C) against domain edge, (cm, kappa): metamaterial, homogeneous.
const PAPER_CONDITION_NUMBERS: [[(f64, f64); 3]; 2] =
    [[(9.5, 5.0), (6.5, 10.1), (3.5, 35.9)], [(9.5, 51.5), (6.5, 110.6), (3.5, 236.0)]];

/// "25 x 13 lattice at 1 cm" from an analysis's JSON.
fn lattice_text(analysis: &Value) -> String {
    let l = &analysis["lattice"];
    format!("{} x {} lattice at {:.1} cm", l["nx"], l["ny"], l["spacing_m"].as_f64().unwrap_or(f64::NAN) * 100.0)
}

/// One plate's wavelengths from its analysis's JSON, as the figure takes them (frequencies without an estimate
/// left out).
fn wavelength_series(label: &str, analysis: &Value) -> figures::WavelengthSeries {
    let rows: Vec<&Value> =
        analysis["wavelength"].as_array().into_iter().flatten().filter(|w| w["median_m"].is_f64()).collect();
    let num = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    figures::WavelengthSeries {
        label: label.to_owned(),
        freqs_hz: rows.iter().map(|w| num(&w["freq_hz"])).collect(),
        median_m: rows.iter().map(|w| num(&w["median_m"])).collect(),
        iqr_m: rows.iter().map(|w| (num(&w["iqr_m"][0]), num(&w["iqr_m"][1]))).collect(),
        in_range: rows.iter().map(|w| w["in_range"] == true).collect(),
    }
}

/// The references of a wavelength figure: the analytic A0 (from the first analysis that has it), the paper's
/// measured end points, the resolvable range of the first analysis's lattice.
fn wavelength_references(analyses: &[&Value], with_paper: bool) -> figures::WavelengthReferences {
    let a0: Vec<(f64, f64)> = analyses
        .iter()
        .map(|a| {
            a["wavelength"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|w| Some((w["freq_hz"].as_f64()?, w["a0_wavelength_m"].as_f64()?)))
                .collect::<Vec<_>>()
        })
        .find(|points| !points.is_empty())
        .unwrap_or_default();
    let range = &analyses.first().map_or(&Value::Null, |a| &a["wavelength_resolvable"]);
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
        resolvable_m: range["shortest_m"].as_f64().zip(range["longest_m"].as_f64()),
    }
}

/// Title of a wavelength figure.
fn wavelength_title(analysis: &Value) -> String {
    format!(
        "Wavelength (k-space, median and IQR), {}; hollow: outside {:.0} to {:.1} cm",
        lattice_text(analysis),
        analysis["wavelength_resolvable"]["shortest_m"].as_f64().unwrap_or(f64::NAN) * 100.0,
        analysis["wavelength_resolvable"]["longest_m"].as_f64().unwrap_or(f64::NAN) * 100.0,
    )
}

/// Figures comparing plates on shared axes, from their analyses (`(label, analyze's JSON)`, metamaterial first):
/// the wavelengths with the analytic A0 and the paper's measured points, and the condition numbers against domain
/// edge with the paper's values. `metaplate demo` calls this after analysing both plates.
///
/// # Errors
/// A figure that cannot be drawn or written.
pub fn write_comparison_figures(dir: &Path, analyses: &[(&str, &Value)]) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let Some((_, first)) = analyses.first() else { return Ok(written) };
    let series: Vec<_> = analyses.iter().map(|(label, a)| wavelength_series(label, a)).collect();
    let all: Vec<&Value> = analyses.iter().map(|(_, a)| *a).collect();
    if series.iter().any(|s| !s.freqs_hz.is_empty()) {
        let w = figures::wavelength(
            dir,
            "wavelength",
            &wavelength_title(first),
            &series,
            &wavelength_references(&all, true),
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
fn condition_figure(dir: &Path, analyses: &[(&str, &Value)]) -> anyhow::Result<Option<figures::Written>> {
    let Some((_, first)) = analyses.first() else { return Ok(None) };
    let curves: Vec<figures::Curve> = analyses
        .iter()
        .map(|(label, a)| figures::Curve {
            label: format!("{label} ({})", domain_points_text(a)),
            points: ["9.5", "6.5", "3.5"]
                .iter()
                .filter_map(|k| Some((k.parse::<f64>().ok()?, a["condition_number"][*k].as_f64()?)))
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
    let title = format!("Mean condition number of G_D, 75 to 400 Hz, {}", lattice_text(first));
    Ok(Some(figures::condition_numbers(dir, "condition_numbers", &title, &curves, &marks)?))
}

/// "81 / 49 / 9 points per domain" from an analysis's JSON.
fn domain_points_text(analysis: &Value) -> String {
    let n = |k: &str| analysis["points_per_domain"][k].as_u64().map_or_else(|| "-".to_owned(), |n| n.to_string());
    format!("{} / {} / {} points", n("9.5"), n("6.5"), n("3.5"))
}

/// Writes every figure of one plate; returns the files written. Maps are drawn on the points' own lattice (a
/// regular subset fills its cells; no holes between them).
fn write_figures(
    dir: &Path,
    label: &str,
    g: &PropagationMatrices,
    report: &PlateReport,
    pixels: Result<&PixelAreaMap, &AnalysisError>,
    analysis: &Value,
    overlay: &figures::PlateOverlay,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    // The animation is one file (APNG, no SVG): kept apart and listed after the maps.
    let mut animation = None;
    let mut add = |w: figures::Written| written.extend([w.png, w.svg]);
    let lattice = &report.lattice;
    let series = wavelength_series(label, analysis);
    if !series.freqs_hz.is_empty() {
        let references = wavelength_references(&[analysis], label == "metamaterial");
        add(figures::wavelength(dir, "wavelength", &wavelength_title(analysis), &[series], &references)?);
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
            lattice_text(analysis),
        );
        let overlay = figures::PlateOverlay { focus_m: Some((x, y)), ..overlay.clone() };
        add(figures::focus_snapshots(dir, "focus_snapshots", &lattice.grid, &snaps, &title, &overlay)?);
        let mut frames = Vec::new();
        for step in -(ANIMATION_FRAMES / 2)..=ANIMATION_FRAMES / 2 {
            let tau = f64::from(step) * ANIMATION_STEP_S;
            let field = focus_snapshot(g, row, &opts.band, opts.method, tau)?;
            frames.push((tau, on_grid(&lattice.grid, &lattice.indices, &field)));
        }
        animation = Some(figures::focus_animation(
            dir,
            "focus_animation",
            &lattice.grid,
            &frames,
            &title,
            &overlay,
            ANIMATION_FRAME_MS,
        )?);
    }
    if let Ok(p) = pixels
        && let Some(median) = p.median_area_cm2()
    {
        let values: Vec<f64> = p.area_cm2.iter().map(|a| a.unwrap_or(f64::NAN)).collect();
        let title = format!(
            "{label}: virtual-pixel area, median {median:.2} cm² ({} of {} points closed), 75 to 400 Hz, {}",
            p.area_cm2.iter().flatten().count(),
            p.area_cm2.len(),
            lattice_text(analysis),
        );
        let measured = on_grid(&lattice.grid, &lattice.indices, &vec![0.0; lattice.indices.len()]);
        add(figures::pixel_area_map(
            dir,
            "pixel_area",
            &lattice.grid,
            &on_grid(&lattice.grid, &lattice.indices, &values),
            &measured.iter().map(Option::is_some).collect::<Vec<_>>(),
            &title,
            overlay,
        )?);
    }
    if let Ok(pod) = &report.pod {
        let points = pod.energy.iter().take(64).enumerate().map(|(i, &e)| ((i + 1) as f64, e)).collect();
        let label = format!("{label}: {} components for 99 %, {}", pod.components, lattice_text(analysis));
        add(figures::pod_energy(dir, "pod_energy", &[figures::Curve { label, points }])?);
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
        add(figures::singular_value_energy(dir, "singular_value_energy", &series)?);
    }
    if let Some(w) = condition_figure(dir, &[(label, analysis)])? {
        add(w);
    }
    if let Ok(r) = &report.driven_response {
        let points = r.freqs_hz.iter().copied().zip(r.mean_magnitude.iter().copied()).collect();
        add(figures::driven_response(dir, "driven_response", &[figures::Curve { label: label.to_owned(), points }])?);
    }
    written.extend(animation);
    Ok(written)
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

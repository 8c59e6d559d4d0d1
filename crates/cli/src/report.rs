//! `metaplate report`: one self-contained HTML file on analysed scan datasets (one plate, or the pair of built-in
//! plates): the paper-against-suite table, the figures with captions, each measurement's summary (protocol,
//! points, statuses, status and SNR maps, the error against the truth on the mock lab) and its provenance (scene,
//! configuration hash, calibration, software version).
//!
//! Self-contained: figures are embedded as PNG data URIs, the grid maps as inline SVG, the style inline; there is
//! no script and nothing is fetched, so the file opens offline and can be mailed or archived as it is.
//!
//! The page is built from the same summary the demo writes (`summary.json`, see [`crate::paper_table`]), so the
//! demo's report and `metaplate report` on the demo's datasets say the same.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use base64::Engine as _;
use clap::Args;
use metaplate_core::scene::Scene;
use metaplate_dsp::stats::quantile;
use metaplate_figures::{snr_map_svg, status_map_svg};
use metaplate_monitor::cells::{SNR_SCALE_DB, grid_cells, planned_points};
use metaplate_recipes::Calibration;
use metaplate_store::Dataset;
use serde_json::{Value, json};

use crate::cache::CacheArgs;
use crate::{analyze, paper_table, progress, truth};

/// Width of each grid map on the page, px.
const MAP_WIDTH_PX: usize = 480;

/// Arguments of `metaplate report`.
#[derive(Args)]
pub struct ReportArgs {
    /// Scan dataset directories: one per plate (for both built-in plates, the pair side by side).
    #[arg(required = true)]
    datasets: Vec<PathBuf>,
    /// The HTML file to write (its directory must exist; an earlier file is replaced).
    #[arg(long, default_value = "report.html")]
    out: PathBuf,
    /// Calibration directories the scans were compensated with, any order (each is matched to its scans by content
    /// hash); needed to compare a calibrated scan with the ground truth.
    #[arg(long)]
    calibration: Vec<PathBuf>,
    /// Scene files of scans on scenes that are not built in (matched by hash), for the ground truth.
    #[arg(long)]
    scene: Vec<PathBuf>,
    /// Skip the comparison with the simulated plate's ground truth (its Green's functions take minutes to compute
    /// when they are not cached).
    #[arg(long)]
    no_truth: bool,
    #[command(flatten)]
    cache: CacheArgs,
}

/// Runs `metaplate report`.
pub fn run(args: &ReportArgs) -> anyhow::Result<()> {
    let scenes: Vec<Scene> = args
        .scene
        .iter()
        .map(|p| Scene::load(p).with_context(|| format!("reading scene {}", p.display())))
        .collect::<anyhow::Result<_>>()?;
    let calibrations = args.calibration.as_slice();
    // Figures are drawn into a scratch directory and embedded; it is removed when the report is written.
    let scratch = tempfile::tempdir().context("creating a scratch directory for the figures")?;
    let mut plates = serde_json::Map::new();
    for data in &args.datasets {
        let dataset = Dataset::open(data).with_context(|| format!("opening dataset {}", data.display()))?;
        let name = dataset.manifest().meta.scene.name.clone();
        if plates.contains_key(&name) {
            bail!("two datasets of the scene `{name}`: a report holds one dataset per plate (write one report each)");
        }
        let spinner = progress::spinner(format!("[{name}] analyses and figures"));
        let analysis = analyze::analyse_dataset(data, Some(&scratch.path().join(&name)), None)?;
        spinner.finish_and_clear();
        let scene = find_scene(&dataset, &scenes);
        let truth = if args.no_truth {
            Err("not compared (--no-truth)".to_owned())
        } else {
            let spinner = progress::spinner(format!("[{name}] measured against the ground truth"));
            let errors = truth_errors(&dataset, scene.as_ref(), calibrations, args.cache.dir().as_deref());
            spinner.finish_and_clear();
            errors?
        };
        let mut scan = measurement_json(data, &dataset);
        match truth {
            Ok(errors) => scan["greens_error_db"] = truth::errors_json(&errors),
            Err(why) => scan["greens_error_db_missing"] = json!(why),
        }
        plates.insert(name, json!({"analysis": analysis, "scan": scan}));
    }
    let mut summary = json!({"plates": plates});
    let pair: Vec<(&str, &Value)> =
        paper_table::PLATES.iter().filter_map(|p| Some((*p, summary["plates"].get(*p)?.get("analysis")?))).collect();
    if pair.len() == 2 {
        let written = analyze::write_comparison_figures(&scratch.path().join("figures"), &pair)?;
        summary["comparison_figures"] = json!(written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>());
    }
    write(&args.out, &summary)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The scene of a dataset when the suite can simulate it: a built-in one, or one of `scenes`, with the same hash.
fn find_scene(dataset: &Dataset, scenes: &[Scene]) -> Option<Scene> {
    let id = &dataset.manifest().meta.scene;
    let builtin = Scene::builtin(&id.name).ok().filter(|s| s.id().hash == id.hash);
    builtin.or_else(|| scenes.iter().find(|s| s.id().hash == id.hash).cloned())
}

/// The errors of the dataset's rows against the truth (`Ok(Ok)`), or why they are not compared (`Ok(Err)`): no
/// simulated scene, or a calibrated scan whose calibration is not among `calibrations`.
fn truth_errors(
    dataset: &Dataset,
    scene: Option<&Scene>,
    calibrations: &[PathBuf],
    cache_dir: Option<&Path>,
) -> anyhow::Result<Result<Vec<f64>, String>> {
    let Some(scene) = scene else {
        return Ok(Err("no ground truth: the scene is neither built in nor given with --scene".to_owned()));
    };
    let filters = match dataset.manifest().meta.config.get("calibration").and_then(Value::as_str) {
        None => None,
        Some(hash) => {
            let mut found = None;
            for dir in calibrations {
                let calibration = Calibration::load(dir, scene.actuators.len())
                    .with_context(|| format!("reading calibration {}", dir.display()))?;
                if calibration.content_hash == hash {
                    found = Some(calibration);
                    break;
                }
            }
            let Some(calibration) = found else {
                return Ok(Err(format!(
                    "calibrated scan ({hash}): pass its --calibration DIR to compare with the truth"
                )));
            };
            Some(calibration.filters)
        }
    };
    Ok(Ok(truth::dataset_errors(scene, dataset, filters.as_deref(), cache_dir)?))
}

/// What the demo's summary says of a scan, read back from the dataset: its directory, points committed and
/// planned, row counts by status, and the span of the rows' timestamps (wall clock: on the mock lab, fast-forward,
/// this is how long the simulation took, not the rig time it simulated).
fn measurement_json(dir: &Path, dataset: &Dataset) -> Value {
    let mut statuses: BTreeMap<&str, usize> = BTreeMap::new();
    let mut times_us = (i64::MAX, i64::MIN);
    for meta in dataset.rows() {
        if let Some(status) = meta.status {
            *statuses.entry(status.as_str()).or_default() += 1;
        }
        if let Some(t) = meta.measured_at_unix_us {
            times_us = (times_us.0.min(t), times_us.1.max(t));
        }
    }
    let planned = dataset.manifest().meta.config.get("points").and_then(Value::as_array).map(Vec::len);
    let span_h = (times_us.1 >= times_us.0).then(|| (times_us.1 - times_us.0) as f64 / 3.6e9);
    json!({
        "dir": dir.display().to_string(),
        "points": dataset.points().len(),
        "total": planned,
        "statuses": statuses,
        "measured_span_hours": span_h,
    })
}

/// Writes the report page for `summary` (the demo's shape: see [`crate::paper_table`]) to `path`, reading each
/// plate's dataset (`plates.<name>.scan.dir`) for its maps and provenance and embedding the PNG figures listed in
/// `plates.<name>.analysis.figures` and `comparison_figures`.
///
/// # Errors
/// A dataset or figure that cannot be read, or the file that cannot be written.
pub fn write(path: &Path, summary: &Value) -> anyhow::Result<()> {
    let mut page = String::new();
    let names: Vec<&String> = summary["plates"].as_object().map(|m| m.keys().collect()).unwrap_or_default();
    // Built-in plates in the table's order, then any other.
    let mut ordered: Vec<&str> = paper_table::PLATES.iter().copied().filter(|p| names.iter().any(|n| n == p)).collect();
    ordered.extend(names.iter().map(|n| n.as_str()).filter(|n| !paper_table::PLATES.contains(n)));
    let title = format!("metaplate report: {}", ordered.join(" and "));
    let _ = write!(
        page,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{}</title><style>{STYLE}</style>\
         </head><body><h1>{}</h1><p class=\"meta\">Written {} by metaplate {}.</p>",
        escape(&title),
        escape(&title),
        chrono::Utc::now().format("%Y-%m-%d %H:%M UTC"),
        env!("CARGO_PKG_VERSION"),
    );
    if ordered.iter().any(|p| paper_table::PLATES.contains(p)) {
        table_section(&mut page, summary);
    }
    if let Some(figures) = summary["comparison_figures"].as_array() {
        page.push_str("<section><h2>Both plates</h2><div class=\"figures\">");
        for f in figures.iter().filter_map(Value::as_str) {
            figure(&mut page, Path::new(f))?;
        }
        page.push_str("</div></section>");
    }
    for name in &ordered {
        plate_section(&mut page, name, &summary["plates"][*name])?;
    }
    page.push_str("</body></html>\n");
    fs::write(path, page).with_context(|| format!("writing {}", path.display()))
}

fn table_section(page: &mut String, summary: &Value) {
    let _ = write!(
        page,
        "<section><h2>Paper against suite</h2><table><thead><tr><th>quantity</th><th>paper</th>\
         <th>metaplate ({})</th></tr></thead><tbody>",
        escape(&paper_table::columns(summary))
    );
    for row in paper_table::rows(summary) {
        let _ = write!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&row.quantity),
            escape(&row.paper),
            escape(&row.suite)
        );
    }
    page.push_str(
        "</tbody></table><p class=\"note\">Wavelengths by the plate model (where the demo ran it); the rest on the \
         scanned datasets. Authority and condition numbers name their lattice and points per domain: compare like \
         with like.</p></section>",
    );
}

fn plate_section(page: &mut String, name: &str, plate: &Value) -> anyhow::Result<()> {
    let _ = write!(page, "<section><h2>Plate: {}</h2>", escape(name));
    let scan = &plate["scan"];
    let dataset = match scan["dir"].as_str() {
        Some(dir) => Some(Dataset::open(dir).with_context(|| format!("opening dataset {dir}"))?),
        None => None,
    };
    page.push_str("<h3>Measurement</h3><table class=\"kv\">");
    let meta = dataset.as_ref().map(|d| &d.manifest().meta);
    let protocol = meta.and_then(|m| m.config.get("protocol")?.get("name")?.as_str().map(str::to_owned));
    kv(page, "protocol", protocol.as_deref().unwrap_or("-"));
    let total = scan["total"].as_u64().map_or_else(String::new, |t| format!(" of {t} planned"));
    kv(page, "points committed", &format!("{}{total}", scan["points"]));
    let statuses = scan["statuses"]
        .as_object()
        .map(|m| m.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "))
        .unwrap_or_default();
    kv(page, "rows by status", &statuses);
    if let Some(h) = scan["simulated_hours"].as_f64() {
        kv(page, "measurement time (rig clock, simulated)", &duration_text(h * 3600.0));
    }
    if let Some(h) = scan["measured_span_hours"].as_f64() {
        kv(page, "first to last row (wall clock)", &duration_text(h * 3600.0));
    }
    if let Some(d) = &dataset {
        let mut snr: Vec<f64> = d.rows().iter().filter_map(|m| m.snr_db).filter(|v| v.is_finite()).collect();
        if let (Some(lo), Some(mid)) = (quantile(&mut snr, 0.0), quantile(&mut snr, 0.5)) {
            kv(page, "SNR over rows", &format!("median {mid:.1} dB, lowest {lo:.1} dB"));
        }
    }
    let e = &scan["greens_error_db"];
    let truth_text = match (e["median"].as_f64(), e["p95"].as_f64(), e["worst"].as_f64()) {
        (Some(m), Some(p), Some(w)) => format!(
            "median {m:.1} dB, p95 {p:.1} dB, worst {w:.1} dB over {} rows, {}..{} Hz",
            e["rows"], e["band_hz"][0], e["band_hz"][1]
        ),
        _ => scan["greens_error_db_missing"].as_str().unwrap_or("-").to_owned(),
    };
    kv(page, "Green's functions against the truth", &truth_text);
    page.push_str("</table>");
    if let Some(d) = &dataset {
        let grid = d.manifest().meta.grid;
        let (states, snr) = grid_cells(&grid, &planned_points(&d.manifest().meta.config), d.rows());
        let _ = write!(
            page,
            "<div class=\"maps\"><figure>{}<figcaption>Grid points by status (worst over the actuators).</figcaption>\
             </figure><figure>{}<figcaption>SNR per point, the lowest over the actuators, on a fixed {}..{} dB \
             scale.</figcaption></figure></div>",
            status_map_svg(grid.nx, grid.ny, &states, MAP_WIDTH_PX),
            snr_map_svg(grid.nx, grid.ny, &snr, SNR_SCALE_DB, MAP_WIDTH_PX),
            SNR_SCALE_DB.0,
            SNR_SCALE_DB.1,
        );
        provenance(page, d, plate);
    }
    page.push_str("<h3>Figures</h3><div class=\"figures\">");
    if let Some(figures) = plate["analysis"]["figures"].as_array() {
        for f in figures.iter().filter_map(Value::as_str) {
            figure(page, Path::new(f))?;
        }
    }
    page.push_str("</div></section>");
    Ok(())
}

fn provenance(page: &mut String, dataset: &Dataset, plate: &Value) {
    let manifest = dataset.manifest();
    let meta = &manifest.meta;
    page.push_str("<h3>Provenance</h3><table class=\"kv\">");
    kv(page, "dataset", plate["scan"]["dir"].as_str().unwrap_or("-"));
    kv(page, "scene", &format!("{} ({})", meta.scene.name, meta.scene.hash));
    kv(page, "recipe", &meta.recipe);
    kv(page, "configuration hash", &manifest.config_hash);
    let calibration = meta.config.get("calibration").and_then(Value::as_str).unwrap_or("none (uncompensated drives)");
    let calibration_dir = plate["calibration"]["dir"].as_str().map_or_else(String::new, |d| format!(", {d}"));
    kv(page, "calibration", &format!("{calibration}{calibration_dir}"));
    kv(page, "seed", &meta.seed.to_string());
    kv(page, "created", &manifest.created_at);
    kv(page, "measured with", &format!("metaplate {}", meta.software_version));
    page.push_str("</table>");
}

/// One PNG figure embedded as a data URI, with its caption; other files (the SVG twins) are skipped.
fn figure(page: &mut String, path: &Path) -> anyhow::Result<()> {
    if path.extension().and_then(|e| e.to_str()) != Some("png") {
        return Ok(());
    }
    let bytes = fs::read(path).with_context(|| format!("reading figure {}", path.display()))?;
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    // A figure more than twice as wide as high (a row of maps) takes the page's width rather than half of it.
    let wide = png_size(&bytes).is_some_and(|(w, h)| w > 2 * h);
    let _ = write!(
        page,
        "<figure{}><img alt=\"{}\" src=\"data:image/png;base64,{}\"><figcaption>{}</figcaption></figure>",
        if wide { " class=\"wide\"" } else { "" },
        escape(stem),
        base64::engine::general_purpose::STANDARD.encode(bytes),
        escape(caption(stem)),
    );
    Ok(())
}

/// Width and height of a PNG from its header (the IHDR chunk leads every PNG), px; `None` for anything else.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    let signature: &[u8] = b"\x89PNG\r\n\x1a\n";
    if bytes.get(..8)? != signature || bytes.get(12..16)? != b"IHDR" {
        return None;
    }
    let word = |at: usize| Some(u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    Some((word(16)?, word(20)?))
}

/// What each figure shows, for a reader who has not read the paper (its title carries the numbers).
fn caption(stem: &str) -> &'static str {
    match stem {
        "wavelength" => {
            "Flexural wavelength against frequency by the paper's k-space method (median over the actuators with \
             the interquartile range). Hollow markers fall outside what the lattice resolves (dotted lines)."
        }
        "focus_snapshots" => {
            "The wave field around the focus time when an impulse is focused at the plate's centre (time reversal \
             on the measured Green's functions); the focus's half-maximum region is outlined."
        }
        "focus_animation" => "The focusing in time (the paper's Fig. 5A), as an animation.",
        "pixel_area" => {
            "Virtual-pixel area: at each point, the area inside the half-maximum contour when focusing there."
        }
        "pod_energy" => {
            "Proper orthogonal decomposition of the field: cumulative energy against the number of components."
        }
        "singular_value_energy" => {
            "Cumulative energy of the singular values of the propagation matrix per domain size."
        }
        "condition_numbers" => {
            "Mean condition number of the propagation matrix on square domains against their size, with the \
             paper's values."
        }
        "driven_response" => "The plate's response to each actuator, averaged over the measured points.",
        _ => "",
    }
}

/// A duration in the unit a reader expects: seconds, minutes or hours.
fn duration_text(seconds: f64) -> String {
    if seconds < 120.0 {
        format!("{seconds:.0} s")
    } else if seconds < 7200.0 {
        format!("{:.1} min", seconds / 60.0)
    } else {
        format!("{:.2} h", seconds / 3600.0)
    }
}

fn kv(page: &mut String, key: &str, value: &str) {
    let _ = write!(page, "<tr><th>{}</th><td>{}</td></tr>", escape(key), escape(value));
}

/// Text for HTML element content and attribute values.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The page's style: system fonts only, readable printed.
const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:2em auto;max-width:1100px;\
color:#222;padding:0 1em}h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}\
.meta,.note,figcaption{color:#555;font-size:.9em}table{border-collapse:collapse;margin:.5em 0}\
td,th{border:1px solid #ddd;padding:.3em .6em;text-align:left;vertical-align:top}thead th{background:#f3f3f3}\
table.kv th{background:#f8f8f8;font-weight:600;white-space:nowrap}.figures,.maps{display:flex;flex-wrap:wrap;\
gap:1em}figure{margin:0;flex:1 1 480px;max-width:100%}figure.wide{flex-basis:100%}figure img{max-width:100%;height:auto;border:1px solid #eee}\
@media print{section{break-inside:avoid-page}}";

#[cfg(test)]
mod tests {
    use super::{escape, png_size};

    #[test]
    fn png_size_reads_the_header_and_refuses_anything_else() {
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        png.extend(1200_u32.to_be_bytes());
        png.extend(400_u32.to_be_bytes());
        assert_eq!(png_size(&png), Some((1200, 400)));
        assert_eq!(png_size(&png[..20]), None, "truncated");
        assert_eq!(png_size(b"GIF89a and more bytes than a header"), None);
        assert_eq!(png_size(&[]), None);
    }

    #[test]
    fn escape_leaves_no_markup() {
        assert_eq!(escape(r#"<a href="x">&'"#), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
        assert_eq!(escape("plain 3.2 cm"), "plain 3.2 cm");
    }
}

//! The report's HTML: the page, its sections and its style.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use base64::Engine as _;
use metaplate_analysis::paper_table::{PLATES, PlateResults, columns, paper_rows};
use metaplate_dsp::stats::quantile;
use metaplate_figures::{snr_map_svg, status_map_svg};
use metaplate_recipes::cells::{SNR_SCALE_DB, grid_cells, planned_points};
use metaplate_recipes::progress::duration_text;
use metaplate_store::Dataset;
use serde_json::Value;

use super::ReportPlate;
use crate::error::{EvaluationError, StepExt, io_error};

/// Width of each grid map on the page, px.
const MAP_WIDTH_PX: usize = 480;

/// Writes the report page on `plates` to `path`, reading each plate's dataset for its maps and provenance and
/// embedding the PNG figures of each analysis and `comparison_figures` (a section of its own when given).
///
/// # Errors
/// A dataset or figure that cannot be read, or the file that cannot be written.
pub fn write_report(
    path: &Path,
    plates: &[ReportPlate<'_>],
    comparison_figures: Option<&[String]>,
) -> Result<(), EvaluationError> {
    let mut page = String::new();
    // Built-in plates in the table's order, then any other by name.
    let mut ordered: Vec<&ReportPlate<'_>> =
        PLATES.iter().filter_map(|name| plates.iter().find(|p| p.name == *name)).collect();
    let mut others: Vec<&ReportPlate<'_>> = plates.iter().filter(|p| !PLATES.contains(&p.name)).collect();
    others.sort_by_key(|p| p.name);
    ordered.extend(others);
    let names: Vec<&str> = ordered.iter().map(|p| p.name).collect();
    let title = format!("metaplate report: {}", names.join(" and "));
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
    if names.iter().any(|p| PLATES.contains(p)) {
        table_section(&mut page, plates);
    }
    if let Some(figures) = comparison_figures {
        page.push_str("<section><h2>Both plates</h2><div class=\"figures\">");
        for f in figures {
            figure(&mut page, Path::new(f))?;
        }
        page.push_str("</div></section>");
    }
    for plate in &ordered {
        plate_section(&mut page, plate)?;
    }
    page.push_str("</body></html>\n");
    fs::write(path, page).map_err(io_error("writing", path))
}

fn table_section(page: &mut String, plates: &[ReportPlate<'_>]) {
    let results: Vec<PlateResults<'_>> = plates
        .iter()
        .map(|p| PlateResults {
            name: p.name,
            analysis: Some(p.analysis),
            model_wavelengths: p.model_wavelengths,
            pattern_peak_velocity_m_s: p.pattern_peak_velocity_m_s,
        })
        .collect();
    let _ = write!(
        page,
        "<section><h2>Paper against suite</h2><table><thead><tr><th>quantity</th><th>paper</th>\
         <th>metaplate ({})</th></tr></thead><tbody>",
        escape(&columns(&results))
    );
    for row in paper_rows(&results) {
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

fn plate_section(page: &mut String, plate: &ReportPlate<'_>) -> Result<(), EvaluationError> {
    let _ = write!(page, "<section><h2>Plate: {}</h2>", escape(plate.name));
    let scan = plate.scan;
    let dataset = Dataset::open(&scan.dir).step(|| format!("opening dataset {}", scan.dir))?;
    page.push_str("<h3>Measurement</h3><table class=\"kv\">");
    let meta = &dataset.manifest().meta;
    let protocol = meta.config.get("protocol").and_then(|p| p.get("name")).and_then(Value::as_str);
    kv(page, "protocol", protocol.unwrap_or("-"));
    let total = scan.total.map_or_else(String::new, |t| format!(" of {t} planned"));
    kv(page, "points committed", &format!("{}{total}", scan.points));
    let statuses = scan.statuses.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ");
    kv(page, "rows by status", &statuses);
    if let Some(h) = scan.simulated_hours.filter(|h| h.is_finite()) {
        kv(page, "measurement time (rig clock, simulated)", &duration_text(h * 3600.0));
    }
    if let Some(h) = scan.measured_span_hours.filter(|h| h.is_finite()) {
        kv(page, "first to last row (wall clock)", &duration_text(h * 3600.0));
    }
    let mut snr: Vec<f64> = dataset.rows().iter().filter_map(|m| m.snr_db).filter(|v| v.is_finite()).collect();
    if let (Some(lo), Some(mid)) = (quantile(&mut snr, 0.0), quantile(&mut snr, 0.5)) {
        kv(page, "SNR over rows", &format!("median {mid:.1} dB, lowest {lo:.1} dB"));
    }
    let finite = |v: Option<f64>| v.filter(|x| x.is_finite());
    let truth_text = match &scan.greens_error {
        Ok(e) => match (finite(e.median), finite(e.p95), finite(e.worst)) {
            (Some(m), Some(p), Some(w)) => format!(
                "median {m:.1} dB, p95 {p:.1} dB, worst {w:.1} dB over {} rows, {:?}..{:?} Hz",
                e.rows, e.band_hz[0], e.band_hz[1]
            ),
            _ => "-".to_owned(),
        },
        Err(why) => why.clone(),
    };
    kv(page, "Green's functions against the truth", &truth_text);
    page.push_str("</table>");
    let grid = meta.grid;
    let (states, snr) = grid_cells(&grid, &planned_points(&meta.config), dataset.rows());
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
    provenance(page, &dataset, plate);
    page.push_str("<h3>Figures</h3><div class=\"figures\">");
    for f in plate.analysis.figures.iter().flatten() {
        figure(page, Path::new(f))?;
    }
    page.push_str("</div></section>");
    Ok(())
}

fn provenance(page: &mut String, dataset: &Dataset, plate: &ReportPlate<'_>) {
    let manifest = dataset.manifest();
    let meta = &manifest.meta;
    page.push_str("<h3>Provenance</h3><table class=\"kv\">");
    kv(page, "dataset", &plate.scan.dir);
    kv(page, "scene", &format!("{} ({})", meta.scene.name, meta.scene.hash));
    kv(page, "recipe", &meta.recipe);
    kv(page, "configuration hash", &manifest.config_hash);
    let calibration = meta.config.get("calibration").and_then(Value::as_str).unwrap_or("none (uncompensated drives)");
    let calibration_dir = plate.calibration_dir.map_or_else(String::new, |d| format!(", {d}"));
    kv(page, "calibration", &format!("{calibration}{calibration_dir}"));
    kv(page, "seed", &meta.seed.to_string());
    kv(page, "created", &manifest.created_at);
    kv(page, "measured with", &format!("metaplate {}", meta.software_version));
    page.push_str("</table>");
}

/// One PNG figure embedded as a data URI, with its caption; other files (the SVG twins) are skipped.
fn figure(page: &mut String, path: &Path) -> Result<(), EvaluationError> {
    if path.extension().and_then(|e| e.to_str()) != Some("png") {
        return Ok(());
    }
    let bytes = fs::read(path).map_err(io_error("reading figure", path))?;
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
             the interquartile range). Hollow markers fall outside what the lattice resolves (dotted lines), or are \
             all hollow when less than half the lattice was measured (the title says so)."
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

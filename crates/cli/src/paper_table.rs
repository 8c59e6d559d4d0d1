//! The paper-against-suite table (DESIGN.md section 6) and the measurement lines under it, built from the demo's
//! summary: the demo prints them, `report` writes them as HTML.
//!
//! The summary's `plates` object maps a plate's name to what was done on it: `analysis` (`metaplate analyze
//! --json`), and where they were run `dispersion` (the plate model's), `pattern`, `scan` and `calibration`. A plate
//! or a part that is missing shows as "-".

use serde_json::Value;

/// The built-in plates in the table's column order, and the paper's value per plate where it reports one.
pub const PLATES: [&str; 2] = ["metamaterial", "homogeneous"];

/// Frequencies of the model's dispersion table, Hz: the paper's two measured points and the band between.
pub const DISPERSION_FREQS_HZ: [f64; 6] = [75.0, 150.0, 250.0, 400.0, 500.0, 600.0];

/// One row: what is compared, the paper's value, metaplate's (one value per plate, "/" between).
pub struct TableRow {
    pub quantity: String,
    pub paper: String,
    pub suite: String,
}

/// The table's rows from the demo's summary (see the module documentation).
pub fn rows(summary: &Value) -> Vec<TableRow> {
    let plates = &summary["plates"];
    let present: Vec<&str> = PLATES.iter().copied().filter(|p| plates.get(*p).is_some()).collect();
    let disp = |plate: &str, f: f64| {
        plates[plate]["dispersion"]["points"]
            .as_array()
            .and_then(|ps| ps.iter().find(|p| p["freq_hz"].as_f64() == Some(f)))
            .and_then(|p| p["wavelength_m"].as_f64())
    };
    let a = |plate: &str| &plates[plate]["analysis"];
    let num = |v: &Value, digits: usize| v.as_f64().map_or_else(|| "-".to_owned(), |x| format!("{x:.digits$}"));
    let per_plate = |cell: &dyn Fn(&str) -> String| present.iter().map(|p| cell(p)).collect::<Vec<_>>().join(" / ");
    let mut rows = Vec::new();
    let mut row = |quantity: &str, paper: &str, suite: String| {
        rows.push(TableRow { quantity: quantity.to_owned(), paper: paper.to_owned(), suite });
    };
    let cm = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |m| format!("{:.1} cm", m * 100.0));
    row("wavelength at 75 Hz, metamaterial (model)", "11.3 cm", cm(disp("metamaterial", 75.0)));
    row("wavelength at 600 Hz, metamaterial (model)", "2.5 cm", cm(disp("metamaterial", 600.0)));
    let ratios: Vec<f64> =
        DISPERSION_FREQS_HZ.iter().filter_map(|&f| Some(disp("homogeneous", f)? / disp("metamaterial", f)?)).collect();
    let ratio_text = match ratios.iter().copied().reduce(f64::min).zip(ratios.iter().copied().reduce(f64::max)) {
        Some((lo, hi)) => format!("{lo:.1} to {hi:.1}"),
        None => "-".to_owned(),
    };
    row("homogeneous / metamaterial wavelength", "2.1 to 4.8", ratio_text);
    let area = |p: &str| a(p)["median_pixel_area_cm2"].as_f64();
    let area_ratio = match (area("metamaterial"), area("homogeneous")) {
        (Some(m), Some(h)) if m > 0.0 => format!(" ({:.1} x)", h / m),
        _ => String::new(),
    };
    row(
        "median virtual-pixel area, cm^2",
        "2.74 / about 10 x",
        format!("{}{area_ratio}", per_plate(&|p| num(&a(p)["median_pixel_area_cm2"], 2))),
    );
    row("refresh, ms", "5 / -", per_plate(&|p| num(&a(p)["refresh_ms"], 1)));
    row("POD components for 99 %", "23 / 11", per_plate(&|p| num(&a(p)["pod_components_99"], 0)));
    // Authority depends on the lattice (how many points a domain holds): each side says its own, so that unlike
    // is not read as like. The paper's domains hold 361, 169 and 49 points of its 5 mm grid.
    let lattice = |key: &str, edge: &str| {
        let values = per_plate(&|p| num(&a(p)[key][edge], 1));
        let Some(first) = present.first() else { return values };
        let spacing_cm = a(first)["lattice"]["spacing_m"].as_f64().map_or(f64::NAN, |h| h * 100.0);
        let points = a(first)["points_per_domain"][edge].as_u64().map_or_else(|| "-".to_owned(), |n| n.to_string());
        format!("{values} [{points} pts, {spacing_cm:.1} cm]")
    };
    row("effective rank of G_D, d = 3.5 cm", "7.4 / 4.3 [49 pts, 0.5 cm]", lattice("effective_rank", "3.5"));
    for (edge, paper) in [
        ("9.5", "5.0 / 51.5 [361 pts, 0.5 cm]"),
        ("6.5", "10.1 / 110.6 [169 pts, 0.5 cm]"),
        ("3.5", "35.9 / 236.0 [49 pts, 0.5 cm]"),
    ] {
        row(&format!("mean condition number, d = {edge} cm"), paper, lattice("condition_number", edge));
    }
    let peak_mm_s = |p: &str| {
        plates[p]["pattern"]["pixels"].as_array().map_or_else(
            || "-".to_owned(),
            |px| {
                let peak = px.iter().filter_map(|x| x["peak_velocity_m_s"].as_f64()).fold(0.0_f64, f64::max);
                format!("{:.1}", peak * 1e3)
            },
        )
    };
    row("peak velocity at a pixel (full-scale drive), mm/s", "> 10", per_plate(&peak_mm_s));
    rows
}

/// The plates the table has a column for, as its header names them ("metamaterial / homogeneous").
pub fn columns(summary: &Value) -> String {
    PLATES.iter().copied().filter(|p| summary["plates"].get(*p).is_some()).collect::<Vec<_>>().join(" / ")
}

/// One line per plate on its measurement: calibrated actuators, points by status, simulated and wall time, the
/// Green's functions' error against the truth, the pattern's peak drive. Plates without a scan are left out.
pub fn measurement_lines(summary: &Value) -> Vec<String> {
    let plates = &summary["plates"];
    let num = |v: &Value, digits: usize| v.as_f64().map_or_else(|| "-".to_owned(), |x| format!("{x:.digits$}"));
    let mut lines = Vec::new();
    for plate in PLATES {
        let s = &plates[plate]["scan"];
        if s.is_null() {
            continue;
        }
        let e = &s["greens_error_db"];
        let statuses = s["statuses"]
            .as_object()
            .map_or_else(String::new, |m| m.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "));
        let calibrated = plates[plate]["calibration"]["actuators"]
            .as_array()
            .map_or(0, |a| a.iter().filter(|c| c["status"] == "valid").count());
        lines.push(format!(
            "{plate}: {calibrated}/8 actuators calibrated; {} points ({statuses}), {} h simulated in {} s; Green's \
             functions against the truth: median {} dB, p95 {} dB; pattern peak drive {}",
            s["points"],
            num(&s["simulated_hours"], 2),
            num(&s["wall_s"], 0),
            num(&e["median"], 1),
            num(&e["p95"], 1),
            num(&plates[plate]["pattern"]["peak_drive"], 3),
        ));
    }
    lines
}

/// Prints the table and the measurement lines on stdout, as the demo shows them.
pub fn print(summary: &Value) {
    let line = |q: &str, paper: &str, suite: &str| println!("{q:<46} {paper:>30}   {suite}");
    println!("\n{:<46} {:>30}   metaplate ({})", "quantity", "paper", columns(summary));
    for r in rows(summary) {
        line(&r.quantity, &r.paper, &r.suite);
    }
    println!("\nthe measurement (mock lab, {} protocol):", summary["protocol"].as_str().unwrap_or("?"));
    for l in measurement_lines(summary) {
        println!("  {l}");
    }
}

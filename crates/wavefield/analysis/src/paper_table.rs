//! The paper-against-suite table (DESIGN.md section 6): the paper's values beside the suite's, per built-in plate,
//! from typed inputs ([`PlateResults`]): a dataset's analysis, the plate model's wavelengths where they were
//! computed, and the peak velocity of a rendered pattern where one was played. A plate or a part that is missing
//! shows as "-".

use crate::dataset_report::DatasetAnalysis;

/// The built-in plates in the table's column order.
pub const PLATES: [&str; 2] = ["metamaterial", "homogeneous"];

/// Frequencies of the model's dispersion table, Hz: the paper's two measured points and the band between.
pub const DISPERSION_FREQS_HZ: [f64; 6] = [75.0, 150.0, 250.0, 400.0, 500.0, 600.0];

/// The plate model's k-space wavelength at one frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelWavelength {
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// The median over the actuators, m.
    pub wavelength_m: f64,
    /// Whether every actuator's estimate lies in the method's resolved range (false: for some, the peak is the
    /// aperture's, or an alias's, not a wave's).
    pub resolved: bool,
}

/// What the suite found on one plate.
#[derive(Debug, Clone, Copy)]
pub struct PlateResults<'a> {
    /// The plate's (scene's) name: a column when it is one of [`PLATES`].
    pub name: &'a str,
    /// The analysis of its scanned dataset.
    pub analysis: Option<&'a DatasetAnalysis>,
    /// The plate model's k-space wavelength per frequency, where it was computed (`None`: not run).
    pub model_wavelengths: Option<&'a [ModelWavelength]>,
    /// The largest peak velocity at a pixel of a rendered pattern, m/s (`None`: no pattern).
    pub pattern_peak_velocity_m_s: Option<f64>,
}

/// One row: what is compared, the paper's value, metaplate's (one value per plate, "/" between).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PaperRow {
    /// What is compared.
    pub quantity: String,
    /// The paper's value.
    pub paper: String,
    /// The suite's, per plate.
    pub suite: String,
}

/// The built-in plates of `plates` in the table's column order.
fn present<'p, 'a>(plates: &'p [PlateResults<'a>]) -> Vec<&'p PlateResults<'a>> {
    PLATES.iter().filter_map(|name| plates.iter().find(|p| p.name == *name)).collect()
}

/// The plates the table has a column for, as its header names them ("metamaterial / homogeneous").
pub fn columns(plates: &[PlateResults<'_>]) -> String {
    present(plates).iter().map(|p| p.name).collect::<Vec<_>>().join(" / ")
}

/// The table's rows.
pub fn paper_rows(plates: &[PlateResults<'_>]) -> Vec<PaperRow> {
    let present = present(plates);
    let plate = |name: &str| present.iter().find(|p| p.name == name);
    let disp = |name: &str, f: f64| {
        plate(name)?.model_wavelengths?.iter().find(|w| w.freq_hz == f).filter(|w| w.wavelength_m.is_finite())
    };
    let num = |v: Option<f64>, digits: usize| {
        v.filter(|x| x.is_finite()).map_or_else(|| "-".to_owned(), |x| format!("{x:.digits$}"))
    };
    let analysis_value =
        |p: &PlateResults<'_>, value: &dyn Fn(&DatasetAnalysis) -> Option<f64>| p.analysis.and_then(value);
    let per_plate =
        |cell: &dyn Fn(&PlateResults<'_>) -> String| present.iter().map(|p| cell(p)).collect::<Vec<_>>().join(" / ");
    let mut rows = Vec::new();
    let mut row = |quantity: &str, paper: &str, suite: String| {
        rows.push(PaperRow { quantity: quantity.to_owned(), paper: paper.to_owned(), suite });
    };
    let cm = |w: Option<&ModelWavelength>| {
        w.map_or_else(
            || "-".to_owned(),
            |w| match w.resolved {
                true => format!("{:.1} cm", w.wavelength_m * 100.0),
                false => format!("unresolved ({:.1} cm)", w.wavelength_m * 100.0),
            },
        )
    };
    row("wavelength at 75 Hz, metamaterial (model)", "11.3 cm", cm(disp("metamaterial", 75.0)));
    row("wavelength at 600 Hz, metamaterial (model)", "2.5 cm", cm(disp("metamaterial", 600.0)));
    // Where the metamaterial's wave is resolved; the homogeneous plate's long waves may exceed the aperture (its
    // k-space reads them short, so the ratio errs low).
    let ratios: Vec<f64> = DISPERSION_FREQS_HZ
        .iter()
        .filter_map(|&f| {
            let meta = disp("metamaterial", f).filter(|w| w.resolved)?;
            Some(disp("homogeneous", f)?.wavelength_m / meta.wavelength_m)
        })
        .collect();
    let ratio_text = match ratios.iter().copied().reduce(f64::min).zip(ratios.iter().copied().reduce(f64::max)) {
        Some((lo, hi)) => format!("{lo:.1} to {hi:.1}"),
        None => "-".to_owned(),
    };
    row("homogeneous / metamaterial wavelength", "2.1 to 4.8", ratio_text);
    let area = |name: &str| {
        plate(name).and_then(|p| analysis_value(p, &|a| a.median_pixel_area_cm2)).filter(|v| v.is_finite())
    };
    let area_ratio = match (area("metamaterial"), area("homogeneous")) {
        (Some(m), Some(h)) if m > 0.0 => format!(" ({:.1} x)", h / m),
        _ => String::new(),
    };
    row(
        "median virtual-pixel area, cm^2",
        "2.74 / about 10 x",
        format!("{}{area_ratio}", per_plate(&|p| num(analysis_value(p, &|a| a.median_pixel_area_cm2), 2))),
    );
    row("refresh, ms", "5 / -", per_plate(&|p| num(analysis_value(p, &|a| a.refresh_ms), 1)));
    let components = |a: &DatasetAnalysis| a.pod_components_99.map(|n| n as f64);
    row("POD components for 99 %", "23 / 11", per_plate(&|p| num(analysis_value(p, &components), 0)));
    // Authority depends on the lattice (how many points a domain holds): each side says its own, so that unlike
    // is not read as like. The paper's domains hold 361, 169 and 49 points of its 5 mm grid.
    let lattice = |rank: bool, edge: &str| {
        let value = |a: &DatasetAnalysis| {
            let map = if rank { &a.effective_rank } else { &a.condition_number };
            map.get(edge).copied().flatten()
        };
        let values = per_plate(&|p| num(analysis_value(p, &value), 1));
        let Some(first) = present.first() else { return values };
        let spacing_cm = first.analysis.map_or(f64::NAN, |a| a.lattice.spacing_m * 100.0);
        let points = first
            .analysis
            .and_then(|a| a.points_per_domain.get(edge))
            .map_or_else(|| "-".to_owned(), ToString::to_string);
        format!("{values} [{points} pts, {spacing_cm:.1} cm]")
    };
    row("effective rank of G_D, d = 3.5 cm", "7.4 / 4.3 [49 pts, 0.5 cm]", lattice(true, "3.5"));
    for (edge, paper) in [
        ("9.5", "5.0 / 51.5 [361 pts, 0.5 cm]"),
        ("6.5", "10.1 / 110.6 [169 pts, 0.5 cm]"),
        ("3.5", "35.9 / 236.0 [49 pts, 0.5 cm]"),
    ] {
        row(&format!("mean condition number, d = {edge} cm"), paper, lattice(false, edge));
    }
    let peak_mm_s = |p: &PlateResults<'_>| {
        p.pattern_peak_velocity_m_s.map_or_else(|| "-".to_owned(), |v| format!("{:.1}", v * 1e3))
    };
    row("peak velocity at a pixel (full-scale drive), mm/s", "> 10", per_plate(&peak_mm_s));
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_plates_and_parts_show_as_dashes_and_the_model_rows_use_the_dispersion() {
        let at = |freq_hz: f64, wavelength_m: f64, resolved: bool| ModelWavelength { freq_hz, wavelength_m, resolved };
        let paper = [(75.0, 0.113), (150.0, 0.08), (250.0, 0.06), (400.0, 0.04), (500.0, 0.03), (600.0, 0.025)];
        let meta: Vec<ModelWavelength> = paper.iter().map(|&(f, m)| at(f, m, true)).collect();
        // The homogeneous plate's long waves unresolved at 75 Hz: still in the ratio (its k-space reads them short).
        let homo: Vec<ModelWavelength> = paper.iter().map(|&(f, m)| at(f, m * 3.0, f > 75.0)).collect();
        let plates = [
            PlateResults {
                name: "homogeneous",
                analysis: None,
                model_wavelengths: Some(&homo),
                pattern_peak_velocity_m_s: Some(0.0123),
            },
            PlateResults {
                name: "metamaterial",
                analysis: None,
                model_wavelengths: Some(&meta),
                pattern_peak_velocity_m_s: None,
            },
            PlateResults { name: "other", analysis: None, model_wavelengths: None, pattern_peak_velocity_m_s: None },
        ];
        assert_eq!(columns(&plates), "metamaterial / homogeneous");
        let rows = paper_rows(&plates);
        assert_eq!(rows.len(), 11);
        assert_eq!(rows[0].suite, "11.3 cm");
        assert_eq!(rows[1].suite, "2.5 cm");
        assert_eq!(rows[2].suite, "3.0 to 3.0");
        assert_eq!(rows[3].suite, "- / -");
        assert_eq!(rows[6].suite, "- / - [- pts, NaN cm]");
        assert_eq!(rows[10].suite, "- / 12.3");
        assert_eq!(paper_rows(&[]).iter().filter(|r| r.suite == "-").count(), 3);

        // The metamaterial's 600 Hz estimate unresolved (no wave: the peak is the aperture's): said so, and left out
        // of the ratio, whose range is then the resolved frequencies'.
        let mut above = meta.clone();
        above[5] = at(600.0, 0.229, false);
        above[4].wavelength_m = 0.015;
        let plates = [
            PlateResults { model_wavelengths: Some(&above), ..plates[1] },
            PlateResults { model_wavelengths: Some(&homo), ..plates[0] },
        ];
        let rows = paper_rows(&plates);
        assert_eq!(rows[1].suite, "unresolved (22.9 cm)");
        assert_eq!(rows[2].suite, "3.0 to 6.0");
    }
}

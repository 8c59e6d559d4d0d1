//! Line figures: wavelength, POD energy, singular-value energy, condition numbers, driven response.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::PALETTE;
use crate::render::{FONT, Figure, FigureError, Written, axis_range, save};

/// One labelled series of points `(x, y)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Legend label (for example the plate's name).
    pub label: String,
    /// Points, in drawing order; non-finite ones are skipped.
    pub points: Vec<(f64, f64)>,
}

/// Wavelength against frequency for one plate.
#[derive(Debug, Clone, PartialEq)]
pub struct WavelengthSeries {
    /// Legend label.
    pub label: String,
    /// Frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// Median wavelength, m, one per frequency.
    pub median_m: Vec<f64>,
    /// Interquartile range, m, one per frequency.
    pub iqr_m: Vec<(f64, f64)>,
}

/// Band-averaged relative singular-value energy of one plate over one domain.
#[derive(Debug, Clone, PartialEq)]
pub struct SingularValueSeries {
    /// Legend label (plate and domain edge).
    pub label: String,
    /// Mean over frequency of `10 log10(sigma_i^2 / sigma_1^2)`, dB, for i = 1..N.
    pub mean_db: Vec<f64>,
    /// Standard deviation across frequency, dB, one per singular value.
    pub std_db: Vec<f64>,
}

/// Points of a curve, `(x, y)`.
type Points = Vec<(f64, f64)>;
/// Vertical error bars, `(x, low, high)`.
type Bars = Vec<(f64, f64, f64)>;

/// One series of a panel: label, points, and vertical error bars `(x, low, high)`.
struct Series {
    label: String,
    points: Vec<(f64, f64)>,
    bars: Vec<(f64, f64, f64)>,
}

/// One chart: axes, title and series. With `log_y` the y values are plotted as their base-10 logarithm and labelled
/// as powers of ten.
struct Panel {
    title: String,
    x_desc: &'static str,
    y_desc: &'static str,
    log_y: bool,
    series: Vec<Series>,
}

/// Panels stacked vertically.
struct Stack {
    name: &'static str,
    panels: Vec<Panel>,
}

impl Figure for Stack {
    const NAME: &'static str = "line figure";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let areas = root.split_evenly((self.panels.len().max(1), 1));
        for (panel, area) in self.panels.iter().zip(&areas) {
            draw_panel(area, panel).map_err(|e| format!("{}: {e}", self.name))?;
        }
        Ok(())
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> Result<(), String> {
    let ty = |y: f64| if panel.log_y { if y > 0.0 { y.log10() } else { f64::NAN } } else { y };
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let series: Vec<(Points, Bars)> = panel
        .series
        .iter()
        .map(|s| {
            let pts = s.points.iter().map(|&(x, y)| (x, ty(y))).filter(finite).collect();
            let bars = s
                .bars
                .iter()
                .map(|&(x, lo, hi)| (x, ty(lo), ty(hi)))
                .filter(|b| b.0.is_finite() && b.1.is_finite() && b.2.is_finite())
                .collect();
            (pts, bars)
        })
        .collect();
    let xs = series.iter().flat_map(|(p, b)| p.iter().map(|q| q.0).chain(b.iter().map(|q| q.0)));
    let ys = series.iter().flat_map(|(p, b)| p.iter().map(|q| q.1).chain(b.iter().flat_map(|q| [q.1, q.2])));
    let (Some((x0, x1)), Some((y0, y1))) = (axis_range(xs, 0.03), axis_range(ys, 0.08)) else {
        return Err("no finite point to plot".to_owned());
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    let log_y = panel.log_y;
    let y_fmt = move |v: &f64| if log_y { format!("1e{v:.1}") } else { format!("{v:.3}") };
    chart
        .configure_mesh()
        .x_desc(panel.x_desc)
        .y_desc(panel.y_desc)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .y_label_formatter(&y_fmt)
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, ((pts, bars), s)) in series.iter().zip(&panel.series).enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(s.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled()))).map_err(|e| e.to_string())?;
        chart
            .draw_series(bars.iter().map(|&(x, lo, hi)| PathElement::new(vec![(x, lo), (x, hi)], colour)))
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())
}

fn check_nonempty<T>(figure: &'static str, items: &[T]) -> Result<(), FigureError> {
    if items.is_empty() {
        return Err(FigureError::InvalidData { figure, reason: "no series".to_owned() });
    }
    Ok(())
}

fn plain(label: &str, points: Vec<(f64, f64)>) -> Series {
    Series { label: label.to_owned(), points, bars: Vec::new() }
}

/// Wavelength (cm, median with the interquartile range as bars) against frequency (Hz), one curve per plate
/// (paper, Fig. 2A). Writes `<dir>/<name>.png` and `.svg`.
///
/// # Errors
/// [`FigureError::InvalidData`] for no series, mismatched lengths, or nothing finite; [`FigureError::Draw`],
/// [`FigureError::Io`] when drawing or writing fails.
pub fn wavelength(dir: &Path, name: &str, series: &[WavelengthSeries]) -> Result<Written, FigureError> {
    check_nonempty("wavelength", series)?;
    let mut out = Vec::new();
    for s in series {
        if s.median_m.len() != s.freqs_hz.len() || s.iqr_m.len() != s.freqs_hz.len() {
            return Err(FigureError::InvalidData {
                figure: "wavelength",
                reason: format!("{}: frequencies, medians and ranges differ in length", s.label),
            });
        }
        out.push(Series {
            label: s.label.clone(),
            points: s.freqs_hz.iter().zip(&s.median_m).map(|(&f, &m)| (f, m * 100.0)).collect(),
            bars: s.freqs_hz.iter().zip(&s.iqr_m).map(|(&f, &(lo, hi))| (f, lo * 100.0, hi * 100.0)).collect(),
        });
    }
    let panel = Panel {
        title: "Wavelength (k-space, median and IQR)".to_owned(),
        x_desc: "frequency (Hz)",
        y_desc: "wavelength (cm)",
        log_y: false,
        series: out,
    };
    save(&Stack { name: "wavelength", panels: vec![panel] }, dir, name, (900, 600))
}

/// POD energy (paper, Fig. 6A): normalised component energy (log scale) and cumulative energy (%) against component
/// number, one curve per plate; `series[i].points` are `(component number from 1, energy fraction)`.
///
/// # Errors
/// As [`wavelength`].
pub fn pod_energy(dir: &Path, name: &str, series: &[Curve]) -> Result<Written, FigureError> {
    check_nonempty("POD energy", series)?;
    let energy = series.iter().map(|c| plain(&c.label, c.points.clone())).collect();
    let cumulative = series
        .iter()
        .map(|c| {
            let mut sum = 0.0;
            let pts = c.points.iter().map(|&(n, e)| {
                sum += e;
                (n, 100.0 * sum)
            });
            plain(&c.label, pts.collect())
        })
        .collect();
    let panels = vec![
        Panel {
            title: "POD component energy".to_owned(),
            x_desc: "component",
            y_desc: "normalised energy",
            log_y: true,
            series: energy,
        },
        Panel {
            title: "Cumulative POD energy".to_owned(),
            x_desc: "component",
            y_desc: "cumulative energy (%)",
            log_y: false,
            series: cumulative,
        },
    ];
    save(&Stack { name: "POD energy", panels }, dir, name, (900, 900))
}

/// Band-averaged relative singular-value energy `10 log10(sigma_i^2 / sigma_1^2)` (dB) against singular-value
/// index, with the standard deviation across frequency as bars (paper, Fig. 6B), one curve per plate and domain.
///
/// # Errors
/// As [`wavelength`].
pub fn singular_value_energy(dir: &Path, name: &str, series: &[SingularValueSeries]) -> Result<Written, FigureError> {
    check_nonempty("singular-value energy", series)?;
    let mut out = Vec::new();
    for s in series {
        if s.std_db.len() != s.mean_db.len() {
            return Err(FigureError::InvalidData {
                figure: "singular-value energy",
                reason: format!("{}: means and deviations differ in length", s.label),
            });
        }
        let x = |i: usize| (i + 1) as f64;
        out.push(Series {
            label: s.label.clone(),
            points: s.mean_db.iter().enumerate().map(|(i, &m)| (x(i), m)).collect(),
            bars: s.mean_db.iter().zip(&s.std_db).enumerate().map(|(i, (&m, &d))| (x(i), m - d, m + d)).collect(),
        });
    }
    let panel = Panel {
        title: "Relative singular-value energy of G_D (band average)".to_owned(),
        x_desc: "singular value index",
        y_desc: "energy (dB re sigma_1^2)",
        log_y: false,
        series: out,
    };
    save(&Stack { name: "singular-value energy", panels: vec![panel] }, dir, name, (900, 600))
}

/// Mean condition number `sigma_1 / sigma_N` of `G_D` (log scale) against domain edge (cm), one curve per plate
/// (paper, Fig. 6C); `series[i].points` are `(edge_cm, condition number)`.
///
/// # Errors
/// As [`wavelength`].
pub fn condition_numbers(dir: &Path, name: &str, series: &[Curve]) -> Result<Written, FigureError> {
    check_nonempty("condition numbers", series)?;
    let panel = Panel {
        title: "Mean condition number of G_D".to_owned(),
        x_desc: "domain edge (cm)",
        y_desc: "condition number",
        log_y: true,
        series: series.iter().map(|c| plain(&c.label, c.points.clone())).collect(),
    };
    save(&Stack { name: "condition numbers", panels: vec![panel] }, dir, name, (900, 600))
}

/// Mean driven response `|G|` (log scale) against frequency (Hz), one curve per plate; `series[i].points` are
/// `(freq_hz, mean |G|)`.
///
/// # Errors
/// As [`wavelength`].
pub fn driven_response(dir: &Path, name: &str, series: &[Curve]) -> Result<Written, FigureError> {
    check_nonempty("driven response", series)?;
    let panel = Panel {
        title: "Mean driven response".to_owned(),
        x_desc: "frequency (Hz)",
        y_desc: "mean |G|",
        log_y: true,
        series: series.iter().map(|c| plain(&c.label, c.points.clone())).collect(),
    };
    save(&Stack { name: "driven response", panels: vec![panel] }, dir, name, (900, 600))
}

//! Line figures: wavelength, POD energy, singular-value energy, condition numbers, driven response, band structure.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::PALETTE;
use crate::render::{FONT, Figure, FigureError, Ticked, Written, axis_range, plain_number, save};

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
    /// Per frequency: whether the estimate lies in the lattice's resolvable range (drawn filled) or not (drawn
    /// hollow, without its range bar). Empty: all in range.
    pub in_range: Vec<bool>,
}

/// What a wavelength figure shows besides the measured series.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WavelengthReferences {
    /// Model curves (for example the analytic A0 wavelength), wavelength in m against frequency in Hz: dashed.
    pub curves: Vec<Curve>,
    /// Reference points (for example the paper's measured wavelengths), m against Hz: large crosses.
    pub marks: Vec<Curve>,
    /// The lattice's resolvable range, (shortest, longest) wavelength in m: dotted horizontal lines.
    pub resolvable_m: Option<(f64, f64)>,
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
    look: Look,
}

/// How a series is drawn.
#[derive(Clone, PartialEq)]
enum Look {
    /// A line through filled dots; the dots whose flag is `false` hollow (outside a valid range).
    Measured(Vec<bool>),
    /// A dashed line (a model).
    Dashed,
    /// Large crosses, no line (reference values).
    Marks,
    /// A dotted grey line (a limit).
    Limit,
    /// Small filled dots, no line (samples of a relation that is not a function of x, such as a band's c(f)).
    Dots,
}

/// One chart: axes, title and series. With `log_y` the y values are plotted as their base-10 logarithm and labelled
/// as powers of ten.
struct Panel {
    title: String,
    x_desc: &'static str,
    /// Named positions on the x axis (ticks labelled by name, for example a band diagram's Γ, X, M); empty: numbers.
    x_names: &'static [(f64, &'static str)],
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

/// A panel's layout, pixels: its caption's font, margin, axis label areas and legend font (`draw_panel` draws with
/// them, `place_legend` sizes the legend's box from them).
const CAPTION_FONT_PX: u32 = 20;
const PANEL_MARGIN_PX: u32 = 12;
const X_LABEL_AREA_PX: u32 = 45;
const Y_LABEL_AREA_PX: u32 = 80;
const LEGEND_FONT_PX: u32 = 14;

/// Where the legend goes so that it hides no point: the first corner (upper right, upper left, lower right, lower
/// left) whose box, as large as the legend's labels make it, holds no point of the panel; when every corner holds
/// some, upper right with the y axis raised until the points under the box sit below it. Returns the corner and the
/// top of the y axis (plotted units). `size` is the panel's area in pixels.
fn place_legend(
    size: (u32, u32),
    panel: &Panel,
    series: &[(Points, Bars)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> (SeriesLabelPosition, f64) {
    let labels: Vec<&str> = panel.series.iter().map(|s| s.label.as_str()).filter(|l| !l.is_empty()).collect();
    if labels.is_empty() {
        return (SeriesLabelPosition::UpperRight, y1);
    }
    // The plotting area without the caption (its font and half again), labels and margins, as `draw_panel` builds
    // it; the legend's box in its fractions: a character about 0.54 of the legend's font, a line 1.36 of it (19
    // pixels at 14), plus the swatch and padding.
    let margins = f64::from(2 * PANEL_MARGIN_PX);
    let plot_w = (f64::from(size.0) - f64::from(Y_LABEL_AREA_PX) - margins).max(1.0);
    let caption = 1.5 * f64::from(CAPTION_FONT_PX);
    let plot_h = (f64::from(size.1) - f64::from(X_LABEL_AREA_PX) - caption - margins).max(1.0);
    let font = f64::from(LEGEND_FONT_PX);
    let chars = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let w = ((chars as f64 * font * 15.0 / 28.0 + 50.0) / plot_w).min(1.0);
    let h = ((labels.len() as f64 * font * 19.0 / 14.0 + 16.0) / plot_h).min(0.9);
    let points: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(p, b)| p.iter().copied().chain(b.iter().flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)])))
        .map(|(x, y)| ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0)))
        .collect();
    let corners = [
        (SeriesLabelPosition::UpperRight, (1.0 - w, 1.0), (1.0 - h, 1.0)),
        (SeriesLabelPosition::UpperLeft, (0.0, w), (1.0 - h, 1.0)),
        (SeriesLabelPosition::LowerRight, (1.0 - w, 1.0), (0.0, h)),
        (SeriesLabelPosition::LowerLeft, (0.0, w), (0.0, h)),
    ];
    let inside = |&(x, y): &(f64, f64), (xa, xb): (f64, f64), (ya, yb): (f64, f64)| {
        (xa - 0.04..=xb + 0.04).contains(&x) && (ya - 0.04..=yb + 0.04).contains(&y)
    };
    for (corner, xs, ys) in corners {
        if !points.iter().any(|p| inside(p, xs, ys)) {
            return (corner, y1);
        }
    }
    // Raise the top so that the highest point under the box's columns ends below the box.
    let highest = points.iter().filter(|p| p.0 >= 1.0 - w - 0.04).map(|p| p.1).fold(0.0, f64::max);
    let raised = y0 + (y1 - y0) * highest / (1.0 - h - 0.05).max(0.1);
    (SeriesLabelPosition::UpperRight, y1.max(raised))
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
    let (legend_at, y1) = place_legend(area.dim_in_pixel(), panel, &series, (x0, x1), (y0, y1));
    let x_axis = if panel.x_names.is_empty() {
        Ticked::linear(x0, x1)
    } else {
        let at: Vec<f64> = panel.x_names.iter().map(|n| n.0).collect();
        Ticked { lo: x0, hi: x1, labelled: at.clone(), grid: at }
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, (FONT, CAPTION_FONT_PX))
        .margin(PANEL_MARGIN_PX)
        .x_label_area_size(X_LABEL_AREA_PX)
        .y_label_area_size(Y_LABEL_AREA_PX)
        .build_cartesian_2d(x_axis, if panel.log_y { Ticked::log(y0, y1) } else { Ticked::linear(y0, y1) })
        .map_err(|e| e.to_string())?;
    let log_y = panel.log_y;
    let y_fmt = move |v: &f64| if log_y { plain_number(10f64.powf(*v)) } else { plain_number(*v) };
    let names = panel.x_names;
    let x_fmt = move |v: &f64| match names.iter().find(|n| (n.0 - v).abs() < 1e-9) {
        Some(n) => n.1.to_owned(),
        None => plain_number(*v),
    };
    chart
        .configure_mesh()
        .x_desc(panel.x_desc)
        .y_desc(panel.y_desc)
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 15))
        .y_label_formatter(&y_fmt)
        .x_label_formatter(&x_fmt)
        .draw()
        .map_err(|e| e.to_string())?;
    // Measured series take the palette in order; reference marks take it in order too, so that the k-th set of
    // marks shares the k-th measured series' colour (a plate and the paper's values for it); models are black.
    let (mut measured, mut marks) = (0, 0);
    for ((pts, bars), s) in series.iter().zip(&panel.series) {
        let next = |n: &mut usize| {
            *n += 1;
            PALETTE[(*n - 1) % PALETTE.len()]
        };
        let colour = match s.look {
            Look::Limit => RGBColor(140, 140, 140),
            Look::Dashed => BLACK,
            Look::Marks => next(&mut marks),
            Look::Measured(_) | Look::Dots => next(&mut measured),
        };
        match &s.look {
            Look::Measured(in_range) => {
                let filled = |i: usize| in_range.get(i).copied().unwrap_or(true);
                // Solid between points both in range; thin and dashed where either lies outside it, so that a jump to
                // an aperture's or an alias's reading is not drawn as the wave's.
                let (solid, outside): (Vec<_>, Vec<_>) =
                    pts.windows(2).enumerate().partition(|(i, _)| filled(*i) && filled(*i + 1));
                chart
                    .draw_series(solid.iter().map(|(_, pair)| PathElement::new(pair.to_vec(), colour.stroke_width(2))))
                    .map_err(|e| e.to_string())?
                    .label(s.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
                for (_, pair) in &outside {
                    chart
                        .draw_series(DashedLineSeries::new(pair.iter().copied(), 4, 4, colour.stroke_width(1)))
                        .map_err(|e| e.to_string())?;
                }
                chart
                    .draw_series(pts.iter().enumerate().map(|(i, &p)| {
                        let style = if filled(i) { colour.filled() } else { WHITE.filled() };
                        Circle::new(p, 4, style)
                    }))
                    .map_err(|e| e.to_string())?;
                chart
                    .draw_series(
                        pts.iter()
                            .enumerate()
                            .filter(|(i, _)| !filled(*i))
                            .map(|(_, &p)| Circle::new(p, 4, colour.stroke_width(2))),
                    )
                    .map_err(|e| e.to_string())?;
                chart
                    .draw_series(bars.iter().map(|&(x, lo, hi)| PathElement::new(vec![(x, lo), (x, hi)], colour)))
                    .map_err(|e| e.to_string())?;
            }
            Look::Dashed | Look::Limit => {
                let (dash, gap, width) = if s.look == Look::Limit { (3, 4, 1) } else { (10, 6, 2) };
                let drawn = chart
                    .draw_series(DashedLineSeries::new(pts.iter().copied(), dash, gap, colour.stroke_width(width)))
                    .map_err(|e| e.to_string())?;
                if !s.label.is_empty() {
                    drawn
                        .label(s.label.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], colour.stroke_width(width)));
                }
            }
            Look::Dots => {
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| e.to_string())?
                    .label(s.label.clone())
                    .legend(move |(x, y)| Circle::new((x + 10, y), 3, colour.filled()));
            }
            Look::Marks => {
                chart
                    .draw_series(pts.iter().map(|&p| Cross::new(p, 7, colour.stroke_width(3))))
                    .map_err(|e| e.to_string())?
                    .label(s.label.clone())
                    .legend(move |(x, y)| Cross::new((x + 10, y), 5, colour.stroke_width(2)));
            }
        }
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LEGEND_FONT_PX))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend_at)
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
    Series { label: label.to_owned(), points, bars: Vec::new(), look: Look::Measured(Vec::new()) }
}

/// Wavelength (cm, median with the interquartile range as bars) against frequency (Hz), one curve per plate on
/// shared axes (paper, Fig. 2A), with `references` (models dashed, reference values as crosses, the resolvable range
/// dotted); estimates outside the resolvable range drawn hollow. `title` goes above (the lattice, for example).
/// Writes `<dir>/<name>.png` and `.svg`.
///
/// # Errors
/// [`FigureError::InvalidData`] for no series, mismatched lengths, or nothing finite; [`FigureError::Draw`],
/// [`FigureError::Io`] when drawing or writing fails.
pub fn wavelength(
    dir: &Path,
    name: &str,
    title: &str,
    series: &[WavelengthSeries],
    references: &WavelengthReferences,
) -> Result<Written, FigureError> {
    check_nonempty("wavelength", series)?;
    let mut out = Vec::new();
    for s in series {
        if s.median_m.len() != s.freqs_hz.len()
            || s.iqr_m.len() != s.freqs_hz.len()
            || !(s.in_range.is_empty() || s.in_range.len() == s.freqs_hz.len())
        {
            return Err(FigureError::InvalidData {
                figure: "wavelength",
                reason: format!("{}: frequencies, medians, ranges and flags differ in length", s.label),
            });
        }
        let in_range = |i: usize| s.in_range.get(i).copied().unwrap_or(true);
        out.push(Series {
            label: s.label.clone(),
            points: s.freqs_hz.iter().zip(&s.median_m).map(|(&f, &m)| (f, m * 100.0)).collect(),
            bars: s
                .freqs_hz
                .iter()
                .zip(&s.iqr_m)
                .enumerate()
                .filter(|(i, _)| in_range(*i))
                .map(|(_, (&f, &(lo, hi)))| (f, lo * 100.0, hi * 100.0))
                .collect(),
            look: Look::Measured(s.in_range.clone()),
        });
    }
    let to_cm = |c: &Curve| c.points.iter().map(|&(f, m)| (f, m * 100.0)).collect::<Vec<_>>();
    for c in &references.curves {
        out.push(Series { label: c.label.clone(), points: to_cm(c), bars: Vec::new(), look: Look::Dashed });
    }
    for c in &references.marks {
        out.push(Series { label: c.label.clone(), points: to_cm(c), bars: Vec::new(), look: Look::Marks });
    }
    if let Some((short_m, long_m)) = references.resolvable_m {
        let fs = series.iter().flat_map(|s| s.freqs_hz.iter().copied()).filter(|f| f.is_finite());
        let (f0, f1) = fs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), f| (a.min(f), b.max(f)));
        if f0.is_finite() {
            for (label, m) in [("resolvable range", long_m), ("", short_m)] {
                let points = vec![(f0, m * 100.0), (f1, m * 100.0)];
                out.push(Series { label: label.to_owned(), points, bars: Vec::new(), look: Look::Limit });
            }
        }
    }
    let panel = Panel {
        title: title.to_owned(),
        x_desc: "frequency (Hz)",
        x_names: &[],
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
            x_names: &[],
            y_desc: "normalised energy",
            log_y: true,
            series: energy,
        },
        Panel {
            title: "Cumulative POD energy".to_owned(),
            x_desc: "component",
            x_names: &[],
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
            look: Look::Measured(Vec::new()),
        });
    }
    let panel = Panel {
        title: "Relative singular-value energy of G_D (band average)".to_owned(),
        x_desc: "singular value index",
        x_names: &[],
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
pub fn condition_numbers(
    dir: &Path,
    name: &str,
    title: &str,
    series: &[Curve],
    marks: &[Curve],
) -> Result<Written, FigureError> {
    check_nonempty("condition numbers", series)?;
    let mut all: Vec<Series> = series.iter().map(|c| plain(&c.label, c.points.clone())).collect();
    all.extend(marks.iter().filter(|c| !c.points.is_empty()).map(|c| Series {
        label: c.label.clone(),
        points: c.points.clone(),
        bars: Vec::new(),
        look: Look::Marks,
    }));
    let panel = Panel {
        title: title.to_owned(),
        x_desc: "domain edge (cm)",
        x_names: &[],
        y_desc: "condition number",
        log_y: true,
        series: all,
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
        x_names: &[],
        y_desc: "mean |G|",
        log_y: true,
        series: series.iter().map(|c| plain(&c.label, c.points.clone())).collect(),
    };
    save(&Stack { name: "driven response", panels: vec![panel] }, dir, name, (900, 600))
}

/// A unit cell's band structure (paper, Fig. 2B-D), each curve's points in plain SI units.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BandFigure {
    /// Title over the band diagram (the design's name).
    pub title: String,
    /// The branches, (path position in units of pi / a, frequency in Hz), one curve per mode.
    pub branches: Vec<Curve>,
    /// The homogeneous plate's A0 folded into the zone, same axes: dashed.
    pub a0_folded: Vec<Curve>,
    /// The clamped cell's resonator mode, Hz: a dotted horizontal line.
    pub resonator_hz: Option<f64>,
    /// Phase velocity, (frequency in Hz, m/s), one curve per branch shown.
    pub phase_velocity: Vec<Curve>,
    /// Wavelength, (frequency in Hz, m), one curve per branch shown.
    pub wavelength: Vec<Curve>,
    /// The analytic A0's phase velocity and wavelength against frequency (Hz, m/s and Hz, m): dashed.
    pub a0_phase_velocity: Option<Curve>,
    /// See `a0_phase_velocity`.
    pub a0_wavelength: Option<Curve>,
}

/// A band structure in three stacked panels (paper, Fig. 2B-D): frequency along Gamma-X-M-Gamma with the folded A0
/// and the resonator mode, phase velocity against frequency, wavelength (cm) against frequency; the branches as
/// dots. Writes `<dir>/<name>.png` and `.svg`.
///
/// # Errors
/// As [`wavelength`].
pub fn band_structure(dir: &Path, name: &str, figure: &BandFigure) -> Result<Written, FigureError> {
    check_nonempty("band structure", &figure.branches)?;
    let dots = |c: &Curve, scale: f64| Series {
        label: c.label.clone(),
        points: c.points.iter().map(|&(x, y)| (x, y * scale)).collect(),
        bars: Vec::new(),
        look: Look::Dots,
    };
    let dashed = |c: &Curve, scale: f64, label: bool| Series {
        label: if label { c.label.clone() } else { String::new() },
        points: c.points.iter().map(|&(x, y)| (x, y * scale)).collect(),
        bars: Vec::new(),
        look: Look::Dashed,
    };
    let mut bands: Vec<Series> = figure.branches.iter().map(|c| dots(c, 1.0)).collect();
    bands.extend(figure.a0_folded.iter().enumerate().map(|(i, c)| dashed(c, 1.0, i == 0)));
    if let Some(f_n) = figure.resonator_hz {
        let xs = figure.branches.iter().flat_map(|c| c.points.iter().map(|p| p.0));
        let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        if x0.is_finite() {
            let label = format!("clamped-cell resonator mode {f_n:.0} Hz");
            bands.push(Series { label, points: vec![(x0, f_n), (x1, f_n)], bars: Vec::new(), look: Look::Limit });
        }
    }
    let with_a0 = |curves: &[Curve], a0: &Option<Curve>, scale: f64| {
        let mut out: Vec<Series> = curves.iter().map(|c| dots(c, scale)).collect();
        out.extend(a0.iter().map(|c| dashed(c, scale, true)));
        out
    };
    let panels = vec![
        Panel {
            title: figure.title.clone(),
            x_desc: "wave vector along Γ-X-M-Γ (π/a)",
            x_names: &[(0.0, "Γ"), (1.0, "X"), (2.0, "M"), (2.0 + std::f64::consts::SQRT_2, "Γ")],
            y_desc: "frequency (Hz)",
            log_y: false,
            series: bands,
        },
        Panel {
            title: "Phase velocity".to_owned(),
            x_desc: "frequency (Hz)",
            x_names: &[],
            y_desc: "phase velocity (m/s)",
            log_y: true,
            series: with_a0(&figure.phase_velocity, &figure.a0_phase_velocity, 1.0),
        },
        Panel {
            title: "Wavelength".to_owned(),
            x_desc: "frequency (Hz)",
            x_names: &[],
            y_desc: "wavelength (cm)",
            log_y: true,
            series: with_a0(&figure.wavelength, &figure.a0_wavelength, 100.0),
        },
    ];
    save(&Stack { name: "band structure", panels }, dir, name, (900, 1500))
}

#[cfg(test)]
mod tests {
    use plotters::prelude::SeriesLabelPosition;

    use super::{Look, Panel, Series, place_legend};
    use crate::render::{log_ticks, plain_number};

    #[test]
    fn the_legend_takes_a_free_corner_or_raises_the_axis_above_the_points() {
        let place = |points: &[(f64, f64)]| {
            let series =
                Series { label: "a label".into(), points: points.to_vec(), bars: Vec::new(), look: Look::Dots };
            let panel = Panel {
                title: String::new(),
                x_desc: "",
                x_names: &[],
                y_desc: "",
                log_y: false,
                series: vec![series],
            };
            place_legend((900, 500), &panel, &[(points.to_vec(), Vec::new())], (0.0, 10.0), (0.0, 10.0))
        };
        // Upper right and lower left taken: the legend goes upper left, the axis as it was.
        let (at, top) = place(&[(9.5, 9.5), (0.5, 0.5)]);
        assert!(matches!(at, SeriesLabelPosition::UpperLeft) && top == 10.0);
        let (at, _) = place(&[(9.5, 9.5), (0.5, 9.5)]);
        assert!(matches!(at, SeriesLabelPosition::LowerRight));
        // Every corner taken: upper right, the top raised so that the highest point under it ends below the box
        // (one line of 19 pixels and 16 of padding in a plotting area 401 pixels high, and a margin of 5 %).
        let (at, top) = place(&[(0.5, 9.5), (9.5, 9.5), (0.5, 0.5), (9.5, 0.5)]);
        assert!(matches!(at, SeriesLabelPosition::UpperRight));
        let box_bottom = 1.0 - 35.0 / 401.0 - 0.05;
        assert!((9.5 / top - box_bottom).abs() < 1e-12, "top {top}");
    }

    #[test]
    fn log_ticks_fall_at_plain_values() {
        let labels = |lo: f64, hi: f64| -> Vec<String> {
            log_ticks(lo.log10(), hi.log10()).0.iter().map(|t| plain_number(10f64.powf(*t))).collect()
        };
        assert_eq!(labels(3.0, 2500.0), ["5", "10", "20", "50", "100", "200", "500", "1000", "2000"]);
        assert_eq!(labels(2e-6, 0.5), ["10⁻⁵", "10⁻⁴", "10⁻³", "0.01", "0.1"]);
        assert_eq!(labels(250.0, 420.0), ["300", "400"]);
        let (_, grid) = log_ticks(1.0, 2.0);
        assert_eq!(grid.len(), 10, "1 to 9 x 10 and 100: {grid:?}");
    }

    #[test]
    fn log_axis_labels_are_plain_numbers() {
        let labels: Vec<String> = [2.8f64, 3.0, 1.6, 0.0, -1.5].iter().map(|v| plain_number(10f64.powf(*v))).collect();
        assert_eq!(labels, ["631", "1000", "39.8", "1", "0.0316"]);
        assert_eq!(plain_number(10f64.powf(-2.5)), "3.2×10⁻³");
        assert_eq!(plain_number(2.5), "2.5");
        assert_eq!(plain_number(-0.5), "-0.5");
        assert_eq!(plain_number(0.0), "0");
        assert_eq!(plain_number(10f64.powf(-4.5)), "3.2×10⁻⁵");
        assert_eq!(plain_number(1e-4), "10⁻⁴");
        assert_eq!(plain_number(2.5e7), "2.5×10⁷");
    }
}

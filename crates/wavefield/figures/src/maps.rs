//! Maps over the plate: focus snapshots, the focusing animation and the virtual-pixel-area map, each an image of
//! the field on the plate's outline (see [`crate::field`]) with the plate's marks drawn over it.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use metaplate_core::grid::GridSpec;
use plotters::coord::{ReverseCoordTranslate, Shift};
use plotters::prelude::*;

use crate::colour::{MASKED, NO_VALUE, diverging, viridis};
use crate::field::{LatticeField, Raster, Sample, convex_hull, inside_row, row_crossings};
use crate::render::{FONT, Figure, FigureError, Written, plain_number, render_rgb, save, write_apng};

/// What is drawn on a map besides the field, in the grid's frame (m).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlateOverlay {
    /// Actuator positions, m: drawn as black triangles.
    pub actuators_m: Vec<(f64, f64)>,
    /// Support positions, m: drawn as black squares.
    pub supports_m: Vec<(f64, f64)>,
    /// The plate's outline, m: a polygon, vertices in order (the last joins the first). The field is masked
    /// outside it and the outline drawn. Empty: unknown (nothing masked, no outline).
    pub outline_m: Vec<(f64, f64)>,
    /// Resonator (rod) centres, m: drawn as small dots, their region's outline (convex hull) dashed. Empty: a plate
    /// without resonators.
    pub resonator_sites_m: Vec<(f64, f64)>,
    /// The focus target, m, on maps of a focused field: drawn as a ring. `None`: no target.
    pub focus_m: Option<(f64, f64)>,
}

/// How a map's image is drawn.
#[derive(Clone, Copy, PartialEq)]
enum Resolution {
    /// One sample per screen pixel, blitted as a bitmap (PNG).
    Pixels,
    /// This many cells across the frame, each a rectangle (SVG: a pixel-per-pixel image would be megabytes).
    Cells(usize),
}

/// Steps of a map's colour argument per unit: 200 colours across the diverging map's -1 to 1, 100 across viridis.
const COLOUR_LEVELS: f64 = 100.0;

/// Cells across a map's frame on a vector backend.
const VECTOR_CELLS: usize = 60;

/// One map: values on the lattice, drawn as an image.
struct MapPanel<'a> {
    title: String,
    /// One value per lattice point, `None` where there is none.
    values: Cow<'a, [Option<f64>]>,
    /// One flag per lattice point: measured (a point without value is then drawn as "no value").
    measured: Cow<'a, [bool]>,
    colour: fn(f64) -> RGBColor,
    /// Maps a value to the colour map's argument.
    scale: (f64, f64),
    /// Draw the line where the image crosses this value (the focus's half maximum: only around the overlay's focus
    /// target when it has one); `None`: no line.
    contour_at: Option<f64>,
}

/// A key entry under a map.
enum Key {
    /// A filled swatch of this colour (with a thin border).
    Fill(RGBColor),
    /// The overlay's marks.
    Actuator,
    Support,
    Rod,
    Focus,
    /// The level line.
    Contour,
    /// The resonator region's outline.
    Region,
}

struct Maps<'a> {
    /// Above every panel: what the figure shows, with its numbers.
    title: String,
    overlay: &'a PlateOverlay,
    grid: GridSpec,
    panels: Vec<MapPanel<'a>>,
    /// A colour bar under the maps: (label, low, high).
    bar: Option<(String, f64, f64)>,
    /// The key beside the bar.
    key: Vec<(Key, String)>,
    /// The frame of every map, cm: (x0, x1, y0, y1).
    frame_cm: (f64, f64, f64, f64),
}

/// Height of the strip under the maps holding the bar and the key, px.
const BAR_HEIGHT: u32 = 110;
/// Height of the figure's title, px (plotters' `titled` takes the font's height plus margins).
const TITLE_HEIGHT: u32 = 30;

impl Figure for Maps<'_> {
    const NAME: &'static str = "map";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        self.draw_at(root, Resolution::Pixels)
    }

    fn draw_vector<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        self.draw_at(root, Resolution::Cells(VECTOR_CELLS))
    }
}

impl<'a> Maps<'a> {
    /// Maps of `panels` under `title`, with `overlay` drawn on each and its marks in the key; no bar.
    fn new(title: String, overlay: &'a PlateOverlay, grid: GridSpec, panels: Vec<MapPanel<'a>>) -> Self {
        let frame_cm = frame_cm(&grid, overlay);
        let mut key = Vec::new();
        if panels.iter().any(|p| p.contour_at.is_some()) {
            key.push((Key::Contour, "half maximum".to_owned()));
        }
        if overlay.focus_m.is_some() {
            key.push((Key::Focus, "focus target".to_owned()));
        }
        if !overlay.actuators_m.is_empty() {
            key.push((Key::Actuator, "actuator".to_owned()));
        }
        if !overlay.supports_m.is_empty() {
            key.push((Key::Support, "support".to_owned()));
        }
        if !overlay.resonator_sites_m.is_empty() {
            key.push((Key::Rod, "resonator rod".to_owned()));
            key.push((Key::Region, "resonator region".to_owned()));
        }
        Self { title, overlay, grid, panels, bar: None, key, frame_cm }
    }

    /// With a colour bar (label, low, high) under the maps and `key` entries after the marks'.
    fn with_bar(mut self, label: &str, lo: f64, hi: f64, key: Vec<(Key, String)>) -> Self {
        self.bar = Some((label.to_owned(), lo, hi));
        self.key.extend(key);
        self
    }

    /// The figure's size for `columns` maps side by side, each `map_width` px wide, with x and y at one scale.
    fn size(&self, columns: usize, map_width: u32) -> (u32, u32) {
        let (x0, x1, y0, y1) = self.frame_cm;
        let plot_width = map_width.saturating_sub(MAP_MARGIN * 2 + Y_LABELS) as f64;
        let plot_height = plot_width * (y1 - y0) / (x1 - x0);
        let map_height = plot_height.round() as u32 + MAP_MARGIN * 2 + X_LABELS + CAPTION;
        (map_width * columns.max(1) as u32, TITLE_HEIGHT + map_height + BAR_HEIGHT)
    }

    fn draw_at<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>, resolution: Resolution) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root.titled(&self.title, (FONT, 17)).map_err(|e| e.to_string())?;
        let h = root.dim_in_pixel().1;
        let (maps, strip) = root.split_vertically(h.saturating_sub(BAR_HEIGHT));
        let areas = maps.split_evenly((1, self.panels.len().max(1)));
        for (panel, area) in self.panels.iter().zip(&areas) {
            self.draw_map(area, panel, resolution)?;
        }
        let width = strip.dim_in_pixel().0;
        let key_width = if self.key.is_empty() { 0 } else { (width / 2).min(460) };
        let (bar_area, key_area) = strip.split_horizontally(width - key_width);
        if let Some((label, lo, hi)) = &self.bar
            && let Some(panel) = self.panels.first()
        {
            draw_bar(&bar_area, label, *lo, *hi, panel.colour, panel.scale)?;
        }
        self.draw_key(&key_area)
    }

    fn draw_map<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &MapPanel<'_>,
        resolution: Resolution,
    ) -> Result<(), String> {
        let cm = 100.0;
        let (x0, x1, y0, y1) = self.frame_cm;
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 18))
            .margin(MAP_MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (cm)")
            .y_desc("y (cm)")
            .x_label_formatter(&|v: &f64| plain_number(*v))
            .y_label_formatter(&|v: &f64| plain_number(*v))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .draw()
            .map_err(|e| e.to_string())?;
        let field = LatticeField { grid: &self.grid, values: &panel.values, measured: &panel.measured };
        let outline_cm: Vec<(f64, f64)> = self.overlay.outline_m.iter().map(|&(x, y)| (x * cm, y * cm)).collect();
        let (lo, hi) = panel.scale;
        let span = if hi > lo { hi - lo } else { 1.0 };
        // The colour at a position in cm, given its row's crossings of the outline; `None`: the background (off
        // the plate, or nothing known there).
        let colour_at = |x: f64, y: f64, row: Option<&[f64]>| -> Option<RGBColor> {
            if !inside_row(row, x) {
                return None;
            }
            match field.at(x / cm, y / cm) {
                // The colour map's argument in steps of 1/COLOUR_LEVELS: invisible as steps, but long runs of
                // equal pixels make the PNG (and the animation) several times smaller.
                Sample::Value(v) => Some((panel.colour)(((v - lo) / span * COLOUR_LEVELS).round() / COLOUR_LEVELS)),
                Sample::NoValue => Some(NO_VALUE),
                Sample::Unmeasured => (!outline_cm.is_empty()).then_some(MASKED),
            }
        };
        match resolution {
            Resolution::Pixels => {
                let (xs, ys) = chart.plotting_area().get_pixel_range();
                let (w, h) = ((xs.end - xs.start).max(0) as u32, (ys.end - ys.start).max(0) as u32);
                let spec = chart.as_coord_spec();
                let mut rgb = vec![255u8; w as usize * h as usize * 3];
                for (py, row) in rgb.chunks_mut(w as usize * 3).enumerate() {
                    let py = ys.start + py as i32;
                    let Some((_, y)) = spec.reverse_translate((xs.start, py)) else { continue };
                    let crossings = row_crossings(&outline_cm, y);
                    for (px, pixel) in row.chunks_mut(3).enumerate() {
                        let at = spec.reverse_translate((xs.start + px as i32, py));
                        if let Some(c) = at.and_then(|(x, y)| colour_at(x, y, crossings.as_deref())) {
                            pixel.copy_from_slice(&[c.0, c.1, c.2]);
                        }
                    }
                }
                let base = area.get_base_pixel();
                let image = BitMapElement::<_>::with_owned_buffer((xs.start - base.0, ys.start - base.1), (w, h), rgb)
                    .ok_or("image buffer of the wrong size")?;
                area.draw(&image).map_err(|e| e.to_string())?;
            }
            Resolution::Cells(n) => {
                let step = (x1 - x0) / n.max(1) as f64;
                let rows = ((y1 - y0) / step).ceil() as usize;
                // Runs of equal colour along a row are one rectangle each (fewer SVG elements).
                let mut cells = Vec::new();
                for j in 0..rows {
                    let cy = y0 + (j as f64 + 0.5) * step;
                    let crossings = row_crossings(&outline_cm, cy);
                    let colours: Vec<Option<RGBColor>> =
                        (0..n).map(|i| colour_at(x0 + (i as f64 + 0.5) * step, cy, crossings.as_deref())).collect();
                    let mut start = 0;
                    for i in 1..=n {
                        if i < n && colours[i] == colours[start] {
                            continue;
                        }
                        if let Some(c) = colours[start] {
                            let (a, b) = (
                                (x0 + start as f64 * step, cy - step / 2.0),
                                ((x0 + i as f64 * step).min(x1), (cy + step / 2.0).min(y1)),
                            );
                            cells.push(Rectangle::new([a, b], c.filled()));
                        }
                        start = i;
                    }
                }
                chart.draw_series(cells).map_err(|e| e.to_string())?;
            }
        }
        if let Some(level) = panel.contour_at {
            let mut raster = self.raster_cm(&field, &outline_cm);
            if let Some((x, y)) = self.overlay.focus_m {
                raster.keep_region_around((x * cm, y * cm), level);
            }
            let segments =
                raster.contour(level).into_iter().map(|[a, b]| PathElement::new(vec![a, b], BLACK.stroke_width(2)));
            chart.draw_series(segments).map_err(|e| e.to_string())?;
        }
        let overlay = self.overlay;
        if !outline_cm.is_empty() {
            let mut closed = outline_cm.clone();
            closed.extend(outline_cm.first().copied());
            chart.draw_series([PathElement::new(closed, BLACK.stroke_width(2))]).map_err(|e| e.to_string())?;
        }
        if !overlay.resonator_sites_m.is_empty() {
            let rods = overlay
                .resonator_sites_m
                .iter()
                .map(|&(x, y)| Circle::new((x * cm, y * cm), 1, ROD.mix(0.45).filled()));
            chart.draw_series(rods).map_err(|e| e.to_string())?;
            let mut hull: Vec<(f64, f64)> =
                convex_hull(&overlay.resonator_sites_m).iter().map(|&(x, y)| (x * cm, y * cm)).collect();
            hull.extend(hull.first().copied());
            chart.draw_series(DashedLineSeries::new(hull, 6, 4, ROD.stroke_width(2))).map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(overlay.actuators_m.iter().map(|&(x, y)| TriangleMarker::new((x * cm, y * cm), 7, BLACK)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(overlay.supports_m.iter().map(|&(x, y)| {
                let r = 0.4;
                Rectangle::new([(x * cm - r, y * cm - r), (x * cm + r, y * cm + r)], BLACK.filled())
            }))
            .map_err(|e| e.to_string())?;
        if let Some((x, y)) = overlay.focus_m {
            chart.draw_series([Circle::new((x * cm, y * cm), 9, BLACK.stroke_width(1))]).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// The image sampled at an eighth of a lattice step over the lattice and half a step beyond (positions in cm),
    /// `None` off the plate or where the image has no value: what the level line is traced on.
    fn raster_cm(&self, field: &LatticeField<'_>, outline_cm: &[(f64, f64)]) -> Raster {
        let g = &self.grid;
        let cm = 100.0;
        let step = g.spacing_m * cm / 8.0;
        let x0 = (g.origin_x_m - g.spacing_m / 2.0) * cm;
        let y0 = (g.origin_y_m - g.spacing_m / 2.0) * cm;
        let (nx, ny) = (g.nx * 8 + 1, g.ny * 8 + 1);
        let mut values = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            let y = y0 + j as f64 * step;
            let crossings = row_crossings(outline_cm, y);
            values.extend((0..nx).map(|i| {
                let x = x0 + i as f64 * step;
                match field.at(x / cm, y / cm) {
                    Sample::Value(v) if inside_row(crossings.as_deref(), x) => Some(v),
                    _ => None,
                }
            }));
        }
        Raster { x0, y0, step, nx, ny, values }
    }

    fn draw_key<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let rows = 4;
        let (column_width, row_height) = (230, 22);
        let style = TextStyle::from((FONT, 14).into_font()).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Left,
            plotters::style::text_anchor::VPos::Center,
        ));
        for (i, (key, label)) in self.key.iter().enumerate() {
            let (x, y) = (10 + (i / rows) as i32 * column_width, 12 + (i % rows) as i32 * row_height);
            let (cx, cy) = (x + 10, y);
            let mark = |e: Result<(), DrawingAreaErrorKind<DB::ErrorType>>| e.map_err(|e| e.to_string());
            match key {
                Key::Fill(c) => {
                    mark(area.draw(&Rectangle::new([(x, y - 7), (x + 20, y + 7)], c.filled())))?;
                    mark(area.draw(&Rectangle::new([(x, y - 7), (x + 20, y + 7)], BLACK.stroke_width(1))))?;
                }
                Key::Actuator => mark(area.draw(&TriangleMarker::new((cx, cy), 7, BLACK)))?,
                Key::Support => mark(area.draw(&Rectangle::new([(cx - 4, cy - 4), (cx + 4, cy + 4)], BLACK.filled())))?,
                Key::Rod => mark(area.draw(&Circle::new((cx, cy), 2, ROD.filled())))?,
                Key::Focus => mark(area.draw(&Circle::new((cx, cy), 8, BLACK.stroke_width(1))))?,
                Key::Contour => mark(area.draw(&PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2))))?,
                Key::Region => {
                    mark(area.draw(&PathElement::new(vec![(x, y), (x + 7, y)], ROD.stroke_width(2))))?;
                    mark(area.draw(&PathElement::new(vec![(x + 12, y), (x + 20, y)], ROD.stroke_width(2))))?;
                }
            }
            mark(area.draw(&Text::new(label.clone(), (x + 28, y), style.clone())))?;
        }
        Ok(())
    }
}

/// Map margins and axis-label areas, px.
const MAP_MARGIN: u32 = 10;
const X_LABELS: u32 = 40;
const Y_LABELS: u32 = 50;
/// Height of a map's caption, px (18 px text and its margins).
const CAPTION: u32 = 28;

/// Resonator rods and their region.
const ROD: RGBColor = RGBColor(70, 70, 70);

/// The frame of every map, cm: the lattice half a step beyond its points, the outline and the marks, with room.
fn frame_cm(grid: &GridSpec, overlay: &PlateOverlay) -> (f64, f64, f64, f64) {
    let cm = 100.0;
    let half = grid.spacing_m / 2.0;
    let corners = [
        (grid.origin_x_m - half, grid.origin_y_m - half),
        (
            grid.origin_x_m + grid.nx.saturating_sub(1) as f64 * grid.spacing_m + half,
            grid.origin_y_m + grid.ny.saturating_sub(1) as f64 * grid.spacing_m + half,
        ),
    ];
    let points = corners
        .iter()
        .chain(&overlay.outline_m)
        .chain(&overlay.actuators_m)
        .chain(&overlay.supports_m)
        .chain(&overlay.resonator_sites_m)
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (x0, x1, y0, y1) = points.fold((f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY), |b, p| {
        (b.0.min(p.0 * cm), b.1.max(p.0 * cm), b.2.min(p.1 * cm), b.3.max(p.1 * cm))
    });
    // Room for the marks drawn around points (triangles, the ring), 1 cm each side.
    (x0 - 1.0, x1 + 1.0, y0 - 1.0, y1 + 1.0)
}

fn draw_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    label: &str,
    lo: f64,
    hi: f64,
    colour: fn(f64) -> RGBColor,
    scale: (f64, f64),
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin_left(60)
        .margin_right(40)
        .margin_top(10)
        .margin_bottom(5)
        .x_label_area_size(50)
        .build_cartesian_2d(lo..hi, 0.0..1.0)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_y_axis()
        .x_desc(label)
        .x_label_formatter(&|v: &f64| plain_number(*v))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(|e| e.to_string())?;
    let steps = 100;
    let span = if scale.1 > scale.0 { scale.1 - scale.0 } else { 1.0 };
    chart
        .draw_series((0..steps).map(|i| {
            let a = lo + (hi - lo) * i as f64 / steps as f64;
            let b = lo + (hi - lo) * (i + 1) as f64 / steps as f64;
            Rectangle::new([(a, 0.0), (b, 1.0)], colour(((a + b) / 2.0 - scale.0) / span).filled())
        }))
        .map_err(|e| e.to_string())?;
    Ok(())
}

fn check_len(figure: &'static str, grid: &GridSpec, values: &[Option<f64>]) -> Result<(), FigureError> {
    if values.len() != grid.len() || grid.is_empty() {
        return Err(FigureError::InvalidData {
            figure,
            reason: format!("{} values for a {} x {} grid", values.len(), grid.nx, grid.ny),
        });
    }
    Ok(())
}

/// Largest finite magnitude over all `fields`; an error when there is none (or it is zero).
fn peak_magnitude(figure: &'static str, grid: &GridSpec, fields: &[&[Option<f64>]]) -> Result<f64, FigureError> {
    if fields.is_empty() {
        return Err(FigureError::InvalidData { figure, reason: "no field".to_owned() });
    }
    for values in fields {
        check_len(figure, grid, values)?;
    }
    let peak =
        fields.iter().flat_map(|v| v.iter().flatten()).filter(|v| v.is_finite()).fold(0.0, |m, v| f64::max(m, v.abs()));
    if peak <= 0.0 {
        return Err(FigureError::InvalidData { figure, reason: "no non-zero value".to_owned() });
    }
    Ok(peak)
}

/// A signed field normalised by `peak`, with its half-maximum line, on the diverging map.
fn signed_panel<'a>(title: String, values: &[Option<f64>], peak: f64) -> MapPanel<'a> {
    let values: Vec<Option<f64>> = values.iter().map(|v| v.filter(|v| v.is_finite()).map(|v| v / peak)).collect();
    let measured = values.iter().map(Option::is_some).collect::<Vec<_>>();
    MapPanel {
        title,
        values: values.into(),
        measured: measured.into(),
        colour: diverging,
        scale: (0.0, 1.0),
        contour_at: Some(0.5),
    }
}

/// The colour bar's label of a signed field normalised by its peak (the bar spans -1 to 1).
const SIGNED_BAR: &str = "velocity / peak velocity over all instants";

/// Focus snapshots (paper, Fig. 5A): the focused field at a few instants, side by side, each `(title, one value
/// per grid point or None where unmeasured)`, drawn as images on the plate: bilinear interpolation between the
/// lattice's points (no extrapolation beyond half a lattice step from a measured point), masked outside
/// `overlay.outline_m`. One diverging colour scale, normalised by the largest magnitude over all snapshots, with its
/// bar; the line at half that peak (the focus's half-maximum contour, marching squares on the interpolated image);
/// `overlay`'s outline, resonator region, actuators, supports and focus target drawn on each; `title` above all.
///
/// # Errors
/// [`FigureError::InvalidData`] for no snapshot, a snapshot not one value per grid point, or no finite value;
/// [`FigureError::Draw`], [`FigureError::Io`] when drawing or writing fails.
pub fn focus_snapshots(
    dir: &Path,
    name: &str,
    grid: &GridSpec,
    snapshots: &[(String, Vec<Option<f64>>)],
    title: &str,
    overlay: &PlateOverlay,
) -> Result<Written, FigureError> {
    let fields: Vec<&[Option<f64>]> = snapshots.iter().map(|(_, v)| v.as_slice()).collect();
    let peak = peak_magnitude("focus snapshots", grid, &fields)?;
    let panels = snapshots.iter().map(|(title, values)| signed_panel(title.clone(), values, peak)).collect();
    let figure = Maps::new(title.to_owned(), overlay, *grid, panels).with_bar(SIGNED_BAR, -1.0, 1.0, Vec::new());
    let columns = snapshots.len();
    let size = figure.size(columns, if columns > 3 { 380 } else { 520 });
    save(&figure, dir, name, (size.0.max(900), size.1))
}

/// The focusing in time as an animated PNG (paper, Fig. 5A): one frame per `(time relative to the focus time in s,
/// one value per grid point or None)`, each drawn as [`focus_snapshots`] draws a snapshot, on one diverging colour
/// scale over all frames (normalised by their largest magnitude) with its bar, the time on each frame; each frame
/// shown `frame_ms`, looping. Writes `<dir>/<name>.png` only (no SVG) and returns its path.
///
/// # Errors
/// [`FigureError::InvalidData`] for no frame, a frame not one value per grid point, no finite value or a
/// non-finite time; [`FigureError::Draw`], [`FigureError::Io`] when drawing or writing fails.
pub fn focus_animation(
    dir: &Path,
    name: &str,
    grid: &GridSpec,
    frames: &[(f64, Vec<Option<f64>>)],
    title: &str,
    overlay: &PlateOverlay,
    frame_ms: u16,
) -> Result<PathBuf, FigureError> {
    let figure = "focus animation";
    let fields: Vec<&[Option<f64>]> = frames.iter().map(|(_, v)| v.as_slice()).collect();
    let peak = peak_magnitude(figure, grid, &fields)?;
    if let Some((t, _)) = frames.iter().find(|(t, _)| !t.is_finite()) {
        return Err(FigureError::InvalidData { figure, reason: format!("frame time {t} s") });
    }
    let mut pixels = Vec::with_capacity(frames.len());
    let mut size = (0, 0);
    for (t_s, values) in frames {
        let panel = signed_panel(format!("t = {:+.1} ms", t_s * 1e3), values, peak);
        let maps = Maps::new(title.to_owned(), overlay, *grid, vec![panel]).with_bar(SIGNED_BAR, -1.0, 1.0, Vec::new());
        // Small enough that the animation stays near a megabyte: the frames' field is most of its bytes.
        size = maps.size(1, 540);
        size.0 = size.0.max(820);
        pixels.push(render_rgb(&maps, size)?);
    }
    std::fs::create_dir_all(dir).map_err(|e| FigureError::Io { path: dir.to_path_buf(), reason: e.to_string() })?;
    let path = dir.join(format!("{name}.png"));
    write_apng(&path, size, &pixels, frame_ms)?;
    Ok(path)
}

/// The virtual-pixel area (cm²) over the plate (paper, Fig. 5C), as an image (interpolated as in
/// [`focus_snapshots`]) on a viridis scale from the smallest to the largest area, with its bar. `area_cm2` holds one
/// value per grid point (`None` where there is none); `measured` one flag per grid point: a measured point without
/// an area (no closed half-maximum contour) is drawn in its own colour, distinct from unmeasured parts of the plate
/// and from the background off the plate, all three in the key. `title` goes above (for example the median).
///
/// # Errors
/// [`FigureError::InvalidData`] when `area_cm2` or `measured` is not one value per grid point or `area_cm2` holds
/// no finite value; [`FigureError::Draw`], [`FigureError::Io`] when drawing or writing fails.
pub fn pixel_area_map(
    dir: &Path,
    name: &str,
    grid: &GridSpec,
    area_cm2: &[Option<f64>],
    measured: &[bool],
    title: &str,
    overlay: &PlateOverlay,
) -> Result<Written, FigureError> {
    check_len("pixel-area map", grid, area_cm2)?;
    if measured.len() != area_cm2.len() {
        return Err(FigureError::InvalidData {
            figure: "pixel-area map",
            reason: format!("{} measured flags for {} grid points", measured.len(), area_cm2.len()),
        });
    }
    let finite = area_cm2.iter().flatten().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(FigureError::InvalidData { figure: "pixel-area map", reason: "no finite area".to_owned() });
    }
    let hi = if hi > lo { hi } else { lo + 1.0 };
    let values: Vec<Option<f64>> = area_cm2.iter().map(|v| v.filter(|v| v.is_finite())).collect();
    let panels = vec![MapPanel {
        title: String::new(),
        values: values.into(),
        measured: measured.into(),
        colour: viridis,
        scale: (lo, hi),
        contour_at: None,
    }];
    let mut key = vec![(Key::Fill(NO_VALUE), "no closed contour".to_owned())];
    if !overlay.outline_m.is_empty() {
        key.push((Key::Fill(MASKED), "on the plate, not measured".to_owned()));
        key.push((Key::Fill(WHITE), "off the plate".to_owned()));
    } else {
        key.push((Key::Fill(WHITE), "not measured".to_owned()));
    }
    let figure = Maps::new(title.to_owned(), overlay, *grid, panels).with_bar("pixel area (cm²)", lo, hi, key);
    let size = figure.size(1, 1000);
    save(&figure, dir, name, size)
}

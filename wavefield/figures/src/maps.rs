//! Maps over the measurement grid: focus snapshots and the virtual-pixel-area map.

use std::path::Path;

use metaplate_core::grid::GridSpec;
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::{MASKED, diverging, viridis};
use crate::render::{FONT, Figure, FigureError, Written, plain_number, save};

/// Values on a grid, drawn cell by cell.
struct MapPanel<'a> {
    title: String,
    values: std::borrow::Cow<'a, [Option<f64>]>,
    colour: fn(f64) -> RGBColor,
    /// Maps a value to the colour map's argument.
    scale: (f64, f64),
    /// Outline the cells whose value is at least this (the focus's half-maximum region); `None`: no outline.
    outline_at: Option<f64>,
}

/// What is drawn over a map: where the plate is driven and held, in the grid's frame (m).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlateOverlay {
    /// Actuator positions, m: drawn as black triangles.
    pub actuators_m: Vec<(f64, f64)>,
    /// Support positions, m: drawn as black squares.
    pub supports_m: Vec<(f64, f64)>,
}

struct Maps<'a> {
    /// Above every panel: what the figure shows, with its numbers.
    title: String,
    overlay: &'a PlateOverlay,
    grid: GridSpec,
    panels: Vec<MapPanel<'a>>,
    /// A colour bar under the maps: (label, low, high).
    bar: Option<(String, f64, f64)>,
}

impl Figure for Maps<'_> {
    const NAME: &'static str = "map";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root.titled(&self.title, (FONT, 17)).map_err(|e| e.to_string())?;
        let (maps, bar_area) = match self.bar {
            Some(_) => {
                let h = root.dim_in_pixel().1;
                root.split_vertically(h.saturating_sub(100))
            }
            None => root.split_vertically(root.dim_in_pixel().1),
        };
        let areas = maps.split_evenly((1, self.panels.len().max(1)));
        for (panel, area) in self.panels.iter().zip(&areas) {
            self.draw_map(area, panel)?;
        }
        if let Some((label, lo, hi)) = &self.bar
            && let Some(panel) = self.panels.first()
        {
            draw_bar(&bar_area, label, *lo, *hi, panel.colour, panel.scale)?;
        }
        Ok(())
    }
}

impl Maps<'_> {
    fn draw_map<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, panel: &MapPanel<'_>) -> Result<(), String> {
        let g = &self.grid;
        let cm = 100.0;
        let half = g.spacing_m / 2.0 * cm;
        let x0 = g.origin_x_m * cm - half;
        let y0 = g.origin_y_m * cm - half;
        let x1 = (g.origin_x_m + (g.nx.saturating_sub(1)) as f64 * g.spacing_m) * cm + half;
        let y1 = (g.origin_y_m + (g.ny.saturating_sub(1)) as f64 * g.spacing_m) * cm + half;
        // Actuators may sit outside the measured grid (on the plate's rim): widen the frame to show them.
        let marks = self.overlay.actuators_m.iter().chain(&self.overlay.supports_m).map(|&(x, y)| (x * cm, y * cm));
        let (x0, x1, y0, y1) = marks.fold((x0, x1, y0, y1), |(a, b, c, d), (x, y)| {
            (a.min(x - 1.0), b.max(x + 1.0), c.min(y - 1.0), d.max(y + 1.0))
        });
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, (FONT, 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
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
        let (lo, hi) = panel.scale;
        let span = if hi > lo { hi - lo } else { 1.0 };
        chart
            .draw_series(panel.values.iter().enumerate().map(|(i, v)| {
                let (x, y) = g.position_m(i);
                let colour = match v {
                    Some(v) if v.is_finite() => (panel.colour)((v - lo) / span),
                    _ => MASKED,
                };
                Rectangle::new([(x * cm - half, y * cm - half), (x * cm + half, y * cm + half)], colour.filled())
            }))
            .map_err(|e| e.to_string())?;
        if let Some(level) = panel.outline_at {
            let inside = |ix: isize, iy: isize| {
                ix >= 0
                    && iy >= 0
                    && (ix as usize) < g.nx
                    && (iy as usize) < g.ny
                    && panel.values[g.index(ix as usize, iy as usize)].is_some_and(|v| v >= level)
            };
            // Each cell edge between a cell inside and one outside: the region's boundary, cell by cell.
            let mut edges = Vec::new();
            for iy in 0..g.ny as isize {
                for ix in 0..g.nx as isize {
                    if !inside(ix, iy) {
                        continue;
                    }
                    let (x, y) = g.position_m(g.index(ix as usize, iy as usize));
                    let (l, r, b, t) = (x * cm - half, x * cm + half, y * cm - half, y * cm + half);
                    for (dx, dy, a, z) in [
                        (-1, 0, (l, b), (l, t)),
                        (1, 0, (r, b), (r, t)),
                        (0, -1, (l, b), (r, b)),
                        (0, 1, (l, t), (r, t)),
                    ] {
                        if !inside(ix + dx, iy + dy) {
                            edges.push(PathElement::new(vec![a, z], BLACK.stroke_width(2)));
                        }
                    }
                }
            }
            chart.draw_series(edges).map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(self.overlay.actuators_m.iter().map(|&(x, y)| TriangleMarker::new((x * cm, y * cm), 7, BLACK)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(self.overlay.supports_m.iter().map(|&(x, y)| {
                let r = 0.4;
                Rectangle::new([(x * cm - r, y * cm - r), (x * cm + r, y * cm + r)], BLACK.filled())
            }))
            .map_err(|e| e.to_string())?;
        Ok(())
    }
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
        .margin_right(60)
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

/// Focus snapshots (paper, Fig. 4A, B): the focused field on the grid at a few instants, side by side, each
/// `(title, one value per grid point or None where unmeasured)`; a common diverging colour scale, normalised by the
/// largest magnitude over all snapshots, on a continuous red-blue map with its bar; `title` above all of them;
/// `overlay`'s actuators and supports drawn on each, and the cells at or above half the peak outlined in black (the
/// focus's half-maximum region, at the focus time).
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
    if snapshots.is_empty() {
        return Err(FigureError::InvalidData { figure: "focus snapshots", reason: "no snapshot".to_owned() });
    }
    for (_, values) in snapshots {
        check_len("focus snapshots", grid, values)?;
    }
    let peak = snapshots
        .iter()
        .flat_map(|(_, v)| v.iter().flatten())
        .filter(|v| v.is_finite())
        .fold(0.0, |m, v| f64::max(m, v.abs()));
    if peak <= 0.0 {
        return Err(FigureError::InvalidData { figure: "focus snapshots", reason: "no non-zero value".to_owned() });
    }
    // Normalised by the peak, so that the bar's -1 to 1 and the maps' colours are one scale.
    let panels = snapshots
        .iter()
        .map(|(title, values)| MapPanel {
            title: title.clone(),
            values: values.iter().map(|v| v.map(|v| v / peak)).collect::<Vec<_>>().into(),
            colour: diverging,
            scale: (0.0, 1.0),
            outline_at: Some(0.5),
        })
        .collect();
    let figure = Maps {
        title: title.to_owned(),
        overlay,
        grid: *grid,
        panels,
        bar: Some(("velocity / peak velocity over all instants (black outline: at least 0.5)".to_owned(), -1.0, 1.0)),
    };
    let width = 420 * snapshots.len().min(6) as u32;
    save(&figure, dir, name, (width.max(600), 420))
}

/// The virtual-pixel area (cm^2) at each grid point where it was measured (paper, Fig. 4C), `None` elsewhere, on
/// a viridis scale from the smallest to the largest area; `title` goes above (for example the median).
///
/// # Errors
/// [`FigureError::InvalidData`] when `area_cm2` is not one value per grid point or holds no finite value;
/// [`FigureError::Draw`], [`FigureError::Io`] when drawing or writing fails.
pub fn pixel_area_map(
    dir: &Path,
    name: &str,
    grid: &GridSpec,
    area_cm2: &[Option<f64>],
    title: &str,
    overlay: &PlateOverlay,
) -> Result<Written, FigureError> {
    check_len("pixel-area map", grid, area_cm2)?;
    let finite = area_cm2.iter().flatten().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(FigureError::InvalidData { figure: "pixel-area map", reason: "no finite area".to_owned() });
    }
    let hi = if hi > lo { hi } else { lo + 1.0 };
    let panels = vec![MapPanel {
        title: String::new(),
        values: area_cm2.into(),
        colour: viridis,
        scale: (lo, hi),
        outline_at: None,
    }];
    let figure = Maps {
        title: title.to_owned(),
        overlay,
        grid: *grid,
        panels,
        bar: Some(("pixel area (cm²)".to_owned(), lo, hi)),
    };
    save(&figure, dir, name, (1150, 620))
}

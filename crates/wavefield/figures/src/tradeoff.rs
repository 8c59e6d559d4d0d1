//! The speed/accuracy trade of scan protocols: time per point (log scale) against median Green's-function error,
//! every protocol a labelled point, the Pareto front (no other protocol both faster and more accurate) joined.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::PALETTE;
use crate::render::{FONT, Figure, FigureError, Ticked, Written, axis_range, plain_number, save};

/// One protocol's measured trade.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeoffPoint {
    /// Protocol name (the point's label).
    pub label: String,
    /// Rig-clock time per grid point, s (> 0; others are skipped).
    pub time_per_point_s: f64,
    /// Median error against the ground truth, dB.
    pub median_error_db: f64,
}

struct Tradeoff<'a> {
    title: &'a str,
    points: Vec<&'a TradeoffPoint>,
}

impl Figure for Tradeoff<'_> {
    const NAME: &'static str = "trade-off";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let xy: Vec<(f64, f64, &str)> =
            self.points.iter().map(|p| (p.time_per_point_s.log10(), p.median_error_db, p.label.as_str())).collect();
        let (Some((x0, x1)), Some((y0, y1))) =
            (axis_range(xy.iter().map(|p| p.0), 0.1), axis_range(xy.iter().map(|p| p.1), 0.1))
        else {
            return Err("no finite point to plot".to_owned());
        };
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, (FONT, 20))
            .margin(16)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(Ticked::log(x0, x1), y0..y1)
            .map_err(|e| e.to_string())?;
        let x_fmt = |v: &f64| plain_number(10f64.powf(*v));
        chart
            .configure_mesh()
            .x_desc("time per point, s (log scale)")
            .y_desc("median error vs truth, dB")
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .x_label_formatter(&x_fmt)
            .draw()
            .map_err(|e| e.to_string())?;
        // The front: sorted by time, each point more accurate than every faster one.
        let mut sorted = xy.clone();
        sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for p in &sorted {
            if p.1 < best {
                best = p.1;
                front.push((p.0, p.1));
            }
        }
        let colour = PALETTE[0];
        chart.draw_series(LineSeries::new(front, colour.stroke_width(2))).map_err(|e| e.to_string())?;
        chart
            .draw_series(xy.iter().map(|&(x, y, _)| Circle::new((x, y), 5, PALETTE[1 % PALETTE.len()].filled())))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(xy.iter().map(|&(x, y, label)| Text::new(label.to_string(), (x, y), (FONT, 13).into_font())))
            .map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// Writes `<dir>/<name>.png` and `.svg`: time per point against median error, one labelled point per protocol,
/// the Pareto front joined. Points with a non-positive or non-finite time or a non-finite error are skipped.
///
/// # Errors
/// [`FigureError::Draw`] when no point is plottable; [`FigureError::Io`] / [`FigureError::Font`] as
/// [`crate::Written`]'s other producers.
pub fn tradeoff(dir: &Path, name: &str, points: &[TradeoffPoint], title: &str) -> Result<Written, FigureError> {
    let points = points
        .iter()
        .filter(|p| p.time_per_point_s > 0.0 && p.time_per_point_s.is_finite() && p.median_error_db.is_finite())
        .collect();
    save(&Tradeoff { title, points }, dir, name, (900, 600))
}

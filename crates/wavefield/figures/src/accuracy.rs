//! Behavioural results: accuracy per participant with its Wilson 95 % interval and the chance line (the paper's
//! Fig. 8, right-hand panels).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::PALETTE;
use crate::render::{FONT, Figure, FigureError, Written, save};

/// One participant's (or the pool's) accuracy.
#[derive(Debug, Clone, PartialEq)]
pub struct AccuracyBar {
    /// The x label (participant id, or `all`).
    pub label: String,
    /// Fraction correct, 0 to 1.
    pub accuracy: f64,
    /// Wilson 95 % interval, fractions.
    pub wilson_95: [f64; 2],
}

struct Accuracy<'a> {
    title: &'a str,
    bars: Vec<&'a AccuracyBar>,
    chance: f64,
}

impl Figure for Accuracy<'_> {
    const NAME: &'static str = "accuracy";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let n = self.bars.len();
        if n == 0 {
            return Err("no participant to plot".to_owned());
        }
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, (FONT, 20))
            .margin(16)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, 0.0..105.0)
            .map_err(|e| e.to_string())?;
        let labels: Vec<String> = self.bars.iter().map(|b| b.label.clone()).collect();
        let x_fmt = |v: &f64| {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 {
                labels.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_labels(n.max(2))
            .x_desc("participant")
            .y_desc("correct, %")
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 15))
            .x_label_formatter(&x_fmt)
            .disable_x_mesh()
            .draw()
            .map_err(|e| e.to_string())?;
        let chance = self.chance * 100.0;
        chart
            .draw_series(LineSeries::new([(-0.5, chance), (n as f64 - 0.5, chance)], PALETTE[1].stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(format!("chance {chance:.0} %"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], PALETTE[1].stroke_width(2)));
        let colour = PALETTE[0];
        for (i, b) in self.bars.iter().enumerate() {
            let x = i as f64;
            let (lo, hi) = (b.wilson_95[0] * 100.0, b.wilson_95[1] * 100.0);
            chart
                .draw_series([
                    PathElement::new([(x, lo), (x, hi)], colour.stroke_width(2)),
                    PathElement::new([(x - 0.15, lo), (x + 0.15, lo)], colour.stroke_width(2)),
                    PathElement::new([(x - 0.15, hi), (x + 0.15, hi)], colour.stroke_width(2)),
                ])
                .map_err(|e| e.to_string())?;
            chart.draw_series([Circle::new((x, b.accuracy * 100.0), 5, colour.filled())]).map_err(|e| e.to_string())?;
        }
        chart
            .configure_series_labels()
            .label_font((FONT, 13))
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// Writes `<dir>/accuracy.png` and `.svg`: each bar's accuracy (percent) with its Wilson 95 % interval as an error
/// bar, and the chance line. Bars with a non-finite accuracy or interval are skipped.
///
/// # Errors
/// [`FigureError::Draw`] when no bar is plottable; [`FigureError::Io`] / [`FigureError::Font`] as
/// [`crate::Written`]'s other producers.
pub fn accuracy(dir: &Path, title: &str, bars: &[AccuracyBar], chance: f64) -> Result<Written, FigureError> {
    let bars = bars.iter().filter(|b| b.accuracy.is_finite() && b.wilson_95.iter().all(|v| v.is_finite())).collect();
    save(&Accuracy { title, bars, chance }, dir, "accuracy", (900, 600))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn the_accuracy_figure_is_written_and_refuses_no_bars() {
        let dir = tempfile::tempdir().unwrap();
        let bars = [
            AccuracyBar { label: "P01".into(), accuracy: 0.98, wilson_95: [0.9, 0.99] },
            AccuracyBar { label: "all".into(), accuracy: 0.986, wilson_95: [0.97, 0.993] },
        ];
        let w = accuracy(dir.path(), "pixel identification", &bars, 0.2).unwrap();
        assert!(w.png.exists() && w.svg.exists());
        assert!(accuracy(dir.path(), "none", &[], 0.2).is_err());
    }
}

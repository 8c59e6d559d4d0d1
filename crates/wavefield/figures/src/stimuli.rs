//! An experiment's stimuli as the fingertips would feel them: the predicted velocity at each pixel over time, one
//! panel per stimulus, the pixels stacked top to bottom on one scale (the paper's Figs. S8 to S11, which show each
//! experiment's stimuli at the five pixels). Targets are drawn in colour, nulls in grey, a distractor's pixels in a
//! second colour: a well-focused stimulus shows its targets and flat lines elsewhere.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::PALETTE;
use crate::render::{FONT, Figure, FigureError, Written, save};

/// What a pixel does in a stimulus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelRole {
    /// What the participant must find.
    Target,
    /// Actively suppressed.
    Null,
    /// Plays something else (a distractor).
    Other,
}

/// One pixel's predicted velocity in a stimulus.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelTrace {
    /// The pixel's name (the y label).
    pub label: String,
    /// What the pixel does.
    pub role: PixelRole,
    /// Predicted velocity, mm/s, at the panel's sample rate from its `start_s`.
    pub velocity_mm_s: Vec<f64>,
}

/// One stimulus: its pixels' traces on a common time axis.
#[derive(Debug, Clone, PartialEq)]
pub struct StimulusPanel {
    /// The stimulus (the panel's title).
    pub title: String,
    /// Samples per second of the traces, Hz.
    pub sample_rate_hz: f64,
    /// Time of the traces' first sample, s (relative to the stimulus's onset).
    pub start_s: f64,
    /// One per pixel, drawn top to bottom in this order.
    pub traces: Vec<PixelTrace>,
}

/// Points a trace is drawn with at most: longer traces are reduced to each bucket's minimum and maximum, which keeps
/// every peak (what the eye compares) and the SVG small.
const MAX_POINTS: usize = 1600;

struct Stimuli<'a> {
    title: &'a str,
    panels: &'a [StimulusPanel],
    /// The largest |v| of all traces, mm/s: every lane's half-height.
    scale_mm_s: f64,
}

/// `(t, v)` points of `trace` at `rate_hz` from `start_s`, min-max reduced to at most [`MAX_POINTS`].
fn points(trace: &[f64], rate_hz: f64, start_s: f64) -> Vec<(f64, f64)> {
    let bucket = trace.len().div_ceil(MAX_POINTS / 2).max(1);
    let mut out = Vec::with_capacity(2 * trace.len().div_ceil(bucket));
    for (k, chunk) in trace.chunks(bucket).enumerate() {
        let t = start_s + (k * bucket) as f64 / rate_hz;
        if bucket == 1 {
            out.push((t, chunk[0]));
            continue;
        }
        let (lo, hi) = chunk.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        out.push((t, lo));
        out.push((t + (bucket / 2) as f64 / rate_hz, hi));
    }
    out
}

impl Figure for Stimuli<'_> {
    const NAME: &'static str = "stimuli";

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let body = root.titled(self.title, (FONT, 18)).map_err(|e| e.to_string())?;
        let legend =
            format!("each lane +/- {:.2} mm/s; red: target, blue: other (a distractor), grey: null", self.scale_mm_s);
        let body = body.titled(&legend, (FONT, 13)).map_err(|e| e.to_string())?;
        let columns = if self.panels.len() > 5 { 2 } else { 1 };
        let rows = self.panels.len().div_ceil(columns);
        let areas = body.split_evenly((rows, columns));
        for (panel, area) in self.panels.iter().zip(&areas) {
            let lanes = panel.traces.len();
            let end_s = panel.start_s
                + panel.traces.iter().map(|t| t.velocity_mm_s.len()).max().unwrap_or(0) as f64 / panel.sample_rate_hz;
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, (FONT, 14))
                .margin(6)
                .x_label_area_size(28)
                .y_label_area_size(60)
                .build_cartesian_2d(panel.start_s..end_s.max(panel.start_s + 1e-3), -0.6..lanes as f64 - 0.4)
                .map_err(|e| e.to_string())?;
            let labels: Vec<&str> = panel.traces.iter().map(|t| t.label.as_str()).collect();
            let lane_label = |y: &f64| {
                let i = y.round();
                let lane = lanes as f64 - 1.0 - i;
                if (y - i).abs() < 1e-6 && lane >= 0.0 {
                    labels.get(lane as usize).map(|s| (*s).to_owned()).unwrap_or_default()
                } else {
                    String::new()
                }
            };
            chart
                .configure_mesh()
                .y_labels(lanes.max(2))
                .y_label_formatter(&lane_label)
                .x_desc("time from onset, s")
                .label_style((FONT, 11))
                .axis_desc_style((FONT, 11))
                .disable_y_mesh()
                .light_line_style(TRANSPARENT)
                .draw()
                .map_err(|e| e.to_string())?;
            for (k, trace) in panel.traces.iter().enumerate() {
                let lane = (lanes - 1 - k) as f64;
                let colour = match trace.role {
                    PixelRole::Target => PALETTE[0].to_rgba(),
                    PixelRole::Null => RGBColor(150, 150, 150).to_rgba(),
                    PixelRole::Other => PALETTE[1].to_rgba(),
                };
                let gain = 0.45 / self.scale_mm_s;
                let pts = points(&trace.velocity_mm_s, panel.sample_rate_hz, panel.start_s);
                chart
                    .draw_series(LineSeries::new(pts.into_iter().map(|(t, v)| (t, lane + gain * v)), colour))
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    }
}

/// Writes `<dir>/<name>.png` and `.svg`: one panel per stimulus of `panels` (two columns beyond five), each pixel's
/// predicted velocity in its lane, every lane on the scale of the largest |v| of all (written in the title).
///
/// # Errors
/// [`FigureError::InvalidData`] for no panels, a panel without traces, a non-finite or non-positive sample rate, a
/// non-finite start, a non-finite sample, or all traces silent; [`FigureError::Draw`], [`FigureError::Io`] and
/// [`FigureError::Font`] as for every figure.
pub fn stimuli(dir: &Path, name: &str, title: &str, panels: &[StimulusPanel]) -> Result<Written, FigureError> {
    let invalid = |reason: String| FigureError::InvalidData { figure: "stimuli", reason };
    if panels.is_empty() {
        return Err(invalid("no stimulus to plot".into()));
    }
    for p in panels {
        if p.traces.is_empty() {
            return Err(invalid(format!("stimulus `{}` has no pixel", p.title)));
        }
        if !(p.sample_rate_hz.is_finite() && p.sample_rate_hz > 0.0 && p.start_s.is_finite()) {
            return Err(invalid(format!(
                "stimulus `{}`: a sample rate of {} Hz from {} s",
                p.title, p.sample_rate_hz, p.start_s
            )));
        }
        if let Some(t) = p.traces.iter().find(|t| t.velocity_mm_s.iter().any(|v| !v.is_finite())) {
            return Err(invalid(format!("stimulus `{}`, pixel `{}`: a non-finite sample", p.title, t.label)));
        }
    }
    let scale_mm_s =
        panels.iter().flat_map(|p| &p.traces).flat_map(|t| &t.velocity_mm_s).fold(0.0f64, |m, v| m.max(v.abs()));
    if scale_mm_s <= 0.0 {
        return Err(invalid("every trace is silent".into()));
    }
    let columns = if panels.len() > 5 { 2 } else { 1 };
    let rows = panels.len().div_ceil(columns) as u32;
    let lanes = panels.iter().map(|p| p.traces.len()).max().unwrap_or(1) as u32;
    let size = (if columns == 2 { 1400 } else { 900 }, 80 + rows * (70 + 28 * lanes));
    save(&Stimuli { title, panels, scale_mm_s }, dir, name, size)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    fn panel(title: &str, target_lane: usize, len: usize) -> StimulusPanel {
        let burst: Vec<f64> =
            (0..len).map(|i| 3.0 * (i as f64 * 0.3).sin() * f64::from(u8::from(i % 400 < 100))).collect();
        let traces = (0..5)
            .map(|k| PixelTrace {
                label: format!("finger {k}"),
                role: if k == target_lane { PixelRole::Target } else { PixelRole::Null },
                velocity_mm_s: if k == target_lane { burst.clone() } else { burst.iter().map(|v| v * 0.01).collect() },
            })
            .collect();
        StimulusPanel { title: title.into(), sample_rate_hz: 4000.0, start_s: -0.01, traces }
    }

    #[test]
    fn the_figure_is_written_with_long_traces_reduced_and_bad_data_refused() {
        let dir = tempfile::tempdir().unwrap();
        // Ten stimuli of 2 s at 4 kHz (8000 samples a trace): two columns; the SVG stays small.
        let panels: Vec<StimulusPanel> = (0..10).map(|k| panel(&format!("at-{k}"), k % 5, 8000)).collect();
        let w = stimuli(dir.path(), "odd-one-out", "odd one out", &panels).unwrap();
        assert!(w.png.exists());
        let svg_bytes = std::fs::metadata(&w.svg).unwrap().len();
        assert!(svg_bytes < 3_000_000, "{svg_bytes} bytes");

        let mut silent = panel("quiet", 0, 100);
        silent.traces.iter_mut().for_each(|t| t.velocity_mm_s.iter_mut().for_each(|v| *v = 0.0));
        let mut nan = panel("nan", 0, 100);
        nan.traces[2].velocity_mm_s[5] = f64::NAN;
        let mut empty = panel("empty", 0, 100);
        empty.traces.clear();
        for (panels, needle) in [
            (vec![], "no stimulus"),
            (vec![silent], "silent"),
            (vec![nan], "pixel `finger 2`: a non-finite sample"),
            (vec![empty], "has no pixel"),
        ] {
            let err = stimuli(dir.path(), "bad", "bad", &panels).unwrap_err();
            assert!(err.to_string().contains(needle), "{err}");
        }
    }

    #[test]
    fn a_reduced_trace_keeps_every_peak() {
        let mut trace = vec![0.0; 100_000];
        trace[31_337] = 5.0;
        trace[77_777] = -4.0;
        let pts = points(&trace, 1000.0, 0.0);
        assert!(pts.len() <= MAX_POINTS + 2, "{}", pts.len());
        assert!(pts.iter().any(|p| p.1 == 5.0) && pts.iter().any(|p| p.1 == -4.0));
        // A short trace is drawn as it is.
        assert_eq!(points(&[1.0, 2.0], 10.0, 1.0), [(1.0, 1.0), (1.1, 2.0)]);
    }
}

//! The measurement grid as inline SVG for a page: each grid point a cell coloured by its status, or by its
//! signal-to-noise ratio on a fixed scale, with a legend. Plain data in, an SVG string out: no file is written and
//! no font is embedded (text takes the page's sans-serif).
//!
//! Row `iy = 0` (the lowest y) is drawn at the bottom, as on the plate and in the other maps.

use std::fmt::Write as _;

use crate::colour::viridis;

/// What a grid point is, as the status map colours it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellStatus {
    /// Not part of the plan (off the plate, on a support, or outside the scanned subset).
    NotPlanned,
    /// Planned, not committed yet.
    Pending,
    /// Committed, every actuator within the quality limits at the first attempt.
    Measured,
    /// Committed after a re-measure.
    ReMeasured,
    /// The vibrometer or the DAQ clipped on some actuator.
    Overrange,
    /// The signal dropped out on some actuator.
    Dropout,
    /// Every attempt failed on some actuator.
    Failed,
}

impl CellStatus {
    /// Every status in legend order.
    pub const ALL: [CellStatus; 7] = [
        CellStatus::Measured,
        CellStatus::ReMeasured,
        CellStatus::Overrange,
        CellStatus::Dropout,
        CellStatus::Failed,
        CellStatus::Pending,
        CellStatus::NotPlanned,
    ];

    /// The legend's word.
    pub fn label(self) -> &'static str {
        match self {
            CellStatus::NotPlanned => "not planned",
            CellStatus::Pending => "pending",
            CellStatus::Measured => "measured",
            CellStatus::ReMeasured => "re-measured",
            CellStatus::Overrange => "overrange",
            CellStatus::Dropout => "dropout",
            CellStatus::Failed => "failed",
        }
    }

    /// Fill colour, CSS hex: a colour-blind-safe set (Okabe-Ito) for the measured states, greys for the others.
    fn fill(self) -> &'static str {
        match self {
            CellStatus::NotPlanned => "#ffffff",
            CellStatus::Pending => "#d9d9d9",
            CellStatus::Measured => "#009e73",
            CellStatus::ReMeasured => "#56b4e9",
            CellStatus::Overrange => "#e69f00",
            CellStatus::Dropout => "#cc79a7",
            CellStatus::Failed => "#d55e00",
        }
    }
}

/// Largest cell edge, px: small grids stay a readable size rather than filling the width.
const MAX_CELL_PX: usize = 24;
/// Height of the legend under the cells, px (two lines of the status legend, or the colour bar and its labels).
const LEGEND_PX: usize = 46;
/// Narrowest map, px: room for the legend under a small grid.
const MIN_WIDTH_PX: usize = 360;

/// The grid (`nx` by `ny`, cells indexed `iy * nx + ix`) coloured by status, about `width_px` wide, with a legend
/// counting each status. Cells beyond `cells.len()` are drawn as not planned.
pub fn status_map_svg(nx: usize, ny: usize, cells: &[CellStatus], width_px: usize) -> String {
    let cell = cell_px(nx, width_px);
    let fill = |i: usize| cells.get(i).copied().unwrap_or(CellStatus::NotPlanned).fill().to_owned();
    let mut svg = open_svg(nx, ny, cell, "grid points by status");
    draw_cells(&mut svg, nx, ny, cell, fill);
    let (mut x, mut y) = (0, ny * cell + 8);
    let width = (nx * cell).max(MIN_WIDTH_PX);
    for status in CellStatus::ALL {
        let count = cells.iter().filter(|c| **c == status).count();
        let text = format!("{} {count}", status.label());
        // About 7 px per character of 12 px text, a swatch and a gap: wrap to the next line when it would not fit.
        let item_px = 24 + 7 * text.len();
        if x > 0 && x + item_px > width {
            (x, y) = (0, y + 18);
        }
        let _ = write!(
            svg,
            r##"<rect x="{x}" y="{y}" width="12" height="12" fill="{}" stroke="#888"/><text x="{}" y="{}" font-size="12">{text}</text>"##,
            status.fill(),
            x + 16,
            y + 11,
        );
        x += item_px;
    }
    svg.push_str("</svg>");
    svg
}

/// The grid coloured by SNR (dB) on the fixed scale `scale_db` (low, high; values outside are drawn at the ends),
/// about `width_px` wide, with a labelled colour bar. `None` (not measured) and non-finite cells are light grey.
pub fn snr_map_svg(nx: usize, ny: usize, snr_db: &[Option<f64>], scale_db: (f64, f64), width_px: usize) -> String {
    let cell = cell_px(nx, width_px);
    let span = scale_db.1 - scale_db.0;
    let t = |v: f64| if span > 0.0 { ((v - scale_db.0) / span).clamp(0.0, 1.0) } else { 0.0 };
    let hex = |t: f64| {
        let c = viridis(t);
        format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
    };
    let fill = |i: usize| match snr_db.get(i).copied().flatten() {
        Some(v) if v.is_finite() => hex(t(v)),
        _ => "#ececec".to_owned(),
    };
    let mut svg = open_svg(nx, ny, cell, "signal-to-noise ratio per grid point");
    draw_cells(&mut svg, nx, ny, cell, fill);
    // The bar: 20 steps of the map, the scale's ends and middle labelled.
    let (y0, bar_w) = (ny * cell + 8, (nx * cell).clamp(120, 360));
    let steps = 20;
    for k in 0..steps {
        let _ = write!(
            svg,
            r#"<rect x="{}" y="{y0}" width="{}" height="12" fill="{}"/>"#,
            k * bar_w / steps,
            bar_w / steps + 1,
            hex((k as f64 + 0.5) / steps as f64),
        );
    }
    let mid = (scale_db.0 + scale_db.1) / 2.0;
    for (x, anchor, v) in [(0, "start", scale_db.0), (bar_w / 2, "middle", mid), (bar_w, "end", scale_db.1)] {
        let _ = write!(svg, r#"<text x="{x}" y="{}" font-size="12" text-anchor="{anchor}">{v:.0}</text>"#, y0 + 26);
    }
    let _ = write!(svg, r#"<text x="{}" y="{}" font-size="12">SNR, dB</text>"#, bar_w + 8, y0 + 11);
    svg.push_str("</svg>");
    svg
}

fn cell_px(nx: usize, width_px: usize) -> usize {
    (width_px / nx.max(1)).clamp(2, MAX_CELL_PX)
}

fn open_svg(nx: usize, ny: usize, cell: usize, title: &str) -> String {
    let (w, h) = ((nx * cell).max(MIN_WIDTH_PX), ny * cell + LEGEND_PX);
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" role="img"><title>{title}</title>"#
    )
}

fn draw_cells(svg: &mut String, nx: usize, ny: usize, cell: usize, fill: impl Fn(usize) -> String) {
    let _ =
        write!(svg, r##"<rect x="0" y="0" width="{}" height="{}" fill="none" stroke="#888"/>"##, nx * cell, ny * cell);
    for iy in 0..ny {
        for ix in 0..nx {
            let (x, y) = (ix * cell, (ny - 1 - iy) * cell);
            let _ = write!(
                svg,
                r#"<rect x="{x}" y="{y}" width="{cell}" height="{cell}" fill="{}"><title>ix {ix}, iy {iy}</title></rect>"#,
                fill(iy * nx + ix),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(svg: &str, needle: &str) -> usize {
        svg.matches(needle).count()
    }

    #[test]
    fn every_cell_is_drawn_once_with_its_status_colour_and_counted_in_the_legend() {
        let (nx, ny) = (4, 3);
        let mut cells = vec![CellStatus::Measured; nx * ny];
        cells[0] = CellStatus::Failed; // ix 0, iy 0: bottom left.
        cells[11] = CellStatus::Pending;
        let svg = status_map_svg(nx, ny, &cells, 400);
        assert_eq!(count(&svg, "<title>ix "), nx * ny);
        // Cell edge 24 px (capped): iy 0 sits in the bottom row, y = 2 * 24.
        assert!(
            svg.contains(r##"<rect x="0" y="48" width="24" height="24" fill="#d55e00"><title>ix 0, iy 0"##),
            "{svg}"
        );
        assert!(svg.contains("measured 10<") && svg.contains("failed 1<") && svg.contains("pending 1<"), "{svg}");
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
    }

    #[test]
    fn snr_cells_take_the_fixed_scale_and_clamp_beyond_it() {
        let snr = [Some(0.0), Some(60.0), Some(500.0), None, Some(f64::NAN), Some(-10.0)];
        let svg = snr_map_svg(3, 2, &snr, (0.0, 60.0), 300);
        let lo = viridis(0.0);
        let hi = viridis(1.0);
        let lo = format!("#{:02x}{:02x}{:02x}", lo.0, lo.1, lo.2);
        let hi = format!("#{:02x}{:02x}{:02x}", hi.0, hi.1, hi.2);
        // Cells 0 (0 dB) and 5 (-10 dB, clamped) at the low end; 1 and 2 (clamped) at the high end; 3 and 4 grey.
        assert_eq!(count(&svg, &format!(r#"fill="{lo}"><title>"#)), 2, "{svg}");
        assert_eq!(count(&svg, &format!(r#"fill="{hi}"><title>"#)), 2, "{svg}");
        assert_eq!(count(&svg, r##"fill="#ececec"><title>"##), 2);
        assert!(svg.contains(">60</text>") && svg.contains(">30</text>") && svg.contains("SNR, dB"));
    }

    #[test]
    fn a_degenerate_grid_or_scale_still_gives_a_well_formed_svg() {
        let svg = status_map_svg(0, 0, &[], 0);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        let svg = snr_map_svg(1, 1, &[Some(5.0)], (10.0, 10.0), 10);
        assert!(svg.ends_with("</svg>") && !svg.contains("NaN"));
    }
}

//! Rendering one figure to PNG and SVG with the bundled font.

use std::fs;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::glyphs::Glyphs;

/// The bundled font: DejaVu Sans (see `fonts/LICENSE-DejaVu.txt`).
const FONT_TTF: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// The family name every figure uses; the bundled font is registered under it.
pub(crate) const FONT: &str = "sans-serif";

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The data cannot be plotted (empty, mismatched lengths, nothing finite).
    #[error("figure {figure}: {reason}")]
    InvalidData {
        /// Which figure.
        figure: &'static str,
        /// What was wrong.
        reason: String,
    },
    /// The bundled font could not be loaded (a corrupt build).
    #[error("the bundled font could not be loaded")]
    Font,
    /// Plotters failed while drawing.
    #[error("drawing {figure}: {reason}")]
    Draw {
        /// Which figure.
        figure: &'static str,
        /// Plotters' message.
        reason: String,
    },
    /// A file could not be written.
    #[error("writing {path}: {reason}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's message.
        reason: String,
    },
}

/// The files one figure was written to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Written {
    /// The PNG file.
    pub png: PathBuf,
    /// The SVG file.
    pub svg: PathBuf,
}

/// Something that draws itself on any plotters backend.
pub(crate) trait Figure {
    /// Name for error messages.
    const NAME: &'static str;
    /// Draws the whole figure on `root`.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
    /// Draws the whole figure for a vector backend (SVG): as [`Figure::draw`] unless the figure holds images,
    /// which it then draws as coarser cells (an image pixel by pixel would make the SVG megabytes long).
    fn draw_vector<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        self.draw(root)
    }
}

/// Registers the bundled font once.
fn font() -> Result<(), FigureError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FONT, FontStyle::Normal, FONT_TTF).is_ok());
    if ok { Ok(()) } else { Err(FigureError::Font) }
}

/// Draws `figure` at `size` pixels and writes `<dir>/<name>.png` and `<dir>/<name>.svg`.
pub(crate) fn save<F: Figure>(figure: &F, dir: &Path, name: &str, size: (u32, u32)) -> Result<Written, FigureError> {
    let pixels = render_rgb(figure, size)?;
    let draw_error = |reason: String| FigureError::Draw { figure: F::NAME, reason };
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        figure.draw_vector(&root).map_err(draw_error)?;
        root.present().map_err(|e| draw_error(e.to_string()))?;
    }
    // Only now, with both drawn, touch the file system: a figure that cannot be drawn leaves nothing behind.
    fs::create_dir_all(dir).map_err(|e| FigureError::Io { path: dir.to_path_buf(), reason: e.to_string() })?;
    let png = dir.join(format!("{name}.png"));
    write_png(&png, size, &pixels)?;
    let svg = dir.join(format!("{name}.svg"));
    fs::write(&svg, text).map_err(|e| FigureError::Io { path: svg.clone(), reason: e.to_string() })?;
    Ok(Written { png, svg })
}

/// Draws `figure` at `size` pixels: its RGB pixels, row by row.
pub(crate) fn render_rgb<F: Figure>(figure: &F, size: (u32, u32)) -> Result<Vec<u8>, FigureError> {
    font()?;
    let draw_error = |reason: String| FigureError::Draw { figure: F::NAME, reason };
    let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let font = ab_glyph::FontRef::try_from_slice(FONT_TTF).map_err(|_| FigureError::Font)?;
        let root = Glyphs { inner: BitMapBackend::with_buffer(&mut pixels, size), font }.into_drawing_area();
        figure.draw(&root).map_err(draw_error)?;
        root.present().map_err(|e| draw_error(e.to_string()))?;
    }
    Ok(pixels)
}

/// Writes `frames` (RGB pixels of `size`, each shown `delay_ms`, looping forever) as an animated PNG at `path`.
/// Viewers without APNG support show the first frame.
pub(crate) fn write_apng(
    path: &Path,
    (w, h): (u32, u32),
    frames: &[Vec<u8>],
    delay_ms: u16,
) -> Result<(), FigureError> {
    let io = |e: &dyn std::fmt::Display| FigureError::Io { path: path.to_path_buf(), reason: e.to_string() };
    let count = u32::try_from(frames.len()).map_err(|e| io(&e))?;
    let file = fs::File::create(path).map_err(|e| io(&e))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_animated(count, 0).map_err(|e| io(&e))?;
    encoder.set_frame_delay(delay_ms, 1000).map_err(|e| io(&e))?;
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder.write_header().map_err(|e| io(&e))?;
    let mut previous: Option<&Vec<u8>> = None;
    for frame in frames {
        // After the first frame, only the rectangle that changed is stored (blended over the frame before it).
        let (x0, y0, fw, fh) = match previous {
            Some(before) => changed_rectangle(before, frame, w as usize),
            None => (0, 0, w as usize, h as usize),
        };
        let mut data = Vec::with_capacity(fw * fh * 3);
        for row in frame.chunks(w as usize * 3).skip(y0).take(fh) {
            data.extend_from_slice(&row[x0 * 3..(x0 + fw) * 3]);
        }
        let dim = |v: usize| u32::try_from(v).map_err(|e| io(&e));
        writer.set_frame_dimension(dim(fw)?, dim(fh)?).map_err(|e| io(&e))?;
        writer.set_frame_position(dim(x0)?, dim(y0)?).map_err(|e| io(&e))?;
        writer.write_image_data(&data).map_err(|e| io(&e))?;
        previous = Some(frame);
    }
    writer.finish().map_err(|e| io(&e))
}

/// The smallest rectangle `(x, y, width, height)`, px, holding every pixel where the RGB images `a` and `b` (rows
/// of `width` pixels) differ; one pixel at the origin when they are equal.
fn changed_rectangle(a: &[u8], b: &[u8], width: usize) -> (usize, usize, usize, usize) {
    let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
    for (y, (ra, rb)) in a.chunks(width * 3).zip(b.chunks(width * 3)).enumerate() {
        for (x, (pa, pb)) in ra.chunks(3).zip(rb.chunks(3)).enumerate() {
            if pa != pb {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    if x0 == usize::MAX { (0, 0, 1, 1) } else { (x0, y0, x1 - x0 + 1, y1 - y0 + 1) }
}

fn write_png(path: &Path, (w, h): (u32, u32), rgb: &[u8]) -> Result<(), FigureError> {
    let io = |e: &dyn std::fmt::Display| FigureError::Io { path: path.to_path_buf(), reason: e.to_string() };
    let file = fs::File::create(path).map_err(|e| io(&e))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| io(&e))?;
    writer.write_image_data(rgb).map_err(|e| io(&e))?;
    writer.finish().map_err(|e| io(&e))
}

/// Smallest and largest finite value, widened a little (and made non-degenerate) for an axis.
pub(crate) fn axis_range(values: impl Iterator<Item = f64>, pad: f64) -> Option<(f64, f64)> {
    let (lo, hi) =
        values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
    Some((lo - pad * span, hi + pad * span))
}

/// A number as a reader writes it, with three significant digits at most: 631, 1000, 25.5, 0.316 (never `1e2.8`);
/// below 0.01 or from a million up in powers of ten with superscripts, 3.2×10⁻⁵, 10⁶.
pub(crate) fn plain_number(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let magnitude = v.abs();
    if magnitude != 0.0 && !(1e-2..1e6).contains(&magnitude) {
        let exponent = magnitude.log10().floor();
        let mantissa = v / 10f64.powf(exponent);
        let power = format!("10{}", superscript(exponent as i32));
        let mantissa_text = format!("{mantissa:.1}");
        return match mantissa_text.as_str() {
            "1.0" => power,
            "-1.0" => format!("-{power}"),
            _ => format!("{}×{power}", mantissa_text.trim_end_matches(".0")),
        };
    }
    let decimals = if magnitude >= 100.0 || magnitude == 0.0 { 0 } else { (2.0 - magnitude.log10().floor()) as usize };
    let text = format!("{v:.decimals$}");
    // Trailing zeros after the point say nothing: 2.50 -> 2.5, 3.0 -> 3.
    if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_owned() } else { text }
}

/// `n` in superscript digits (with a superscript minus).
fn superscript(n: i32) -> String {
    n.to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect()
}

/// Tick positions for a log axis spanning `lo..hi` (base-10 logarithms of the values): `(labelled, unlabelled)`,
/// both as logarithms. Labelled ticks fall at plain values, 1-2-5 x 10^n (decades alone when those are many, 1 to 9
/// x 10^n when the span is narrow); unlabelled ones at every 1 to 9 x 10^n for the grid.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return (Vec::new(), Vec::new());
    }
    let at = |mantissas: &[f64]| -> Vec<f64> {
        let mut ticks = Vec::new();
        for decade in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for m in mantissas {
                let t = (m * 10f64.powi(decade)).log10();
                if t >= lo - 1e-9 && t <= hi + 1e-9 {
                    ticks.push(t);
                }
            }
        }
        ticks
    };
    let all = at(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    let one_two_five = at(&[1.0, 2.0, 5.0]);
    let decades = at(&[1.0]);
    let labelled = if one_two_five.len() > 10 && decades.len() >= 3 {
        decades
    } else if one_two_five.len() >= 3 {
        one_two_five
    } else if all.len() >= 2 {
        all.clone()
    } else {
        // A span narrower than one step of 1 to 9 x 10^n: its ends, which `plain_number` rounds to plain values.
        vec![lo, hi]
    };
    (labelled, all)
}

/// A linear axis over `lo..hi` with its ticks given: `labelled` carry labels and bold grid lines, `grid` light ones.
/// (plotters' `with_key_points` drops the value formatter of `f64` axes, which the mesh needs.)
pub(crate) struct Ticked {
    pub lo: f64,
    pub hi: f64,
    pub labelled: Vec<f64>,
    pub grid: Vec<f64>,
}

impl Ticked {
    /// A log axis over `lo..hi` (base-10 logarithms) with ticks at plain values, see [`log_ticks`].
    pub fn log(lo: f64, hi: f64) -> Self {
        let (labelled, grid) = log_ticks(lo, hi);
        Self { lo, hi, labelled, grid }
    }

    /// A linear axis over `lo..hi` with plotters' own ticks and grid (10 labels, 10 grid lines between).
    pub fn linear(lo: f64, hi: f64) -> Self {
        let range = plotters::coord::types::RangedCoordf64::from(lo..hi);
        Self {
            lo,
            hi,
            labelled: range.key_points(10),
            grid: range.key_points(plotters::coord::ranged1d::LightPoints::new(10, 100)),
        }
    }
}

impl plotters::coord::ranged1d::Ranged for Ticked {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        plotters::coord::types::RangedCoordf64::from(self.lo..self.hi).map(value, limit)
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() { self.grid.clone() } else { self.labelled.clone() }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

impl plotters::coord::ranged1d::ReversibleRanged for Ticked {
    fn unmap(&self, input: i32, limit: (i32, i32)) -> Option<f64> {
        plotters::coord::types::RangedCoordf64::from(self.lo..self.hi).unmap(input, limit)
    }
}

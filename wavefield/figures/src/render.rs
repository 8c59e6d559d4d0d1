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
}

/// Registers the bundled font once.
fn font() -> Result<(), FigureError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FONT, FontStyle::Normal, FONT_TTF).is_ok());
    if ok { Ok(()) } else { Err(FigureError::Font) }
}

/// Draws `figure` at `size` pixels and writes `<dir>/<name>.png` and `<dir>/<name>.svg`.
pub(crate) fn save<F: Figure>(figure: &F, dir: &Path, name: &str, size: (u32, u32)) -> Result<Written, FigureError> {
    font()?;
    let draw_error = |reason: String| FigureError::Draw { figure: F::NAME, reason };
    let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let font = ab_glyph::FontRef::try_from_slice(FONT_TTF).map_err(|_| FigureError::Font)?;
        let root = Glyphs { inner: BitMapBackend::with_buffer(&mut pixels, size), font }.into_drawing_area();
        figure.draw(&root).map_err(draw_error)?;
        root.present().map_err(|e| draw_error(e.to_string()))?;
    }
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        figure.draw(&root).map_err(draw_error)?;
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

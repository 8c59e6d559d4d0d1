//! Figures of the paper's analyses, each written as PNG and SVG: wavelength against frequency, focus snapshots (and
//! the focusing as an animated PNG), the virtual-pixel-area map, POD energy, singular-value energy and condition
//! numbers (plus the driven response); behavioural accuracy per participant with the chance line, and an
//! experiment's stimuli as predicted at its pixels.
//!
//! Text is set in DejaVu Sans, bundled in the crate (`fonts/`, Bitstream Vera licence) and read by ab_glyph: no
//! system font, fontconfig or font-kit is ever consulted, so figures look the same on every machine and in CI.
//!
//! Each figure function takes plain data (no analysis types, so any source can plot) and writes `<name>.png` and
//! `<name>.svg` into a directory, returning both paths. The grid maps for pages (`status_map_svg`, `snr_map_svg`)
//! return inline SVG instead.

mod accuracy;
mod colour;
mod field;
mod glyphs;
mod grid_svg;
mod maps;
mod plots;
mod render;
mod stimuli;
mod tradeoff;

pub use accuracy::{AccuracyBar, accuracy};
pub use grid_svg::{CellStatus, snr_map_svg, status_map_svg};
pub use maps::{PlateOverlay, focus_animation, focus_snapshots, pixel_area_map};
pub use plots::{
    Curve, SingularValueSeries, WavelengthReferences, WavelengthSeries, condition_numbers, driven_response, pod_energy,
    singular_value_energy, wavelength,
};
pub use render::{FigureError, Written};
pub use stimuli::{PixelRole, PixelTrace, StimulusPanel, stimuli};
pub use tradeoff::{TradeoffPoint, tradeoff};

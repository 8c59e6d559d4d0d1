//! Figures of the paper's analyses, each written as PNG and SVG: wavelength against frequency, focus snapshots (and
//! the focusing as an animated PNG), the virtual-pixel-area map, POD energy, singular-value energy and condition
//! numbers (plus the driven response); the speed/accuracy trade of the scan protocols; behavioural accuracy per
//! participant with the chance line, and an experiment's stimuli as predicted at its pixels; and the measurement
//! grid as inline SVG for pages.
//!
//! Each figure function takes plain data (no analysis types, so any source can plot) and writes `<name>.png` and
//! `<name>.svg` into a directory, returning both paths ([`Written`]). The grid maps for pages ([`status_map_svg`],
//! [`snr_map_svg`]) return inline SVG instead, and the animation is a PNG only.
//!
//! # Drawing
//!
//! - Text is set in DejaVu Sans, bundled in the crate (`fonts/`, Bitstream Vera licence) and read by ab_glyph: no
//!   system font, fontconfig or font-kit is ever consulted, so figures look the same on every machine and in CI. On
//!   the PNG, text is drawn glyph by glyph with each glyph's bearing (`glyphs` module: plotters' own bitmap text
//!   drops it).
//! - Colour maps are continuous: viridis for magnitudes, a red-blue diverging map for signed fields, with labelled
//!   colour bars. Log axes are ticked at 1-2-5 x 10^n, labelled in plain numbers.
//! - Wave fields are images on the plate (`field` module): bilinear between the lattice's measured points, no
//!   extrapolation beyond half a step, masked outside the outline polygon; the focus's half-maximum contour by
//!   marching squares. [`PlateOverlay`] draws the outline, the resonator rods and their region, the actuators, the
//!   supports and the focus target over them.
//!
//! # Figures
//!
//! - [`wavelength`]: wavelength against frequency, with model curves (the analytic A0), reference points (the
//!   paper's) and the lattice's resolvable range; estimates outside it are drawn hollow.
//! - [`focus_snapshots`], [`focus_animation`] (the focusing in time as an animated PNG, APNG via `png`) and
//!   [`pixel_area_map`]: maps over the plate.
//! - [`pod_energy`], [`singular_value_energy`], [`condition_numbers`], [`driven_response`]: line figures.
//! - [`band_structure`]: a unit cell's band diagram with the folded A0, phase velocity and wavelength against
//!   frequency (the paper's Fig. 2B-D; `metaplate design band --figures`).
//! - [`tradeoff`]: time per point against median Green's-function error, every protocol a labelled point, the Pareto
//!   front joined.
//! - [`status_map_svg`], [`snr_map_svg`]: the grid by point status, or by SNR on a fixed scale, as inline SVG (the
//!   report's maps).
//! - [`accuracy`]: behavioural accuracy per participant with Wilson intervals and the chance line.
//! - [`stimuli`]: an experiment's stimuli as predicted at its pixels, one panel per stimulus, a lane per pixel, long
//!   traces min-max reduced (the paper's Figs. S8 to S11).
//!
//! Both built-in plates on shared axes (the demo's figures) are drawn by `metaplate-analysis`'
//! `dataset_figures::write_comparison_figures` with these functions.

mod accuracy;
mod colour;
mod design_band;
mod field;
mod glyphs;
mod grid_svg;
mod maps;
mod plots;
mod render;
mod stimuli;
mod tradeoff;

pub use accuracy::{AccuracyBar, accuracy};
pub use design_band::design_band;
pub use grid_svg::{CellStatus, snr_map_svg, status_map_svg};
pub use maps::{PlateOverlay, focus_animation, focus_snapshots, pixel_area_map};
pub use plots::{
    BandFigure, Curve, SingularValueSeries, WavelengthReferences, WavelengthSeries, band_structure, condition_numbers,
    driven_response, pod_energy, singular_value_energy, wavelength,
};
pub use render::{FigureError, Written};
pub use stimuli::{PixelRole, PixelTrace, StimulusPanel, stimuli};
pub use tradeoff::{TradeoffPoint, tradeoff};

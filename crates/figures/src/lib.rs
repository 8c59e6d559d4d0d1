//! Figures (PNG and SVG, plotters with a bundled font): wavelength, focus snapshots, pixel-area maps, POD and singular-value energy.

//! The paper's Fig. 2C-D from a computed band diagram: c(f) and lambda(f) walk from Gamma outwards while the
//! frequency rises, one value per frequency, not the path's legs drawn over each other; m = 1 reaches the branch's
//! top.

use metaplate_core::design::Design;
use metaplate_design::{BandOptions, band_diagram};
use metaplate_figures::design_band;

#[test]
fn the_paper_cells_curves_rise_in_frequency_to_the_slow_branchs_top() {
    let design = Design::paper();
    let options = BandOptions { wave_vectors: 46, modes: 3, ..BandOptions::default() };
    let band = band_diagram(&design, &options, &[]).unwrap();
    let figure = design_band(&design, &band);
    for curve in figure.phase_velocity.iter().chain(&figure.wavelength) {
        assert!(curve.points.len() > 5, "{}: {} points", curve.label, curve.points.len());
        assert!(curve.points.windows(2).all(|w| w[1].0 > w[0].0), "{}: frequency rises", curve.label);
    }
    let m1_top_hz = figure.phase_velocity[0].points.last().unwrap().0;
    let top_hz = band.slow_branch.top_hz;
    assert!((m1_top_hz / top_hz - 1.0).abs() < 1e-9, "m = 1 drawn to its top, {m1_top_hz} Hz against {top_hz} Hz");
}

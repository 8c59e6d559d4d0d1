//! A unit cell's band diagram as the paper's Fig. 2B-D draws it, for [`crate::band_structure`].

use metaplate_core::design::Design;
use metaplate_design::{BandDiagram, BranchPoint};

use crate::plots::{BandFigure, Curve};

/// Where Gamma-X-M ends on the path ([`metaplate_design::PathPoint::path_position`], units of pi/a: M at 2), with room for
/// rounding.
const M_END: f64 = 2.0 + 1e-9;

/// The paper's Fig. 2B-D: the first five branches with the folded A0 and f_n, up to 1.5 times the top of m = 2 (the
/// slow branch and its partner stay legible; the rod's higher modes are kHz above); c(f) and lambda(f) of m = 1, 2
/// walking from Gamma along Gamma-X-M while the frequency rises (one value per frequency, as the slow branch's
/// wavelengths are read: over the whole path each branch passes its frequencies two or three times; m = 1 reaches
/// its top at M) with the analytic A0's.
pub fn design_band(design: &Design, band: &BandDiagram) -> BandFigure {
    let position = |i: usize| band.path[i].path_position;
    let f_max = band.branches.iter().take(2).flat_map(|b| b.points.iter().map(|p| p.freq_hz)).fold(0.0, f64::max);
    let clip_hz = 1.5 * f_max;
    // Curves broken where they leave the plot, so that no line joins across the gap (the figure labels the first).
    let clipped = |label: &str, values: &mut dyn Iterator<Item = (f64, f64)>| -> Vec<Curve> {
        let mut out: Vec<Curve> = Vec::new();
        let mut open = false;
        for (x, f) in values {
            if f <= clip_hz {
                if !open {
                    out.push(Curve { label: label.to_owned(), points: Vec::new() });
                    open = true;
                }
                if let Some(c) = out.last_mut() {
                    c.points.push((x, f));
                }
            } else {
                open = false;
            }
        }
        out
    };
    let branches: Vec<Curve> = band.branches[..band.branches.len().min(5)]
        .iter()
        .map(|b| Curve {
            label: format!("m = {}", b.mode),
            points: b
                .points
                .iter()
                .filter(|p| p.freq_hz <= clip_hz)
                .map(|p| (position(p.path_index), p.freq_hz))
                .collect(),
        })
        .filter(|c| !c.points.is_empty())
        .collect();
    let a0_folded = band
        .a0_folded_hz
        .iter()
        .flat_map(|f| {
            clipped("A0, homogeneous plate (folded)", &mut f.iter().enumerate().map(|(i, &f)| (position(i), f)))
        })
        .collect();
    let per_branch = |value: &dyn Fn(&BranchPoint) -> Option<f64>| -> Vec<Curve> {
        band.branches
            .iter()
            .take(2)
            .map(|b| Curve {
                label: format!("m = {}", b.mode),
                points: b
                    .points
                    .iter()
                    .take_while(|p| band.path[p.path_index].path_position <= M_END)
                    .scan(f64::NEG_INFINITY, |last_hz, p| {
                        (p.freq_hz >= *last_hz).then(|| {
                            *last_hz = p.freq_hz;
                            p
                        })
                    })
                    .filter_map(|p| value(p).map(|v| (p.freq_hz, v)))
                    .collect(),
            })
            .collect()
    };
    let plate = design.plate;
    let a0_at = |f_hz: f64| {
        let k = plate.a0_wavenumber_rad_m(f_hz);
        (2.0 * std::f64::consts::PI * f_hz / k, 2.0 * std::f64::consts::PI / k)
    };
    let freqs: Vec<f64> = (1..=100).map(|i| f_max * f64::from(i) / 100.0).collect();
    BandFigure {
        title: format!("Band structure of the {} unit cell (branches drawn up to {clip_hz:.0} Hz)", band.design),
        branches,
        a0_folded,
        resonator_hz: band.resonator_mode_hz,
        phase_velocity: per_branch(&|p| p.phase_velocity_m_s),
        wavelength: per_branch(&|p| p.wavelength_m),
        a0_phase_velocity: Some(Curve {
            label: "A0, homogeneous plate (analytic)".into(),
            points: freqs.iter().map(|&f| (f, a0_at(f).0)).collect(),
        }),
        a0_wavelength: Some(Curve {
            label: "A0, homogeneous plate (analytic)".into(),
            points: freqs.iter().map(|&f| (f, a0_at(f).1)).collect(),
        }),
    }
}

//! The homogenised rocking rod: the fit recovers a model's own parameters, follows the paper's cell where the
//! lattice is fine against the wavelength, and refuses what it cannot fit.

use std::f64::consts::PI;

use metaplate_core::design::Design;
use metaplate_design::{
    BandOptions, DesignError, HOMOGENISED_MAX_KA, PAPER_WAVELENGTH_FREQS_HZ, RockingRodFit, band_diagram,
    fit_rocking_rod,
};

fn point(kx_rad_m: f64, ky_rad_m: f64, freq_hz: f64) -> (f64, f64) {
    (kx_rad_m.hypot(ky_rad_m), freq_hz)
}

/// A model with chosen parameters (the fitted fields that the dispersion reads).
fn model(rigidity_factor: f64, rotary_inertia_kg_m2: f64, resonance_hz: f64) -> RockingRodFit {
    RockingRodFit {
        added_mass_ratio: 0.0,
        rigidity_factor,
        rotary_inertia_kg_m2,
        resonance_hz,
        points: 0,
        min_freq_hz: 0.0,
        max_freq_hz: 0.0,
        max_relative_error: 0.0,
        rms_relative_error: 0.0,
    }
}

/// Points drawn from the model itself are fitted back to its parameters (the optimiser, not the physics): from a
/// start a factor of 2 to 3 away in each parameter, to 1e-6.
#[test]
fn the_fit_recovers_a_models_own_parameters() {
    let design = Design::paper();
    let truth = model(1.2, 4e-7, 520.0);
    let a = design.lattice_constant_m;
    let points: Vec<(f64, f64)> = (1..=12)
        .map(|i| {
            let k = HOMOGENISED_MAX_KA / a * i as f64 / 12.0;
            point(k, 0.0, truth.freq_hz(&design, k))
        })
        .collect();
    let fit = fit_rocking_rod(&design, &points).unwrap();
    for (got, want, what) in [
        (fit.rigidity_factor, 1.2, "stiffness factor"),
        (fit.rotary_inertia_kg_m2, 4e-7, "rotary inertia"),
        (fit.resonance_hz, 520.0, "joint resonance"),
    ] {
        assert!((got / want - 1.0).abs() < 1e-6, "{what}: {got} against {want}");
    }
    assert!(fit.max_relative_error < 1e-9, "residual {}", fit.max_relative_error);
    assert_eq!(fit.points, 12);
}

/// The model's dispersion at its extremes: 0 at k = 0, tending to the joint's resonance as k grows, and the
/// wavenumber it gives back at a frequency is the one that frequency came from.
#[test]
fn the_models_dispersion_inverts_and_tends_to_the_resonance() {
    let design = Design::paper();
    let m = model(1.3, 7.8e-7, 600.0);
    assert_eq!(m.freq_hz(&design, 0.0), 0.0);
    let far = m.freq_hz(&design, 1e7);
    assert!(far < 600.0 && far > 599.9, "at k = 1e7 rad/m: {far} Hz");
    for f in [0.01, 1.0, 75.0, 400.0, 599.0] {
        let k = m.wavenumber_rad_m(&design, f).unwrap();
        let back = m.freq_hz(&design, k);
        assert!((back / f - 1.0).abs() < 1e-9, "{f} Hz -> {k} rad/m -> {back} Hz");
    }
    for f in [600.0, 700.0, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(m.wavenumber_rad_m(&design, f), None, "{f} Hz");
    }
}

/// The paper's cell: the continuum follows its slow branch within 3 % in frequency at wavelengths of 4 lattice
/// constants and more, along Gamma-X and Gamma-M alike (an isotropic continuum: the cell's anisotropy at |k| a near
/// pi/2 is most of the residual), with physical parameters: the footprints, an eighth of the cell, stiffen the
/// plate by less than 2 x; the rod rocks with an inertia within 2 x of a rigid rod's about its base; the joint
/// resonates above the fitted band. Its wavelength at 75 Hz is the cell's within 1 %.
#[test]
fn the_paper_cell_is_followed_by_its_homogenised_plate() {
    let design = Design::paper();
    let options = BandOptions { wave_vectors: 46, modes: 1, ..BandOptions::default() };
    let band = band_diagram(&design, &options, &PAPER_WAVELENGTH_FREQS_HZ).unwrap();
    let fit = band.homogenised.unwrap();
    assert!(fit.points >= 8, "{} points", fit.points);
    assert!(fit.max_relative_error < 0.03, "max error {}", fit.max_relative_error);
    assert!((1.0..2.0).contains(&fit.rigidity_factor), "stiffness factor {}", fit.rigidity_factor);
    let metaplate_core::design::CellResonator::Rod(rod) = design.resonator else { unreachable!() };
    let rigid = rod.free_mass_kg() * rod.free_length_m().powi(2) / 3.0;
    let ratio = fit.rotary_inertia_kg_m2 / rigid;
    assert!((0.5..2.0).contains(&ratio), "inertia {ratio} x a rigid rod's");
    assert!(fit.resonance_hz > fit.max_freq_hz, "joint {} Hz within the band", fit.resonance_hz);
    assert!((fit.added_mass_ratio / 19.73 - 1.0).abs() < 0.01, "added mass {}", fit.added_mass_ratio);
    let cell_75 = band.slow_branch.wavelength_m_at[0].wavelength_m.unwrap();
    let model_75 = 2.0 * PI / fit.wavenumber_rad_m(&design, 75.0).unwrap();
    assert!((model_75 / cell_75 - 1.0).abs() < 0.01, "75 Hz: {model_75} m against the cell's {cell_75} m");
}

/// No rod, or too few points near Gamma: an option error naming why, not a fit.
#[test]
fn what_cannot_be_fitted_is_refused() {
    let paper = Design::paper();
    let points: Vec<(f64, f64)> = (1..=6).map(|i| point(10.0 * i as f64, 0.0, i as f64)).collect();
    match fit_rocking_rod(&paper.homogeneous(), &points) {
        Err(DesignError::Option(why)) => assert!(why.contains("rod"), "{why}"),
        other => panic!("{other:?}"),
    }
    match fit_rocking_rod(&paper, &points[..3]) {
        Err(DesignError::Option(why)) => assert!(why.contains("at least 4"), "{why}"),
        other => panic!("{other:?}"),
    }
    // Points beyond |k| a = pi/2 do not count.
    let far: Vec<(f64, f64)> = (1..=6).map(|i| point(300.0 + i as f64, 0.0, 400.0)).collect();
    assert!(matches!(fit_rocking_rod(&paper, &far), Err(DesignError::Option(_))));
    // A 2-point path has no points near Gamma: the diagram leaves the fit out.
    let band = band_diagram(&paper, &BandOptions { wave_vectors: 2, modes: 1, ..BandOptions::default() }, &[]).unwrap();
    assert!(band.homogenised.is_none());
}

/// The plate model's own fit (16 wave vectors, no band diagram) agrees with the band diagram's within its error.
#[test]
fn the_plate_models_fit_agrees_with_the_band_diagrams() {
    let design = Design::paper();
    let options = BandOptions { wave_vectors: 46, modes: 1, ..BandOptions::default() };
    let from_band = band_diagram(&design, &options, &[]).unwrap().homogenised.unwrap();
    let own = metaplate_design::homogenised_rocking_rod(&design).unwrap();
    assert_eq!(own.points, 16);
    assert!(own.max_relative_error < 0.03, "max error {}", own.max_relative_error);
    for f in [75.0, 200.0, 300.0] {
        let (a, b) = (own.wavenumber_rad_m(&design, f).unwrap(), from_band.wavenumber_rad_m(&design, f).unwrap());
        assert!((a / b - 1.0).abs() < 0.02, "{f} Hz: {a} against {b} rad/m");
    }
    assert!(metaplate_design::homogenised_rocking_rod(&design.homogeneous()).is_err());
}

//! Wavelengths of the simulated plates, measured from their fields with the analysis crate's two estimators: the
//! paper's k-space method and the plate-equation (biharmonic Rayleigh quotient) estimator, which no aperture limits.
//!
//! The figures behind the tolerances print with
//! `cargo test -p metaplate-plate --test dispersion -- --nocapture`.
#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use std::f64::consts::PI;

use metaplate_analysis::dispersion::{DispersionOptions, FrequencyWavelengths, SceneLayout, wavelengths_at};
use metaplate_core::scene::Scene;
use metaplate_plate::{ModelOptions, PlateModel};

/// The band of the issue, at 8 frequencies.
const FREQS_HZ: [f64; 8] = [75.0, 100.0, 150.0, 200.0, 300.0, 400.0, 500.0, 600.0];

/// Both estimators at `freq_hz` for every actuator of `scene`.
fn wavelengths(scene: &Scene, model: &PlateModel, freq_hz: f64) -> FrequencyWavelengths {
    let layout = SceneLayout::new(scene);
    let actuators: Vec<usize> = (0..scene.actuators.len()).collect();
    let response = model.frequency_response(freq_hz, &actuators, &layout.points).unwrap();
    wavelengths_at(&response, actuators.len(), &layout.layout(), &DispersionOptions::default()).unwrap()
}

/// The k-space median over actuators, the paper's figure.
fn k_space_median(scene: &Scene, model: &PlateModel, freq_hz: f64) -> f64 {
    wavelengths(scene, model, freq_hz).k_space_summary.median_m
}

/// The plate-equation median over actuators; every actuator must have given an estimate.
fn local_median(w: &FrequencyWavelengths) -> f64 {
    let summary = w.local_summary.unwrap();
    assert_eq!(summary.actuators, w.local.len(), "an actuator gave no plate-equation estimate: {:?}", w.local);
    summary.wavelength_m
}

/// The built-in metamaterial with its rods given key by key, as 0.8's built-in gave them (rocking rods with their own
/// mass and clamped bending mode, and an 11 mm radius of gyration), for the models no design's fit goes through.
fn keyed_metamaterial() -> Scene {
    let mut scene = Scene::builtin("metamaterial").unwrap();
    scene.resonators.design = None;
    scene.resonators.rod_height_m = 0.0334;
    scene.resonators.gyration_radius_m = Some(0.011);
    scene.validate().unwrap();
    scene
}

#[test]
fn metamaterial_is_the_papers_at_75_hz_monotonic_and_flags_what_it_does_not_resolve() {
    // The built-in takes its rods from the paper's cell (design `paper`), fitted to nothing the paper measured.
    let scene = Scene::builtin("metamaterial").unwrap();
    let model = PlateModel::from_scene(&scene, &ModelOptions::default()).unwrap();
    let freqs = FREQS_HZ;
    let measured: Vec<FrequencyWavelengths> = freqs.iter().map(|&f| wavelengths(&scene, &model, f)).collect();
    let lambdas: Vec<f64> = measured.iter().map(|w| w.k_space_summary.median_m).collect();
    println!("k-space: {lambdas:?}");
    // 75 Hz within 15 % of the paper's measured 11.3 cm, on the plate-equation estimate (the k-space peak of a
    // 10 cm wave on a 24 x 12 cm aperture reads short, as it does on the homogeneous plate).
    let at_75 = local_median(&measured[0]);
    assert!((at_75 / 0.113 - 1.0).abs() < 0.15, "75 Hz: {at_75} m");
    // Monotonic, and 2 to 5 times shorter than the homogeneous plate's A0, from 75 to 300 Hz. From 400 Hz the slow
    // wave (2.1 cm at 400 Hz) is under 6 steps of this field's 5 mm lattice, outside the plate-equation estimator's
    // range, and the k-space peak of a single frequency's field is not the slow wave's (it reads 17 cm at 400 Hz);
    // the band-limited ground truth resolves 400 Hz at 2.09 cm (`wavelength_lattice` in metaplate-analysis).
    // 600 Hz lies above the cell's slow branch (it tops out at 552 Hz): the plate carries no slow wave there, where
    // the paper measured 2.5 cm (above its own simulated branch, which tops out at 558 Hz).
    let in_range = freqs.iter().take_while(|&&f| f <= 300.0).count();
    for (w, f) in lambdas[..in_range].windows(2).zip(freqs.windows(2)) {
        assert!(w[1] < w[0], "not monotonic between {} and {} Hz: {lambdas:?}", f[0], f[1]);
    }
    for (&f, &l) in freqs.iter().zip(&lambdas).take(in_range) {
        let ratio = scene.plate.a0_wavelength_m(f).unwrap() / l;
        assert!((2.0..=5.0).contains(&ratio), "{f} Hz: A0 / metamaterial = {ratio}");
    }
    // Where it reads no slow wave, most actuators' k-space estimates say so (the paper table shows them as
    // unresolved): 5 of 8 at 400 Hz, all 8 at 600 Hz.
    for (f, w) in freqs.iter().zip(&measured).filter(|&(&f, _)| f == 400.0 || f == 600.0) {
        let s = &w.k_space_summary;
        assert!(2 * s.flagged > s.actuators, "{f} Hz: {s:?}");
    }
}

#[test]
fn homogeneous_matches_analytic_a0_within_5_percent() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let model = PlateModel::from_scene(&scene, &ModelOptions::default()).unwrap();
    let aperture_m = scene.grid.nx.max(scene.grid.ny) as f64 * scene.grid.spacing_m;
    println!(
        "{:>6} {:>9} {:>9} {:>9} {:>8} {:>8} {:>7}",
        "f Hz", "A0 cm", "local cm", "k cm", "local %", "k %", "flagged"
    );
    for f in FREQS_HZ {
        let a0 = scene.plate.a0_wavelength_m(f).unwrap();
        let w = wavelengths(&scene, &model, f);
        let local = local_median(&w);
        let k = &w.k_space_summary;
        println!(
            "{f:>6} {:>9.3} {:>9.3} {:>9.3} {:>+8.2} {:>+8.2} {:>7}",
            a0 * 100.0,
            local * 100.0,
            k.median_m * 100.0,
            (local / a0 - 1.0) * 100.0,
            (k.median_m / a0 - 1.0) * 100.0,
            k.flagged
        );
        // The requirement, on the plate-equation estimate (measured: within 0.25 % over the band).
        assert!((local / a0 - 1.0).abs() < 0.05, "{f} Hz: local {local} m, A0 {a0} m");
        for e in w.local.iter().map(|r| r.as_ref().unwrap()) {
            // Every actuator's field: inside the estimator's range (9 cm at 600 Hz is 18 grid steps), and obeying
            // one plate equation where it is measured: residual 0.035 at most over the band, against 0.8 to 0.99
            // with no actuator exclusion (the near field then in the sums); 0.1 separates the two.
            assert!(e.flags.in_range(), "{f} Hz: {e:?}");
            assert!(e.residual < 0.1, "{f} Hz: {e:?}");
            assert!((e.wavelength_m / a0 - 1.0).abs() < 0.05, "{f} Hz: {e:?}");
        }
        // For the record, the paper's k-space method on the same fields: where A0 exceeds 0.6 L it reads at least
        // 4 % short (its documented bias, `metaplate_analysis::wavelength`), so above L / 2: every actuator is
        // flagged under-resolved. Across the band it stays within 20 % of A0, its documented bias at L, but it is
        // not within 5 %: it misses A0 by 8 to 16 % at most frequencies (the table above).
        if a0 > 0.6 * aperture_m {
            assert!(w.k_space.iter().all(|e| e.flags.under_resolved), "{f} Hz: {:?}", w.k_space);
        }
        assert!((k.median_m / a0 - 1.0).abs() < 0.20, "{f} Hz: k-space {} m, A0 {a0} m", k.median_m);
    }
}

/// Checks the plate-equation wavelength of `scene` against `homogenised(f)` at each of `freqs_hz`, within the
/// tolerance of the discretisation (plus `extra_tolerance`, relative) where the estimator is in range.
fn check_homogenised(scene: &Scene, freqs_hz: &[f64], extra_tolerance: f64, homogenised: impl Fn(f64) -> f64) {
    let options = ModelOptions::default();
    let model = PlateModel::from_scene(scene, &options).unwrap();
    let lattice_m = scene.grid.spacing_m / options.refinement as f64;
    println!("{:>6} {:>9} {:>9} {:>9} {:>8} {:>8}", "f Hz", "eff cm", "local cm", "k cm", "local %", "k/local %");
    let mut misses = Vec::new();
    for &f in freqs_hz {
        let effective = homogenised(f);
        let w = wavelengths(scene, &model, f);
        let local = local_median(&w);
        let k_space = w.k_space_summary.median_m;
        println!(
            "{f:>6} {:>9.3} {:>9.3} {:>9.3} {:>+8.2} {:>+8.2}",
            effective * 100.0,
            local * 100.0,
            k_space * 100.0,
            (local / effective - 1.0) * 100.0,
            (k_space / local - 1.0) * 100.0
        );
        let summary = w.local_summary.unwrap();
        if summary.flagged > 0 {
            // Under 6 grid steps is outside the estimator's stated range, and it says so.
            assert!(local < 6.0 * scene.grid.spacing_m, "{f} Hz: flagged at {local} m");
            continue;
        }
        // Tolerance: the model's own discretisation reads wavelengths short by (k h_lattice)^2 / 24 (its
        // documentation), the estimator's stencil leaves up to (k h)^2 / 96 by direction (`wavelength::local`),
        // and 0.5 % covers what the formula leaves out (the rods' 1 % height spread and their own loss, the
        // rod-free 1 cm strip along the edge that some stencils reach). Measured: added mass within 0.7 % up to 500 Hz,
        // rocking rods within 0.8 % (75 and 100 Hz, see their test) and 1.2 % at 600 Hz.
        let k = 2.0 * PI / effective;
        let tolerance =
            (k * lattice_m).powi(2) / 24.0 + (k * scene.grid.spacing_m).powi(2) / 96.0 + 0.005 + extra_tolerance;
        if (local / effective - 1.0).abs() >= tolerance {
            misses.push(format!("{f} Hz: local {local} m, homogenised {effective} m, tolerance {tolerance}"));
        }
    }
    assert!(misses.is_empty(), "{misses:#?}");
}

#[test]
fn added_mass_rods_obey_the_homogenised_dispersion() {
    // Rods as a resonant added mass, homogenised: D k^4 = rho h w^2 [1 + mu w_r^2 / (w_r^2 - w^2)]
    // (`metaplate_plate` resonators docs), so the plate obeys one plate equation with an effective mass and its
    // wavelength is A0's divided by that bracket to the 1/4. The parameters are the added-mass fit to the paper's
    // two measured wavelengths (the built-in scene's before the rocking model replaced it).
    let mut scene = keyed_metamaterial();
    scene.resonators.model = metaplate_core::scene::ResonatorModel::AddedMass;
    (scene.resonators.mass_ratio, scene.resonators.resonance_hz) = (Some(24.0), Some(650.0));
    let rods = metaplate_plate::effective_parameters(&scene).unwrap();
    let (mu, f_r) = (rods.mass_ratio, rods.resonance_hz);
    check_homogenised(&scene, &FREQS_HZ, 0.0, |f| {
        scene.plate.a0_wavelength_m(f).unwrap() / (1.0 + mu * f_r * f_r / (f_r * f_r - f * f)).powf(0.25)
    });
}

#[test]
fn rocking_rods_obey_the_homogenised_dispersion() {
    // Rods that move with the plate (mass mu rho h per area) and rock with its slope (rotary inertia
    // J = mu rho h r_g^2 per area, resonant at f_r), homogenised: D k^4 - w^2 J R k^2 - w^2 rho h (1 + mu) = 0 with
    // R = w_r^2 / (w_r^2 - w^2), a quadratic in k^2 whose positive root is the propagating wave.
    let scene = keyed_metamaterial();
    let rods = metaplate_plate::effective_parameters(&scene).unwrap();
    assert_eq!(rods.rigidity_factor, 1.0, "rods given key by key do not stiffen the plate");
    // The plate-equation estimator assumes laplacian^2 w = k^4 w. A plain plate's evanescent companion wave has the
    // same k^4, but the rocking rods' does not (its k_2 has k^2 - k_2^2 = w^2 J / D): the likely reason the estimate
    // reads up to 0.8 % short at 75 and 100 Hz, where edges and sources lie within its decay length. The same
    // residual at refinement 3 (0.5 and 0.7 %) shows it is not the discretisation; 0.5 % more covers it.
    check_homogenised(&scene, &FREQS_HZ, 0.005, |f| rocking_wavelength_m(&scene, &rods, f));
}

/// The homogenised rocking-rod plate's wavelength at `freq_hz`: the positive root in k^2 of
/// `s_D D k^4 - w^2 (J / a^2) R k^2 - w^2 rho h (1 + mu) = 0`, `R = w_r^2 / (w_r^2 - w^2)`, m.
fn rocking_wavelength_m(scene: &Scene, rods: &metaplate_plate::RodParameters, freq_hz: f64) -> f64 {
    let rho_h = scene.plate.mass_per_area_kg_m2();
    let d = rods.rigidity_factor * scene.plate.bending_stiffness_n_m();
    let inertia = rods.rotary_inertia_kg_m2 / scene.resonators.pitch_m.powi(2);
    let (mu, f_r) = (rods.mass_ratio, rods.resonance_hz);
    let w2 = (2.0 * PI * freq_hz).powi(2);
    let j = inertia * f_r * f_r / (f_r * f_r - freq_hz * freq_hz);
    let k2 = (w2 * j + ((w2 * j).powi(2) + 4.0 * d * rho_h * (1.0 + mu) * w2).sqrt()) / (2.0 * d);
    2.0 * PI / k2.sqrt()
}

#[test]
fn a_plate_built_from_a_design_follows_its_cell() {
    // The built-in metamaterial's lattice is the design `paper`'s: the plate takes the cell's homogenised rocking rod
    // (its mass, its footprints' stiffening under the lattice, the rods' inertia and joint). Where that continuum
    // holds (wavelengths of 4 lattice constants and more: 75 to 300 Hz here; from 400 Hz the slow wave is under 6
    // grid steps, outside the estimator's range), the plate's waves are the fit's, within the same tolerance as the
    // rods given key by key; and so the cell's slow branch, within the fit's error. At 75 Hz that is within 15 % of
    // the paper's measured 11.3 cm.
    let scene = Scene::builtin("metamaterial").unwrap();
    assert_eq!(scene.resonators.design, Some(metaplate_core::design::Design::paper()));
    let rods = metaplate_plate::effective_parameters(&scene).unwrap();
    let fit = metaplate_plate::design_fit(scene.resonators.design.as_ref().unwrap()).unwrap();
    assert!(rods.rigidity_factor > 1.0 && fit.max_relative_error < 0.03, "{rods:?}, {fit:?}");
    check_homogenised(&scene, &FREQS_HZ[..5], 0.005, |f| rocking_wavelength_m(&scene, &rods, f));
    let model = PlateModel::from_scene(&scene, &ModelOptions::default()).unwrap();
    let at_75 = local_median(&wavelengths(&scene, &model, 75.0));
    assert!((at_75 / 0.113 - 1.0).abs() < 0.15, "75 Hz: {at_75} m");
}

#[test]
fn rocking_rods_slow_waves_more_than_the_same_rods_as_added_mass() {
    // Rocking rods add rotary inertia J = m r_g^2 on top of the rods' mass, a term -w^2 J laplacian(w) that
    // shortens waves further; with the rods' own (derived) parameters both models run, and rocking is shorter.
    use metaplate_core::scene::ResonatorModel;
    let mut rocking = keyed_metamaterial();
    rocking.resonators.gyration_radius_m = None;
    let mut added = rocking.clone();
    added.resonators.model = ResonatorModel::AddedMass;
    let options = ModelOptions { refinement: 2, threads: 1 };
    let l_added = k_space_median(&added, &PlateModel::from_scene(&added, &options).unwrap(), 300.0);
    let l_rocking = k_space_median(&rocking, &PlateModel::from_scene(&rocking, &options).unwrap(), 300.0);
    assert!(l_rocking < l_added, "rocking {l_rocking} m, added mass {l_added} m");
}

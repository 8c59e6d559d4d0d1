//! Scenes: the built-ins, round trips, the grid mask, and every validation error.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap

use std::path::Path;

use metaplate_core::scene::{
    CANONICAL_FORM_VERSION, FaultKind, Imperfection, Outline, ResonatorModel, ResonatorSpec, SCENE_HASH_PREFIX, Scene,
    SceneError,
};

const METAMATERIAL: &str = include_str!("../scenes/metamaterial.toml");
/// The rods of 0.8's built-in metamaterial, key by key, in place of its design: a lattice a scene gives rod by rod.
const KEYED_RODS: &str = "pitch_m = 0.008\nrod_height_m = 0.0334\nrod_diameter_m = 0.003175\nrod_youngs_modulus_pa = 97e9\n\
                          rod_density_kg_m3 = 8489.0\n";
const RECT_FAULTS: &str = include_str!("scenes/rect_faults.toml");

// Positions here are sums and products of a few decimal lengths below 1 m: 1e-12 m is ~1e4 ulps, ample for rounding
// and far below any physical length.
const TOL_M: f64 = 1e-12;

#[test]
fn builtins_load_validate_and_transcribe_the_paper() {
    assert_eq!(Scene::builtin_names(), ["metamaterial", "homogeneous", "metamaterial-untaped"]);
    for name in Scene::builtin_names() {
        let s = Scene::builtin(name).unwrap();
        assert_eq!(s.name, *name);
        s.validate().unwrap();
        assert_eq!(s.plate.outline, Outline::Stadium { straight_length_m: 0.10, radius_m: 0.075 });
        assert_eq!(
            (s.plate.thickness_m, s.plate.youngs_modulus_pa, s.plate.poisson_ratio, s.plate.density_kg_m3),
            (0.0015, 3.2e9, 0.37, 1180.0)
        );
        assert_eq!((s.supports.len(), s.actuators.len()), (8, 8));
        assert_eq!((s.grid.nx, s.grid.ny, s.grid.spacing_m), (49, 25, 0.005));
        assert!(s.faults.is_empty());
    }
    let meta = Scene::builtin("metamaterial").unwrap();
    assert_eq!(meta.resonators.model, ResonatorModel::RockingRod);
    // The rods are the design `paper`'s: its lattice constant and whole rod height.
    assert_eq!(meta.resonators.design, Some(metaplate_core::design::Design::paper()));
    assert_eq!((meta.resonators.pitch_m, meta.resonators.rod_height_m), (0.008, 0.0334563));
    assert_eq!(Scene::builtin("homogeneous").unwrap().resonators.model, ResonatorModel::None);
    assert!(matches!(Scene::builtin("aluminium"), Err(SceneError::NotFound { .. })));
}

#[test]
fn the_two_builtins_differ_only_in_resonators() {
    // The two files repeat the shared parts; this keeps them from drifting apart.
    let meta = Scene::builtin("metamaterial").unwrap();
    let homo = Scene::builtin("homogeneous").unwrap();
    let twin = Scene {
        name: homo.name.clone(),
        description: homo.description.clone(),
        resonators: ResonatorSpec::none(),
        ..meta.clone()
    };
    assert_eq!(twin, homo);
    assert_ne!(meta.content_hash(), homo.content_hash());
}

#[test]
fn the_untaped_plate_differs_only_in_the_vibrometer() {
    let meta = Scene::builtin("metamaterial").unwrap();
    let untaped = Scene::builtin("metamaterial-untaped").unwrap();
    let twin = Scene {
        name: untaped.name.clone(),
        description: untaped.description.clone(),
        ldv: untaped.ldv,
        ..meta.clone()
    };
    assert_eq!(twin, untaped);
    // Less light, more speckle, dropouts and noise (the lab's 1 / level growth of the noise stops at a level of
    // 0.05, 16 times the taped scene's noise, too little to matter: the scene file says why); the same plate, so
    // the same Green's functions (one cache entry).
    assert!(untaped.ldv.speckle_mean_level < meta.ldv.speckle_mean_level / 10.0);
    assert!(untaped.ldv.speckle_spread > meta.ldv.speckle_spread);
    assert!(untaped.ldv.dropout_probability > meta.ldv.dropout_probability);
    assert!(untaped.ldv.noise_rms_m_s > meta.ldv.noise_rms_m_s);
    assert_eq!(untaped.ldv.max_velocity_m_s, meta.ldv.max_velocity_m_s);
    assert_eq!(untaped.physics_hash(), meta.physics_hash());
}

#[test]
fn round_trip_gives_an_equal_scene_and_hash() {
    let scenes = [
        Scene::builtin("metamaterial").unwrap(),
        Scene::builtin("homogeneous").unwrap(),
        Scene::from_toml_str(RECT_FAULTS, "rect_faults.toml").unwrap(),
    ];
    for s in scenes {
        let text = s.to_toml_string();
        let back = Scene::from_toml_str(&text, "round trip").unwrap();
        assert_eq!(back, s);
        assert_eq!(back.content_hash(), s.content_hash());
        assert_eq!(back.to_toml_string(), text, "the canonical text is a fixed point");
    }
}

#[test]
fn test_scene_reads_overrides_faults_and_defaults() {
    let s = Scene::from_toml_str(RECT_FAULTS, "rect_faults.toml").unwrap();
    assert!(s.supports.is_empty());
    assert_eq!(s.resonators.model, ResonatorModel::RockingRod);
    assert_eq!((s.resonators.height_spread, s.resonators.mass_ratio), (0.0, None));
    let (a, b) = (&s.actuators[0].voice_coil, &s.actuators[1].voice_coil);
    assert_eq!((a.nonlinearity, a.spread_db, b.nonlinearity, b.spread_db), (0.0, 0.0, 0.05, 3.0));
    assert_eq!(b.rolloff_hz, a.rolloff_hz);
    let kinds: Vec<FaultKind> = s.faults.iter().map(|f| f.kind).collect();
    assert_eq!(kinds, [FaultKind::SerialTimeout, FaultKind::LdvDropout, FaultKind::Disconnect]);
    // Every grid point of this rectangle is on the plate and there are no supports.
    assert_eq!(s.measured_points().len(), 45);
}

#[test]
fn hash_follows_content() {
    let s = Scene::builtin("metamaterial").unwrap();
    assert_eq!(s.content_hash(), Scene::builtin("metamaterial").unwrap().content_hash());
    let mut t = s.clone();
    t.seed += 1;
    assert_ne!(t.content_hash(), s.content_hash());
    let mut u = s.clone();
    u.actuators[3].voice_coil.nonlinearity = 0.02;
    assert_ne!(u.content_hash(), s.content_hash());
    // A per-actuator difference survives the canonical form's default-plus-overrides encoding.
    assert_eq!(Scene::from_toml_str(&u.to_toml_string(), "u").unwrap(), u);
}

#[test]
fn paper_grid_mask() {
    let s = Scene::builtin("metamaterial").unwrap();
    let mask = s.grid_mask();
    assert_eq!(mask.len(), 1225);
    // 1065 counted independently with exact rational arithmetic (Python `fractions`): of the 1225 points, 72 lie
    // outside the stadium (8 more lie exactly on its edge, the 3-4-5 points such as (0.095, 0.06) m, and count as
    // on it), and 88 lie on the 8 pads (6 under each straight-edge pad, 16 under each cap pad).
    assert_eq!(s.measured_points().len(), 1065);
    let at = |x: f64, y: f64| {
        let i = (0..s.grid.len())
            .find(|&i| {
                let (px, py) = s.grid.position_m(i);
                (px - x).abs() < TOL_M && (py - y).abs() < TOL_M
            })
            .unwrap();
        mask[i]
    };
    assert!(at(0.0, 0.0), "the centre is measured");
    assert!(!at(0.12, 0.06) && !at(-0.12, -0.06), "bounding-box corners are off the stadium");
    assert!(at(0.095, 0.06) && at(-0.11, -0.045), "points exactly on the edge count as on the plate");
    assert!(!at(0.10, 0.06), "just beyond the edge");
    assert!(!at(0.03, 0.06) && !at(0.09, 0.04) && !at(-0.085, -0.05), "under support pads");
    assert!(at(0.04, 0.05), "beside a pad");
    assert_eq!(Scene::builtin("homogeneous").unwrap().grid_mask(), mask);
}

#[test]
fn actuator_layout_is_peripheral_clear_off_grid_and_asymmetric() {
    let s = Scene::builtin("metamaterial").unwrap();
    let outline = s.plate.outline;
    for (i, a) in s.actuators.iter().enumerate() {
        let d = outline.distance_inside_m(a.x_m, a.y_m);
        assert!((0.015..=0.020).contains(&d), "actuator {i} is {d} m from the edge");
        // The magnets are 1 cm across: keep their centre 5 mm + margin clear of every pad's square.
        for p in &s.supports {
            let gap = ((a.x_m - p.x_m).abs().max((a.y_m - p.y_m).abs())) - p.size_m / 2.0;
            assert!(gap >= 0.008, "actuator {i} is {gap} m from a pad");
        }
        // Half a grid step (2.5 mm) from the nearest grid line in both directions: never on a grid point.
        for (v, o) in [(a.x_m, s.grid.origin_x_m), (a.y_m, s.grid.origin_y_m)] {
            let steps = (v - o) / s.grid.spacing_m;
            assert!(((steps - steps.floor()) - 0.5).abs() < 1e-6, "actuator {i} coordinate {v} m");
        }
    }
    let mirrored = |fx: f64, fy: f64| {
        s.actuators
            .iter()
            .all(|a| s.actuators.iter().any(|b| (b.x_m - fx * a.x_m).abs() < 1e-3 && (b.y_m - fy * a.y_m).abs() < 1e-3))
    };
    assert!(!mirrored(-1.0, 1.0) && !mirrored(1.0, -1.0) && !mirrored(-1.0, -1.0), "the layout must not be symmetric");
    // The supports, by contrast, are symmetric about both axes.
    for p in &s.supports {
        assert!(s.supports.iter().any(|q| (q.x_m + p.x_m).abs() < TOL_M && (q.y_m - p.y_m).abs() < TOL_M));
        assert!(s.supports.iter().any(|q| (q.x_m - p.x_m).abs() < TOL_M && (q.y_m + p.y_m).abs() < TOL_M));
    }
}

#[test]
fn resonator_lattice_and_mass_ratio() {
    let s = Scene::builtin("metamaterial").unwrap();
    let sites = s.resonators.lattice_sites_m(&s.plate.outline).unwrap();
    // 421 counted independently (Python, same rule): > 300 as the paper says.
    assert_eq!(sites.len(), 421);
    assert!(sites.iter().all(|&(x, y)| s.plate.outline.distance_inside_m(x, y) >= 0.01));
    // Rod mass / plate mass per cell: 8489 kg/m^3 x pi (3.175 mm)^2 / 4 x 33.4563 mm = 2.24860 g over 1180 kg/m^3 x
    // 1.5 mm x (8 mm)^2 = 0.11328 g, 19.8499 by hand; 1e-4 is the hand value's rounding.
    let ratio = s.resonators.cell_mass_ratio(s.plate.mass_per_area_kg_m2()).unwrap();
    assert!((ratio - 19.8499).abs() < 1e-4, "{ratio}");
    // The built-in takes its rods from its design and overrides nothing: the plate model takes the rest from the
    // cell (its dispersion tests own the values).
    assert_eq!(
        (s.resonators.mass_ratio, s.resonators.resonance_hz, s.resonators.gyration_radius_m),
        (None, None, None)
    );
    let homo = Scene::builtin("homogeneous").unwrap();
    assert!(homo.resonators.lattice_sites_m(&homo.plate.outline).unwrap().is_empty());
    assert!(homo.resonators.cell_mass_ratio(homo.plate.mass_per_area_kg_m2()).is_err(), "0/0 is refused");
    let tiny = ResonatorSpec { pitch_m: 1e-6, ..s.resonators.clone() };
    assert!(tiny.lattice_sites_m(&s.plate.outline).is_err(), "3.75e10 rods exceed the limit");
}

#[test]
fn plate_a0_dispersion() {
    let p = Scene::builtin("homogeneous").unwrap().plate;
    // D = 3.2e9 * 0.0015^3 / (12 * (1 - 0.37^2)) = 1.042753 N m (Python); 1e-6 relative covers its 7 digits.
    let d = p.bending_stiffness_n_m();
    assert!((d / 1.042_753 - 1.0).abs() < 1e-6, "{d}");
    assert!((p.mass_per_area_kg_m2() - 1.77).abs() < 1e-12);
    // At 100 Hz: k = (1.77 * (200 pi)^2 / D)^(1/4) = 28.611 rad/m, lambda = 0.21960 m (Python); 1e-4 relative
    // covers the 5-digit reference values.
    let k = p.a0_wavenumber_rad_m(100.0).unwrap();
    assert!((k / 28.611 - 1.0).abs() < 1e-4, "{k}");
    assert!((p.a0_wavelength_m(100.0).unwrap() / 0.21960 - 1.0).abs() < 1e-4);
    // lambda goes as f^(-1/2): exactly (to rounding, 1e-12 relative) half at 4x the frequency.
    let ratio = p.a0_wavelength_m(400.0).unwrap() / p.a0_wavelength_m(100.0).unwrap();
    assert!((ratio - 0.5).abs() < 1e-12);
    // Extremes: 0 Hz has k = 0 and no finite wavelength; an absurd frequency is still finite.
    assert_eq!(p.a0_wavenumber_rad_m(0.0).unwrap(), 0.0);
    assert!(matches!(p.a0_wavelength_m(0.0), Err(SceneError::InvalidArgument { .. })));
    for f_hz in [f64::MIN_POSITIVE, 1e-300, 1e300, f64::MAX] {
        let lambda = p.a0_wavelength_m(f_hz).unwrap();
        assert!(lambda.is_finite() && lambda > 0.0, "{f_hz} Hz: {lambda}");
    }
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(p.a0_wavenumber_rad_m(bad), Err(SceneError::InvalidArgument { .. })), "{bad}");
    }
}

#[test]
fn load_and_resolve_files() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/rect_faults.toml");
    let s = Scene::load(&path).unwrap();
    assert_eq!(s.name, "rect-faults");
    assert_eq!(Scene::resolve(path.to_str().unwrap()).unwrap(), s);
    assert_eq!(Scene::resolve("homogeneous").unwrap(), Scene::builtin("homogeneous").unwrap());
    assert!(matches!(Scene::resolve("/nonexistent/scene.toml"), Err(SceneError::NotFound { .. })));
    // A directory exists but is not a readable file.
    assert!(matches!(Scene::load(Path::new(env!("CARGO_MANIFEST_DIR"))), Err(SceneError::Io { .. })));
}

#[test]
fn seed_beyond_toml_integers_is_refused() {
    let mut s = Scene::builtin("metamaterial").unwrap();
    s.seed = u64::MAX;
    let e = s.validate().unwrap_err();
    assert_eq!(e.key_path(), Some("seed"));
    // The toml crate writes and reads such an integer, but the TOML spec (and so other readers) does not.
    let e = Scene::from_toml_str(&s.to_toml_string(), "x.toml").unwrap_err();
    assert_eq!(e.key_path(), Some("seed"));
}

/// The metamaterial scene with its rods given key by key (with a radius of gyration) instead of by its design.
fn keyed() -> String {
    let rods = format!("{KEYED_RODS}gyration_radius_m = 0.011\n");
    assert!(METAMATERIAL.contains("design = \"paper\"\n"), "test setup: the built-in names no design");
    METAMATERIAL.replacen("design = \"paper\"\n", &rods, 1)
}

/// Replaces the first `from` in the metamaterial scene with its rods given key by key ([`keyed`]) by `to` (which
/// must change the text).
fn mutate(from: &str, to: &str) -> String {
    let text = keyed();
    assert!(text.contains(from), "test setup: `{from}` is not in the scene");
    text.replacen(from, to, 1)
}

/// The built-in metamaterial scene, whose rods are the design `paper`'s (no rod key, no override), with its first
/// `from` replaced by `to`.
fn designed(from: &str, to: &str) -> String {
    assert!(METAMATERIAL.contains(from), "test setup: `{from}` is not in the scene");
    METAMATERIAL.replacen(from, to, 1)
}

/// A lattice naming a design takes the lattice constant and the rods from it, with no override; the scene's text
/// as written back holds the design inline (a dataset's copy stands alone) and reads back to the same scene; a
/// design file is read relative to the scene file's folder.
#[test]
fn a_lattice_named_by_a_design_takes_its_rods_and_is_written_inline() {
    let s = Scene::from_toml_str(&designed("", ""), "designed.toml").unwrap();
    let paper = metaplate_core::design::Design::paper();
    assert_eq!(s.resonators.design.as_ref(), Some(&paper));
    assert_eq!(s.resonators.model, ResonatorModel::RockingRod);
    assert_eq!(
        (s.resonators.pitch_m, s.resonators.rod_height_m, s.resonators.rod_diameter_m),
        (0.008, 0.0334563, 0.003175)
    );
    assert_eq!(
        (s.resonators.mass_ratio, s.resonators.resonance_hz, s.resonators.gyration_radius_m),
        (None, None, None)
    );
    assert_eq!((s.resonators.loss_factor, s.resonators.region_inset_m, s.resonators.height_spread), (0.01, 0.01, 0.01));
    assert_eq!(s.resonators.lattice_sites_m(&s.plate.outline).unwrap().len(), 421);
    let text = s.to_toml_string();
    assert!(text.contains("[resonators.design]") && !text.contains("design = \"paper\""), "{text}");
    assert_eq!(Scene::from_toml_str(&text, "written").unwrap(), s);
    assert_eq!(toml::from_str::<Scene>(&text).unwrap(), s);
    assert_eq!(s.id(), Scene::builtin("metamaterial").unwrap().id(), "the built-in is this scene");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("metaplate-scene-design-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("cells")).unwrap();
    std::fs::write(dir.join("cells/mine.toml"), toml::to_string(&paper).unwrap()).unwrap();
    std::fs::write(dir.join("scene.toml"), designed("design = \"paper\"", "design = \"cells/mine.toml\"")).unwrap();
    let from_file = Scene::load(&dir.join("scene.toml")).unwrap();
    assert_eq!(from_file.resonators.design.as_ref(), Some(&paper));
    // The same relative path with no scene folder to go by is looked for in the working directory: not found, and
    // the message names the file.
    let err = Scene::from_toml_str(&std::fs::read_to_string(dir.join("scene.toml")).unwrap(), "x.toml").unwrap_err();
    assert!(err.to_string().contains("cells/mine.toml"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The metamaterial scene without the table whose header is `header` (up to the next blank line).
fn without_table(header: &str) -> String {
    let start = METAMATERIAL.find(header).unwrap();
    let end = start + METAMATERIAL[start..].find("\n\n").unwrap();
    format!("{}{}", &METAMATERIAL[..start], &METAMATERIAL[end..])
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Syntax,
    Schema,
    Invalid,
}

#[test]
fn every_validation_error_names_file_key_and_reason() {
    let fault = |kind: &str, at_s: &str| {
        format!("{METAMATERIAL}\n[[faults]]\nkind = \"{kind}\"\nat_s = {at_s}\nduration_s = 0.1\n")
    };
    // (scene text, error kind, key path, a phrase the message must contain)
    let cases: Vec<(String, Kind, &str, &str)> = vec![
        (mutate("[plate]", "[plate"), Kind::Syntax, "", "not valid TOML"),
        (
            mutate("thickness_m = 0.0015", "thickness_mm = 1.5"),
            Kind::Schema,
            "plate.thickness_mm",
            "unknown key `thickness_mm`: this field is `thickness_m`, in metres",
        ),
        (
            mutate("density_kg_m3", "density_g_cm3"),
            Kind::Schema,
            "plate.density_g_cm3",
            "this field is `density_kg_m3`, in kg/m^3",
        ),
        (mutate("[grid]\n", "[grid]\ncolour = 1\n"), Kind::Schema, "grid.colour", "expected one of `nx`"),
        (mutate("thickness_m = 0.0015\n", ""), Kind::Schema, "plate", "missing key `thickness_m`"),
        (mutate("seed = 20240601\n", ""), Kind::Schema, "", "missing key `seed`"),
        (mutate("seed = 20240601", "seed = -1"), Kind::Schema, "seed", "invalid value"),
        (
            format!("{METAMATERIAL}\n[setup]\nswapped_actuators = [2, 2]\n"),
            Kind::Invalid,
            "setup.swapped_actuators",
            "two different actuators",
        ),
        (
            format!("{METAMATERIAL}\n[setup]\nswapped_actuators = [0, 8]\n"),
            Kind::Invalid,
            "setup.swapped_actuators",
            "of the 8 (0 to 7)",
        ),
        (
            format!("{METAMATERIAL}\n[setup]\naudio_device_rate_hz = 0.0\n"),
            Kind::Invalid,
            "setup.audio_device_rate_hz",
            "> 0",
        ),
        (format!("{METAMATERIAL}\n[setup]\nloopback = false\n"), Kind::Schema, "setup.loopback", "unknown"),
        (
            mutate("thickness_m = 0.0015", "thickness_m = \"1.5 mm\""),
            Kind::Schema,
            "plate.thickness_m",
            "write a plain number: `thickness_m` is in metres",
        ),
        (mutate("nx = 49", "nx = 4.9"), Kind::Schema, "grid.nx", "invalid type"),
        (
            mutate("shape = \"stadium\"", "shape = \"ellipse\""),
            Kind::Schema,
            "plate.outline.shape",
            "unknown variant `ellipse`",
        ),
        (mutate("pitch_m = 0.008\n", ""), Kind::Invalid, "resonators.pitch_m", "missing key `pitch_m`"),
        (
            designed("design = \"paper\"", "design = \"no-such-cell.toml\""),
            Kind::Invalid,
            "resonators.design",
            "cannot read no-such-cell.toml",
        ),
        (
            designed("design = \"paper\"", "design = \"paper\"\nrod_diameter_m = 0.003"),
            Kind::Invalid,
            "resonators.rod_diameter_m",
            "is given by the design",
        ),
        (
            designed("design = \"paper\"", "design = \"paper\"\nresonance_hz = 500.0"),
            Kind::Invalid,
            "resonators.resonance_hz",
            "taken from the design's cell",
        ),
        (
            designed("model = \"rocking_rod\"", "model = \"added_mass\""),
            Kind::Invalid,
            "resonators.model",
            "rocking_rod",
        ),
        (
            designed("thickness_m = 0.0015", "thickness_m = 0.002"),
            Kind::Invalid,
            "plate.thickness_m",
            "design `paper`'s plate has 0.0015",
        ),
        (
            mutate("x_m = -0.0125\n", "x_m = -0.0125\nvoice_coil = { q = 3.0 }\n"),
            Kind::Schema,
            "actuators[6].voice_coil.q",
            "unknown key `q`",
        ),
        (fault("gremlins", "1.0"), Kind::Schema, "faults[0].kind", "unknown variant `gremlins`"),
        (
            mutate("thickness_m = 0.0015", "thickness_m = -0.0015"),
            Kind::Invalid,
            "plate.thickness_m",
            "must be finite and > 0",
        ),
        (
            mutate("thickness_m = 0.0015", "thickness_m = 0"),
            Kind::Invalid,
            "plate.thickness_m",
            "must be finite and > 0",
        ),
        (mutate("thickness_m = 0.0015", "thickness_m = nan"), Kind::Invalid, "plate.thickness_m", "must be finite"),
        (mutate("thickness_m = 0.0015", "thickness_m = 1.5"), Kind::Invalid, "plate.thickness_m", "1.5 mm is 0.0015"),
        (mutate("radius_m = 0.075", "radius_m = -0.075"), Kind::Invalid, "plate.outline.radius_m", "> 0"),
        (mutate("poisson_ratio = 0.37", "poisson_ratio = 0.5"), Kind::Invalid, "plate.poisson_ratio", "(-1, 0.5)"),
        (mutate("poisson_ratio = 0.37", "poisson_ratio = -1.0"), Kind::Invalid, "plate.poisson_ratio", "(-1, 0.5)"),
        (
            mutate("youngs_modulus_pa = 3.2e9", "youngs_modulus_pa = 0.0"),
            Kind::Invalid,
            "plate.youngs_modulus_pa",
            "must lie in",
        ),
        (
            mutate("youngs_modulus_pa = 3.2e9", "youngs_modulus_pa = 3.2"),
            Kind::Invalid,
            "plate.youngs_modulus_pa",
            "in the key's unit",
        ),
        (
            mutate("density_kg_m3 = 1180.0", "density_kg_m3 = 1.18"),
            Kind::Invalid,
            "plate.density_kg_m3",
            "in the key's unit",
        ),
        (mutate("loss_factor = 0.03", "loss_factor = -0.03"), Kind::Invalid, "plate.loss_factor", "must lie in"),
        (
            mutate("x_m = 0.03\ny_m = 0.063", "x_m = 0.03\ny_m = 0.07"),
            Kind::Invalid,
            "supports[0]",
            "not wholly under the plate",
        ),
        (
            mutate("stiffness_n_per_m = 3.2e3", "stiffness_n_per_m = 0.0"),
            Kind::Invalid,
            "supports[0].stiffness_n_per_m",
            "> 0",
        ),
        (
            mutate("rod_diameter_m = 0.003175", "rod_diameter_m = 0.01"),
            Kind::Invalid,
            "resonators.rod_diameter_m",
            "do not fit",
        ),
        (
            mutate("region_inset_m = 0.01", "region_inset_m = 0.08"),
            Kind::Invalid,
            "resonators.region_inset_m",
            "no lattice site",
        ),
        (mutate("height_spread = 0.01", "height_spread = 0.7"), Kind::Invalid, "resonators.height_spread", "[0, 0.5)"),
        (
            mutate("height_spread = 0.01", "height_spread = 0.01\nmass_ratio = -1.0"),
            Kind::Invalid,
            "resonators.mass_ratio",
            "> 0",
        ),
        (
            mutate("gyration_radius_m = 0.011", "gyration_radius_m = -0.011"),
            Kind::Invalid,
            "resonators.gyration_radius_m",
            "> 0",
        ),
        (
            mutate("gyration_radius_m = 0.011", "gyration_radius_m = 0.05"),
            Kind::Invalid,
            "resonators.gyration_radius_m",
            "exceeds the rod height",
        ),
        (mutate("x_m = 0.1075", "x_m = 0.2075"), Kind::Invalid, "actuators[0]", "off the plate"),
        (
            mutate("x_m = 0.0075\ny_m = 0.0575", "x_m = 0.03\ny_m = 0.0575"),
            Kind::Invalid,
            "actuators[2]",
            "on support pad supports[0]",
        ),
        (
            mutate("suspension_q = 2.0", "suspension_q = -2.0"),
            Kind::Invalid,
            "actuators[0].voice_coil.suspension_q",
            "> 0",
        ),
        (without_table("[voice_coil]"), Kind::Invalid, "actuators[0].voice_coil", "missing key `force_factor_n_per_v`"),
        (mutate("spacing_m = 0.005", "spacing_m = 0.0"), Kind::Invalid, "grid.spacing_m", "positive"),
        (mutate("spacing_m = 0.005", "spacing_m = -0.005"), Kind::Invalid, "grid.spacing_m", "positive"),
        (mutate("nx = 49", "nx = 0"), Kind::Invalid, "grid.nx", "empty"),
        (mutate("nx = 49", "nx = 100000"), Kind::Invalid, "grid.nx", "exceed the limit"),
        (mutate("origin_x_m = -0.12", "origin_x_m = 1.0"), Kind::Invalid, "grid", "no grid point is on the plate"),
        (
            mutate("dropout_probability = 0.001", "dropout_probability = 1.5"),
            Kind::Invalid,
            "ldv.dropout_probability",
            "must lie in",
        ),
        (
            mutate("speckle_mean_level = 0.8", "speckle_mean_level = 0.0"),
            Kind::Invalid,
            "ldv.speckle_mean_level",
            "(0, 1]",
        ),
        (mutate("bits = 16", "bits = 33"), Kind::Invalid, "daq.bits", "1..=32"),
        (
            mutate("clock_offset_ppm = 20.0", "clock_offset_ppm = 5000.0"),
            Kind::Invalid,
            "daq.clock_offset_ppm",
            "must lie in",
        ),
        (mutate("channels = 24", "channels = 8"), Kind::Invalid, "audio.channels", "loopback"),
        (mutate("latency_s = 0.005", "latency_s = -0.005"), Kind::Invalid, "audio.latency_s", ">= 0"),
        (fault("usb_stall", "-1.0"), Kind::Invalid, "faults[0].at_s", ">= 0"),
    ];
    for (text, kind, key_path, phrase) in cases {
        let err = Scene::from_toml_str(&text, "test.toml").unwrap_err();
        let msg = err.to_string();
        let kind_ok = matches!(
            (kind, &err),
            (Kind::Syntax, SceneError::Syntax { .. })
                | (Kind::Schema, SceneError::Schema { .. })
                | (Kind::Invalid, SceneError::Invalid { .. })
        );
        assert!(kind_ok, "{kind:?} expected, got {err:?}");
        assert!(msg.starts_with("test.toml:"), "no file and line in: {msg}");
        if !matches!(kind, Kind::Syntax) {
            assert_eq!(err.key_path(), Some(key_path), "{msg}");
        }
        assert!(msg.contains(phrase), "`{phrase}` not in: {msg}");
    }
}

#[test]
fn no_actuators_is_refused() {
    let mut s = Scene::builtin("homogeneous").unwrap();
    s.actuators.clear();
    assert_eq!(s.validate().unwrap_err().key_path(), Some("actuators"));
}

#[test]
fn errors_point_at_the_right_line() {
    let text = mutate("poisson_ratio = 0.37", "poisson_ratio = 0.6");
    let line = text[..text.find("poisson_ratio = 0.6").unwrap()].lines().count() + 1;
    let msg = Scene::from_toml_str(&text, "f.toml").unwrap_err().to_string();
    assert!(msg.starts_with(&format!("f.toml:{line}:1: plate.poisson_ratio:")), "{msg}");
    let text = mutate("[grid]\n", "[grid]\ncolour = 1\n");
    let line = text[..text.find("colour").unwrap()].lines().count() + 1;
    let msg = Scene::from_toml_str(&text, "f.toml").unwrap_err().to_string();
    assert!(msg.starts_with(&format!("f.toml:{line}:1: grid.colour:")), "{msg}");
}

#[test]
fn serde_form_is_the_file_form() {
    // Other crates embed a scene in manifests through serde: the form must be the file's, and reading validates.
    let s = Scene::from_toml_str(RECT_FAULTS, "rect_faults.toml").unwrap();
    assert_eq!(toml::to_string(&s).unwrap(), s.to_toml_string());
    assert_eq!(toml::from_str::<Scene>(&s.to_toml_string()).unwrap(), s);
    let bad = s.to_toml_string().replacen("thickness_m = 0.002", "thickness_m = -0.002", 1);
    let err = toml::from_str::<Scene>(&bad).unwrap_err();
    assert!(err.to_string().contains("plate.thickness_m"), "{err}");
}

/// The built-in scene's identity, pinned: a change here means every dataset's scene id and every Green's-function
/// cache key changes (resumes refuse, caches recompute). Change it only with [`CANONICAL_FORM_VERSION`], or with the
/// built-in's content, on purpose and in CHANGELOG.md (0.9.0: its rods became the design `paper`'s).
const METAMATERIAL_ID: &str = "fnv1a64:eb48bf68ae760260";

#[test]
fn scene_id_is_pinned_and_spelled_once() {
    let s = Scene::builtin("metamaterial").unwrap();
    let id = s.id();
    assert_eq!(id.name, "metamaterial");
    assert_eq!(id.hash, METAMATERIAL_ID);
    assert_eq!(id.hash, format!("{SCENE_HASH_PREFIX}{:016x}", s.content_hash()));
    assert!(s.canonical_text().starts_with(&format!("metaplate-scene-canonical-v{CANONICAL_FORM_VERSION}\n")));
}

#[test]
fn scene_id_depends_only_on_the_values() {
    let s = Scene::builtin("metamaterial").unwrap();
    let text = s.to_toml_string();
    // The same scene written differently: keys reordered (top level and within a table), other whitespace, other
    // float spellings (1e3 for 1000.0, 1.5e-3 for 0.0015, 3_200_000_000.0 for 3.2e9).
    let original = include_str!("../scenes/metamaterial.toml");
    let reformatted = original
        .replacen("seed = 20240601\n", "", 1)
        .replacen("name = \"metamaterial\"\n", "name   =   \"metamaterial\"\nseed=20240601\n", 1)
        .replacen(
            "youngs_modulus_pa = 3.2e9\npoisson_ratio = 0.37\n",
            "poisson_ratio = 3.7e-1\n  youngs_modulus_pa = 3_200_000_000.0\n",
            1,
        )
        .replacen("density_kg_m3 = 1180.0", "density_kg_m3 = 1.18e3", 1)
        .replacen("thickness_m = 0.0015", "thickness_m = 1.5e-3", 1)
        .replacen("nx = 49\nny = 25\n", "ny = 25\nnx = 49\n", 1);
    for (old, new) in [("seed=", "seed = 20240601"), ("3.7e-1", "poisson"), ("1.18e3", "density"), ("1.5e-3", "thick")]
    {
        assert!(reformatted.contains(old), "the rewrite of `{new}` applied");
    }
    assert_ne!(reformatted, original);
    let r = Scene::from_toml_str(&reformatted, "metamaterial.toml").unwrap();
    assert_eq!(r, s);
    assert_eq!(r.id(), s.id());
    assert_eq!(r.canonical_text(), s.canonical_text());
    // The resolved scene's own TOML (another layout again) reads back to the same identity.
    assert_eq!(Scene::from_toml_str(&text, "resolved").unwrap().id(), s.id());
    // And a value change is an identity change.
    // (The plate's outline: its thickness must stay the design's.)
    let wider = original.replacen("radius_m = 0.075", "radius_m = 0.076", 1);
    assert_ne!(Scene::from_toml_str(&wider, "metamaterial.toml").unwrap().id(), s.id());
}

#[test]
fn a_setup_table_changes_the_identity_not_the_physics() {
    let s = Scene::builtin("metamaterial").unwrap();
    // A correct setup writes no table: the built-ins' identity is the one pinned above.
    assert!(s.setup.is_correct() && !s.to_toml_string().contains("[setup]"));
    let text = format!(
        "{METAMATERIAL}\n[setup]\nswapped_actuators = [2, 5]\nloopback_disconnected = true\n\
         audio_device_rate_hz = 44100.0\ndisk_free_bytes = 1000000\n"
    );
    let faulty = Scene::from_toml_str(&text, "faulty.toml").unwrap();
    assert_eq!(faulty.setup.swapped_actuators, Some([2, 5]));
    assert!(faulty.setup.loopback_disconnected);
    assert_eq!((faulty.setup.audio_device_rate_hz, faulty.setup.disk_free_bytes), (Some(44_100.0), Some(1_000_000)));
    assert_eq!(Scene::from_toml_str(&faulty.to_toml_string(), "again").unwrap(), faulty, "round trip");
    assert_ne!(faulty.id(), s.id());
    assert_eq!(faulty.physics_hash(), s.physics_hash(), "the plate is the same: its Green's functions are shared");
    // What the plate depends on changes the physics: the seed (resonator spread), the plate.
    let mut reseeded = s.clone();
    reseeded.seed += 1;
    assert_ne!(reseeded.physics_hash(), s.physics_hash());
    let mut noisier = s.clone();
    noisier.ldv.noise_rms_m_s *= 10.0;
    noisier.name = "noisier".into();
    assert_eq!(noisier.physics_hash(), s.physics_hash());
    assert_ne!(Scene::builtin("homogeneous").unwrap().physics_hash(), s.physics_hash());
    // A plate without resonator spread draws nothing from its seed: its seeds share one physics.
    let plain = Scene::builtin("homogeneous").unwrap();
    let mut plain_reseeded = plain.clone();
    plain_reseeded.seed += 1;
    assert_eq!(plain_reseeded.physics_hash(), plain.physics_hash());
    let mut unspread = s.clone();
    unspread.resonators.height_spread = 0.0;
    let mut unspread_reseeded = unspread.clone();
    unspread_reseeded.seed += 1;
    assert_eq!(unspread_reseeded.physics_hash(), unspread.physics_hash());
}

#[test]
fn every_imperfection_switches_off_on_the_same_plate() {
    for name in Scene::builtin_names() {
        let s = Scene::builtin(name).unwrap();
        // The built-ins have every imperfection but faults and an aiming error.
        let absent = [Imperfection::Faults, Imperfection::AimError];
        for &i in Imperfection::all() {
            assert_eq!(i.is_present(&s), !absent.contains(&i), "{name}: {i}");
            assert_eq!(Imperfection::by_name(i.name()), Some(i));
            let off = s.without(&[i]);
            assert!(!i.is_present(&off), "{name}: {i} is off");
            // Each switch touches its own imperfection alone.
            for &j in Imperfection::all().iter().filter(|&&j| j != i) {
                assert_eq!(j.is_present(&off), j.is_present(&s), "{name}: {i} off leaves {j}");
            }
            assert_eq!(off.physics_hash(), s.physics_hash(), "{name}: {i} off shares the Green's functions");
            assert_eq!(off.id() != s.id(), i.is_present(&s), "{name}: {i}");
        }
        let ideal = s.with_only(&[]);
        assert!(Imperfection::all().iter().all(|i| !i.is_present(&ideal)));
        assert_eq!((ideal.daq.bits, ideal.daq.clipping, ideal.ldv.noise_rms_m_s), (0, false, 0.0));
        assert_eq!(s.with_only(Imperfection::all()), s);
        assert_eq!(s.with_only(&[Imperfection::LdvNoise]), s.without(&Imperfection::all()[1..]));
        // The ideal scene is a valid scene file, the optional keys written and read back.
        let text = ideal.to_toml_string();
        assert!(text.contains("clipping = false") && text.contains("bits = 0"), "{text}");
        assert_eq!(Scene::from_toml_str(&text, "ideal").unwrap(), ideal);
        // The default writes no optional key (the identity pinned above is unchanged).
        assert!(!s.to_toml_string().contains("clipping") && !s.to_toml_string().contains("aim_error"));
        // The aiming error reads, writes and switches off.
        let mut aimed = s.clone();
        aimed.ldv.aim_error_rms_m = 0.0005;
        let text = aimed.to_toml_string();
        assert!(text.contains("aim_error_rms_m = 0.0005"), "{text}");
        assert_eq!(Scene::from_toml_str(&text, "aimed").unwrap(), aimed);
        assert!(Imperfection::AimError.is_present(&aimed) && aimed.with_only(&[]).ldv.aim_error_rms_m == 0.0);
        assert_eq!(aimed.physics_hash(), s.physics_hash());
        let bad = text.replace("aim_error_rms_m = 0.0005", "aim_error_rms_m = 0.5");
        assert!(Scene::from_toml_str(&bad, "bad").unwrap_err().to_string().contains("ldv.aim_error_rms_m"));
    }
}

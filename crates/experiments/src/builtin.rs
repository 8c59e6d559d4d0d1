//! The paper's four behavioural experiments, built in (files in `experiments/builtin/`).

use crate::error::ExperimentError;
use crate::file::Experiment;

/// The built-in experiments: name and TOML text, in the paper's order.
const BUILTINS: &[(&str, &str)] = &[
    ("pixel-identification", include_str!("../builtin/pixel-identification.toml")),
    ("odd-one-out-exploration", include_str!("../builtin/odd-one-out-exploration.toml")),
    ("motion-direction", include_str!("../builtin/motion-direction.toml")),
    ("multi-touch-odd-one-out", include_str!("../builtin/multi-touch-odd-one-out.toml")),
];

/// The names of the built-in experiments, in the paper's order.
pub fn names() -> Vec<&'static str> {
    BUILTINS.iter().map(|(n, _)| *n).collect()
}

/// The TOML text of a built-in experiment.
pub fn text(name: &str) -> Option<&'static str> {
    BUILTINS.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// A built-in experiment by name.
///
/// # Errors
/// [`ExperimentError::NotFound`] for an unknown name. (A built-in that failed to parse would be an
/// [`ExperimentError::Invalid`]; the tests make sure none does.)
pub fn builtin(name: &str) -> Result<Experiment, ExperimentError> {
    match text(name) {
        Some(text) => Experiment::from_toml_str(text, &format!("<built-in {name}>")),
        None => Err(ExperimentError::NotFound { name: name.to_owned(), known: names().join(", ") }),
    }
}

/// A built-in experiment when `name_or_path` names one (a built-in wins over a file of the same name), else the
/// experiment file at that path.
///
/// # Errors
/// [`ExperimentError::NotFound`] when it is neither; otherwise as [`Experiment::load`].
pub fn resolve(name_or_path: &str) -> Result<Experiment, ExperimentError> {
    if text(name_or_path).is_some() {
        return builtin(name_or_path);
    }
    let path = std::path::Path::new(name_or_path);
    if path.exists() {
        Experiment::load(path)
    } else {
        Err(ExperimentError::NotFound { name: name_or_path.to_owned(), known: names().join(", ") })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;
    use crate::plan::{Phase, Plan};

    /// (name, conditions, repeats, familiarisation trials, chance), as the paper's Methods give them.
    const PAPER: &[(&str, usize, u32, usize, f64)] = &[
        ("pixel-identification", 5, 10, 5, 0.2),
        ("odd-one-out-exploration", 10, 5, 10, 0.2),
        ("motion-direction", 8, 10, 8, 0.5),
        ("multi-touch-odd-one-out", 5, 10, 5, 0.2),
    ];

    #[test]
    fn the_four_parse_and_plan_to_the_papers_counts() {
        assert_eq!(names(), PAPER.iter().map(|p| p.0).collect::<Vec<_>>());
        for &(name, conditions, repeats, familiarisation, chance) in PAPER {
            let e = builtin(name).unwrap();
            assert_eq!(e.name, name);
            assert_eq!(e.stimuli.len(), conditions, "{name}");
            assert_eq!(e.phases.repeats, repeats, "{name}");
            assert_eq!(e.chance, chance, "{name}");
            assert_eq!(e.pixels.len(), 5);
            let plan = Plan::new(&e, e.order.seed);
            let fam = plan.trials.iter().filter(|t| t.phase == Phase::Familiarisation).count();
            assert_eq!(fam, familiarisation, "{name}");
            assert_eq!(plan.trials.len() - fam, conditions * repeats as usize, "{name}");
            for s in &e.stimuli {
                let w = s.waveforms(&e, 1).unwrap();
                assert_eq!(w.iter().filter(|p| p.target).count(), if name == "motion-direction" { 5 } else { 1 });
            }
        }
        assert!(matches!(builtin("nope"), Err(ExperimentError::NotFound { .. })));
    }

    #[test]
    fn the_pixels_lie_on_both_plates_display_region_next_to_a_measured_point() {
        use metaplate_core::scene::Scene;
        for scene in ["metamaterial", "homogeneous"] {
            let scene = Scene::builtin(scene).unwrap();
            let measured = scene.measured_points();
            let inset_m = Scene::builtin("metamaterial").unwrap().resonators.region_inset_m;
            for name in names() {
                for p in &builtin(name).unwrap().pixels {
                    // Inside the resonator region (the display), with a fingertip's radius (8 mm) to spare.
                    assert!(scene.plate.outline.distance_inside_m(p.x_m, p.y_m) > inset_m + 0.008, "{name}: {p:?}");
                    let nearest_m = measured
                        .iter()
                        .map(|&i| {
                            let (x, y) = scene.grid.position_m(i);
                            (x - p.x_m).hypot(y - p.y_m)
                        })
                        .fold(f64::INFINITY, f64::min);
                    assert!(nearest_m <= scene.grid.spacing_m / 2.0 + 1e-12, "{name}: {p:?} {nearest_m}");
                }
            }
        }
    }

    #[test]
    fn the_paper_stimuli_have_the_papers_timing() {
        let one = builtin("pixel-identification").unwrap();
        // 5 bursts of 25 ms with 75 ms pauses: 4 x 100 ms + 25 ms.
        assert!((one.stimuli[0].duration_s() - 0.425).abs() < 1e-12);
        let three = builtin("motion-direction").unwrap();
        let speeds: Vec<(f64, u32)> =
            three.stimuli.iter().map(|s| (s.sequence.as_ref().unwrap().delay_s, s.plays)).collect();
        assert_eq!(speeds[..2], [(0.64, 1), (0.64, 1)]);
        assert_eq!(speeds[6..], [(0.08, 4), (0.08, 4)]);
        // 3.2 cm between fingertips: 5 cm/s at 640 ms, 40 cm/s at 80 ms.
        let spacing_m = three.pixels[1].x_m - three.pixels[0].x_m;
        assert!((spacing_m / 0.64 - 0.05).abs() < 1e-12 && (spacing_m / 0.08 - 0.4).abs() < 1e-12);
        let four = builtin("multi-touch-odd-one-out").unwrap();
        assert_eq!(four.stimuli[2].target_pixels(), ["middle"]);
        let two = builtin("odd-one-out-exploration").unwrap();
        assert!(two.record_trial_times);
        assert_eq!(two.presentation, crate::file::Presentation::UntilResponse);
    }
}

//! Property tests: no text, however broken, makes scene loading panic; whatever loads is valid and round-trips.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap

use metaplate_core::scene::Scene;
use proptest::prelude::*;

const METAMATERIAL: &str = include_str!("../scenes/metamaterial.toml");
const RECT_FAULTS: &str = include_str!("scenes/rect_faults.toml");

/// Whatever `from_toml_str` accepts must be a valid scene that survives a round trip.
fn check_text(text: &str) -> Result<(), TestCaseError> {
    if let Ok(scene) = Scene::from_toml_str(text, "fuzz.toml") {
        prop_assert!(scene.validate().is_ok());
        let back = Scene::from_toml_str(&scene.to_toml_string(), "round trip");
        prop_assert_eq!(back.as_ref().ok(), Some(&scene));
        prop_assert_eq!(scene.grid_mask().len(), scene.grid.len());
    }
    Ok(())
}

/// Snippets a TOML scene is made of, to splice into valid text.
fn tomlish() -> impl Strategy<Value = String> {
    prop_oneof![
        "[a-z_\\[\\]=\"'{}.,:#\\- \n0-9]{0,16}",
        Just("[[actuators]]\n".to_owned()),
        Just("[[faults]]\nkind = \"usb_stall\"\n".to_owned()),
        Just("= { shape = \"rectangle\" }".to_owned()),
        Just("nan".to_owned()),
        Just("-inf".to_owned()),
        Just("1e308".to_owned()),
        Just("18446744073709551616".to_owned()),
        Just("\"\u{e9}\u{1F600}\"".to_owned()),
    ]
}

/// A float as TOML spells it, including the extremes.
fn toml_float() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| if v.is_finite() { format!("{v:?}") } else { "nan".to_owned() }),
        Just("inf".to_owned()),
        Just("-0.0".to_owned()),
        Just("0".to_owned()),
        Just("-1".to_owned()),
        (-1e3f64..1e3).prop_map(|v| format!("{v:?}")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in any::<String>()) {
        check_text(&text)?;
    }

    #[test]
    fn tomlish_text_never_panics(parts in prop::collection::vec(tomlish(), 0..24)) {
        check_text(&parts.concat())?;
    }

    #[test]
    fn spliced_scenes_never_panic(
        base in prop_oneof![Just(METAMATERIAL), Just(RECT_FAULTS)],
        at in 0.0f64..1.0,
        cut in 0usize..40,
        insert in tomlish(),
    ) {
        let start = ((base.len() as f64 * at) as usize).min(base.len());
        let start = (0..=start).rev().find(|&i| base.is_char_boundary(i)).unwrap_or(0);
        let end = (start + cut..=base.len()).find(|&i| base.is_char_boundary(i)).unwrap_or(base.len());
        check_text(&format!("{}{insert}{}", &base[..start], &base[end..]))?;
    }

    #[test]
    fn any_number_in_a_valid_scene_never_panics(
        base in prop_oneof![Just(METAMATERIAL), Just(RECT_FAULTS)],
        which in any::<prop::sample::Index>(),
        value in toml_float(),
    ) {
        // Every `key = number` line is a candidate; replace one number.
        let lines: Vec<&str> = base.lines().collect();
        let numeric: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].split_once(" = ").is_some_and(|(_, v)| v.parse::<f64>().is_ok()))
            .collect();
        let i = numeric[which.index(numeric.len())];
        let key = lines[i].split_once(" = ").map(|(k, _)| k).unwrap_or("");
        let mut out: Vec<String> = lines.iter().map(|l| (*l).to_owned()).collect();
        out[i] = format!("{key} = {value}");
        check_text(&out.join("\n"))?;
    }
}

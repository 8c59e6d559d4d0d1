use metaplate_core::toml_locate::DocIndex;

/// The fields of a plate table, as a scene's schema names them (units in the names; `loss_factor` has none).
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)] // Only the refusals are looked at.
struct Plate {
    outline: Option<String>,
    thickness_m: Option<f64>,
    youngs_modulus_pa: Option<f64>,
    density_kg_m3: Option<f64>,
    loss_factor: Option<f64>,
}

/// The message of the schema error `text` gets, as a reader sees it.
fn message(text: &str) -> String {
    let index = DocIndex::parse(text, "plate.toml").unwrap();
    let e = toml::from_str::<Plate>(text).unwrap_err();
    index.schema_error(&e).message
}

#[test]
fn unit_hints() {
    assert_eq!(message("thickness_mm = 1.5"), "unknown key `thickness_mm`: this field is `thickness_m`, in metres");
    assert_eq!(message("thickness = 1.5"), "unknown key `thickness`: this field is `thickness_m`, in metres");
    assert_eq!(
        message("youngs_modulus_gpa = 3.2"),
        "unknown key `youngs_modulus_gpa`: this field is `youngs_modulus_pa`, in pascals"
    );
    assert_eq!(message("density_g_cm3 = 1.2"), "unknown key `density_g_cm3`: this field is `density_kg_m3`, in kg/m^3");
    assert!(message("colour = 1").contains("expected one of `outline`"), "{}", message("colour = 1"));
    // `loss_factor` has no unit, so `loss_factor_db` is not a unit mistake of it.
    assert!(message("loss_factor_db = 1").contains("expected one of"), "{}", message("loss_factor_db = 1"));
    // A value of the wrong type under a key with a unit says to write a plain number; without a unit it does not.
    assert!(message("thickness_m = \"1.5 mm\"").ends_with("; write a plain number: `thickness_m` is in metres"));
    assert!(!message("loss_factor = \"0.01\"").contains("plain number"), "{}", message("loss_factor = \"0.01\""));
}

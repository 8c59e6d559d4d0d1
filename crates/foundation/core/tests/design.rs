//! Design files: the paper's cell as TOML equals the built-in; mistakes are reported with file, line and key.

use metaplate_core::design::Design;
use metaplate_core::toml_locate::TomlFileError;

const PAPER_TOML: &str = r#"name = "paper"
lattice_constant_m = 0.008

[plate]
thickness_m = 0.0015
youngs_modulus_pa = 3.2e9
poisson_ratio = 0.37
density_kg_m3 = 1180

[resonator]
kind = "rod"
height_m = 0.0334563
diameter_m = 0.003175
embedded_m = 0.0015
youngs_modulus_pa = 97e9
poisson_ratio = 0.31
density_kg_m3 = 8489
side = "top"
"#;

fn invalid(text: &str) -> String {
    match Design::from_toml_str(text, "cell.toml") {
        Err(TomlFileError::Invalid(located)) => located.to_string(),
        other => panic!("expected an invalid design, got {other:?}"),
    }
}

#[test]
fn paper_file_equals_builtin() {
    assert_eq!(Design::from_toml_str(PAPER_TOML, "paper.toml").unwrap(), Design::paper());
    assert_eq!(Design::resolve("paper").unwrap(), Design::paper());
}

#[test]
fn unit_mistake_names_file_line_and_key() {
    let message = invalid(&PAPER_TOML.replace("height_m = 0.0334563", "height_mm = 33.4563"));
    assert!(message.starts_with("cell.toml:12:"), "{message}");
    assert!(message.contains("height_mm") && message.contains("height_m") && message.contains("metres"), "{message}");
}

#[test]
fn out_of_range_value_names_line_and_key() {
    let message = invalid(&PAPER_TOML.replace("embedded_m = 0.0015", "embedded_m = 0.003"));
    assert!(message.starts_with("cell.toml:14:"), "{message}");
    assert!(message.contains("resonator.embedded_m"), "{message}");
}

#[test]
fn keys_of_another_kind_and_missing_keys_are_refused() {
    let stray = invalid(&PAPER_TOML.replace("side = \"top\"", "side = \"top\"\nmass_kg = 0.001"));
    assert!(stray.contains("resonator.mass_kg") && stray.contains("not a key of this resonator kind"), "{stray}");
    let missing = invalid(&PAPER_TOML.replace("diameter_m = 0.003175\n", ""));
    assert!(missing.contains("diameter_m"), "{missing}");
    let syntax = invalid("lattice_constant_m = = 1");
    assert!(syntax.starts_with("cell.toml:1:"), "{syntax}");
}

#[test]
fn missing_file_is_an_io_error() {
    let error = Design::resolve("/nonexistent/cell.toml").unwrap_err();
    assert!(matches!(error, TomlFileError::Io { .. }), "{error}");
    assert!(error.to_string().contains("/nonexistent/cell.toml"));
}

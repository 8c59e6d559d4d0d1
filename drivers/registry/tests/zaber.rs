//! `[aim] backend = "zaber"`: its keys, and their checks with the key named.

use std::path::Path;

use metaplate_drivers::{Capability, HardwareError, HardwareFile, aim::AimSection};

const EXAMPLE: &str = include_str!("../../../crates/cli/hardware.example.toml");

const ZABER: &str = r#"
[aim]
backend = "zaber"
port = "/dev/serial/by-id/usb-Zaber-test"
moves = "plate"
move_timeout_s = 30.0

[aim.x]
device = 1
microstep_um = 0.047625
origin_mm = 50.0

[aim.y]
device = 2
axis = 1
microstep_um = 0.047625
origin_mm = 40.0
travel_max_mm = 90.0
"#;

/// The example file with `aim` appended (the example has no `[aim]`, or its own is replaced).
fn with_aim(aim: &str) -> String {
    let end = EXAMPLE.find("\n[aim]").unwrap_or(EXAMPLE.len());
    format!("{}\n{aim}", &EXAMPLE[..end])
}

fn parse(text: &str) -> Result<HardwareFile, HardwareError> {
    HardwareFile::parse(text, Path::new("rig.toml"))
}

fn key_error(text: &str) -> (String, String) {
    match parse(text) {
        Err(HardwareError::File { key, reason, .. }) => (key, reason),
        other => panic!("not a file error: {other:?}"),
    }
}

#[test]
fn the_zaber_section_parses_with_its_defaults() {
    let file = parse(&with_aim(ZABER)).unwrap();
    assert!(file.backends().contains(&(Capability::Aim, "zaber")));
    let Some(AimSection::Zaber(zaber)) = &file.aim else { panic!("{:?}", file.aim) };
    assert_eq!(
        (zaber.baud, zaber.moves.as_str(), zaber.reply_timeout_s, zaber.move_timeout_s),
        (115_200, "plate", 0.5, 30.0)
    );
    assert_eq!((zaber.x.device, zaber.x.axis, zaber.y.travel_max_mm), (1, 1, Some(90.0)));
}

#[test]
fn bad_zaber_keys_are_named() {
    let (key, reason) = key_error(&with_aim(&ZABER.replace("moves = \"plate\"", "moves = \"beam\"")));
    assert_eq!(key, "aim.moves", "{reason}");
    let (key, reason) = key_error(&with_aim(&ZABER.replace("origin_mm = 40.0", "origin_mm = 40.0\nspeed = 3")));
    assert!(key == "aim" && reason.contains("speed"), "{key}: {reason}");
    let (key, _) = key_error(&with_aim(&ZABER.replace("device = 2", "device = \"two\"")));
    assert_eq!(key, "aim");
    if metaplate_drivers::backends::find(Capability::Aim, "zaber").is_some_and(|b| b.available) {
        // Ranges are checked where the backend is built.
        let (key, reason) = key_error(&with_aim(&ZABER.replace("device = 2", "device = 0")));
        assert_eq!(key, "aim.y.device", "{reason}");
        let (key, reason) = key_error(&with_aim(
            &ZABER.replace("microstep_um = 0.047625\norigin_mm = 50.0", "microstep_um = 0.0\norigin_mm = 50.0"),
        ));
        assert_eq!(key, "aim.x.microstep_um", "{reason}");
        let (key, reason) = key_error(&with_aim(&ZABER.replace("device = 2", "device = 1")));
        assert!(key == "aim.y" && reason.contains("same axis"), "{key}: {reason}");
    }
}

#[test]
fn a_found_chain_drafts_a_zaber_section_that_parses_once_uncommented() {
    use metaplate_drivers::{BACKENDS, Found, Listing, draft_hardware_file};
    let chain = Found {
        key: "aim.port",
        value: "/dev/ttyUSB3".into(),
        description: "Zaber chain: device 1 (id 50081), device 2 (id 50081)".into(),
    };
    let listings: Vec<Listing> = BACKENDS
        .iter()
        .map(|backend| {
            let found = if backend.name == "zaber" { vec![chain.clone()] } else { Vec::new() };
            Listing { backend, found, problem: None }
        })
        .collect();
    let draft = draft_hardware_file(&listings, Path::new("draft.toml")).unwrap();
    assert!(draft.contains("# port = \"/dev/ttyUSB3\""), "{draft}");
    // Uncommenting the section gives a file that names the stages.
    let start = draft.find("# [aim]").unwrap();
    let end = start + draft[start..].find("\n\n").unwrap_or(draft.len() - start);
    let section: String = draft[start..end].lines().map(|l| l.trim_start_matches("# ")).collect::<Vec<_>>().join("\n");
    let uncommented = format!("{}{}\n{}", &draft[..start], section, &draft[end..]);
    let file = parse(&uncommented).unwrap();
    assert!(file.backends().contains(&(Capability::Aim, "zaber")), "{uncommented}");
}

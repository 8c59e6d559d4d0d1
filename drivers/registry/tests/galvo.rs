//! `[aim] backend = "galvo"`: its keys, the fit path against the file's folder, and errors naming the key.

use std::path::{Path, PathBuf};

use metaplate_drivers::aim::{AimSection, MirrorOutputsSection};
use metaplate_drivers::{Capability, HardwareError, HardwareFile, open_galvo_outputs};

const EXAMPLE: &str = include_str!("../../../crates/cli/hardware.example.toml");

const GALVO: &str = "\n[aim]\nbackend = \"galvo\"\nfit = \"galvo-fit.toml\"\nsettle_ms = 2.5\n\n[aim.outputs]\nbackend = \
                     \"nidaqmx\"\ndevice = \"Dev1\"\nx_channel = \"ao0\"\ny_channel = \"ao1\"\n";

fn parse(text: &str) -> Result<HardwareFile, HardwareError> {
    HardwareFile::parse(text, Path::new("/lab/rig.toml"))
}

#[test]
fn a_galvo_section_is_read_with_its_fit_beside_the_file() {
    let file = parse(&format!("{EXAMPLE}{GALVO}")).unwrap();
    let Some(AimSection::Galvo(galvo)) = &file.aim else { panic!("{:?}", file.aim) };
    assert_eq!(galvo.fit, PathBuf::from("/lab/galvo-fit.toml"));
    assert_eq!(galvo.settle_ms, 2.5);
    let MirrorOutputsSection::Nidaqmx(ni) = &galvo.outputs;
    assert_eq!(
        (ni.device.as_str(), ni.x_channel.as_str(), ni.y_channel.as_str(), ni.limit_v),
        ("Dev1", "ao0", "ao1", 10.0)
    );
    assert_eq!(file.backends().last(), Some(&(Capability::Aim, "galvo")));
    let absolute = parse(&format!("{EXAMPLE}{}", GALVO.replace("\"galvo-fit.toml\"", "\"/fits/g.toml\""))).unwrap();
    assert!(matches!(&absolute.aim, Some(AimSection::Galvo(g)) if g.fit == Path::new("/fits/g.toml")));
    assert!(parse(EXAMPLE).unwrap().aim.is_none(), "[aim] is optional");
}

#[test]
fn bad_galvo_sections_name_the_key() {
    let cases = [
        (GALVO.replace("settle_ms = 2.5", "settle_ms = -1.0"), "aim.settle_ms"),
        (GALVO.replace("settle_ms = 2.5\n", ""), "aim"),
        (GALVO.replace("backend = \"nidaqmx\"", "backend = \"usb\""), "aim.outputs.backend"),
        (GALVO.replace("y_channel", "z_channel"), "aim.outputs"),
        (GALVO.replace("device = \"Dev1\"", "device = \"\""), "aim.outputs.device"),
        (GALVO.replace("backend = \"galvo\"", "backend = \"laser\""), "aim.backend"),
    ];
    for (section, key) in cases {
        match parse(&format!("{EXAMPLE}{section}")) {
            Err(HardwareError::File { key: k, reason, .. }) => assert_eq!(k, key, "{reason}"),
            other => panic!("{key}: {other:?}"),
        }
    }
}

#[test]
fn teaching_needs_a_galvo_section() {
    let file = parse(EXAMPLE).unwrap();
    match open_galvo_outputs(&file) {
        Err(HardwareError::File { key, .. }) => assert_eq!(key, "aim"),
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("opened outputs the file does not name"),
    }
}

//! `[aim] backend = "galvo"`: its keys, the fit path against the file's folder, and errors naming the key.

use std::path::{Path, PathBuf};

use metaplate_aim::galvo::{FitModel, GalvoFit, TaughtPoint};
use metaplate_drivers::aim::{AimSection, MirrorOutputsSection};
use metaplate_drivers::{Capability, HardwareError, HardwareFile, OpenPurpose, open_galvo_outputs, open_rig};

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

/// A taught fit whose residual is over `aim.max_residual_mm` is refused when the rig opens, naming the aimer, the
/// residual and the limit (one mark taught 2 mm off: marks taught wrongly, or mirrors moved since). The example's
/// other instruments are absent here (named too).
#[cfg(all(feature = "serial", feature = "labjack-u6", feature = "alsa", feature = "nidaqmx", target_os = "linux"))]
#[test]
fn a_fit_whose_residual_is_over_its_limit_is_refused_naming_the_aimer() {
    let dir = tempfile::tempdir().unwrap();
    let marks = [(0.0, 0.0), (0.4, 0.0), (0.4, 0.2), (0.0, 0.2), (0.2, 0.1), (0.1, 0.15), (0.3, 0.05)];
    let points: Vec<TaughtPoint> = marks
        .iter()
        .enumerate()
        .map(|(i, &(x_m, y_m))| {
            let off_m = if i == 4 { 0.002 } else { 0.0 };
            TaughtPoint { x_m, y_m, x_v: 20.0 * (x_m + off_m) - 4.0, y_v: 20.0 * y_m - 2.0 }
        })
        .collect();
    let fit = GalvoFit::fit(FitModel::Projective, &points).unwrap();
    assert!(fit.residual().max_mm > 0.5, "{}", fit.summary());
    metaplate_aim::galvo::file::write(&dir.path().join("galvo-fit.toml"), &fit).unwrap();
    let path = dir.path().join("rig.toml");
    let aim_failure = |limit: &str| -> String {
        let galvo = GALVO.replace("settle_ms = 2.5\n", &format!("settle_ms = 2.5\n{limit}"));
        let file = HardwareFile::parse(&format!("{EXAMPLE}{galvo}"), &path).unwrap();
        let error = open_rig(&file, OpenPurpose::Check).err().unwrap();
        let failed = error.failed_instruments();
        let sections: Vec<&str> = failed.iter().map(|(s, _)| *s).collect();
        assert_eq!(sections, ["ldv", "daq", "audio", "aim"], "{error}");
        failed[3].1.clone()
    };
    let refused = aim_failure("");
    assert!(refused.contains("max_residual_mm = 0.5") && refused.contains("aim teach"), "{refused}");
    // Within a looser limit the fit passes, and what fails is the mirrors' outputs (no NI-DAQmx here).
    let looser = aim_failure("max_residual_mm = 5.0\n");
    assert!(!looser.contains("max_residual_mm") && looser.contains("`Dev1` (galvo)"), "{looser}");
    let bad = GALVO.replace("settle_ms = 2.5\n", "settle_ms = 2.5\nmax_residual_mm = 0.0\n");
    match parse(&format!("{EXAMPLE}{bad}")) {
        Err(HardwareError::File { key, .. }) => assert_eq!(key, "aim.max_residual_mm"),
        other => panic!("{other:?}"),
    }
}

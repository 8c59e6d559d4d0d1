//! The hardware file: every backend reachable from it, typed errors naming the file, the key and the reason, and the
//! registry's tables.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use std::path::Path;

use metaplate_drivers::{
    BACKENDS, Capability, DaqSection, HardwareError, HardwareFile, KeypadSection, OpenPurpose, backends, open_rig,
};

const EXAMPLE: &str = include_str!("../../../crates/cli/hardware.example.toml");

fn parse(text: &str) -> Result<HardwareFile, HardwareError> {
    HardwareFile::parse(text, Path::new("rig.toml"))
}

/// The example with its `[daq]` section replaced by `daq`.
fn with_daq(daq: &str) -> String {
    let start = EXAMPLE.find("[daq]").unwrap();
    let end = EXAMPLE.find("# An NI DAQ").unwrap();
    format!("{}{daq}\n{}", &EXAMPLE[..start], &EXAMPLE[end..])
}

#[test]
fn the_example_names_a_backend_per_instrument() {
    let file = parse(EXAMPLE).unwrap();
    let named: Vec<_> = file.backends();
    assert_eq!(
        named,
        [(Capability::Vibrometer, "polytec"), (Capability::Daq, "labjack-u6"), (Capability::Audio, "alsa")]
    );
    let DaqSection::LabjackU6(u6) = &file.daq else { panic!("{:?}", file.daq) };
    let selector = u6.selector();
    // LabJack's vendor id and the U6's product id; its endpoints as the Exodriver's labjackusb.h names them.
    assert_eq!(
        (selector.vendor_id, selector.product_id, selector.serial.as_deref()),
        (0x0cd5, 0x0006, Some("360012345"))
    );
    assert_eq!(
        (selector.interface, selector.endpoint_out, selector.endpoint_in, selector.endpoint_stream),
        (0, 0x01, 0x82, 0x83)
    );
    assert_eq!((u6.settings().resolution_index, u6.settings().settling_factor), (0, 0));
    assert!(file.keypad.is_none());
}

#[test]
fn nidaqmx_and_the_keypad_are_selectable() {
    let text = with_daq("[daq]\nbackend = \"nidaqmx\"\ndevice = \"Dev1\"\n")
        + "\n[keypad]\nbackend = \"hidraw\"\nusb = \"046d:c31c\"\nreport_id = 1\n";
    let file = parse(&text).unwrap();
    let DaqSection::Nidaqmx(ni) = &file.daq else { panic!("{:?}", file.daq) };
    assert_eq!((ni.device.as_str(), ni.read_timeout_s), ("Dev1", 10.0));
    let Some(KeypadSection::Hidraw(keypad)) = &file.keypad else { panic!("{:?}", file.keypad) };
    assert_eq!((keypad.usb.as_str(), keypad.report_id), ("046d:c31c", Some(1)));
    let named: Vec<_> = file.backends().into_iter().map(|(_, name)| name).collect();
    assert_eq!(named, ["polytec", "nidaqmx", "alsa", "hidraw"]);
}

/// The audio interface's own inputs as the DAQ: the capture PCM and the inputs' full scale, which the wiring's DAQ
/// range must be; opening it opens nothing yet (ALSA opens a stream when the recipe configures its rate and inputs).
#[test]
fn the_audio_interfaces_inputs_are_selectable_as_the_daq() {
    let example = parse(EXAMPLE).unwrap();
    let range_v = example.wiring.daq_range_v;
    let text =
        with_daq(&format!("[daq]\nbackend = \"alsa\"\ndevice = \"hw:CARD=24Ao,DEV=0\"\nfull_scale_v = {range_v:?}\n"));
    let file = parse(&text).unwrap();
    let DaqSection::Alsa(alsa) = &file.daq else { panic!("{:?}", file.daq) };
    assert_eq!((alsa.device.as_str(), alsa.full_scale_v), ("hw:CARD=24Ao,DEV=0", range_v));
    assert_eq!(file.backends()[1], (Capability::Daq, "alsa"));
    assert_eq!(alsa.channel_map, None);
    let with_map = parse(&with_daq(&format!(
        "[daq]\nbackend = \"alsa\"\ndevice = \"hw:0\"\nfull_scale_v = {range_v:?}\nchannel_map = [\"AUX0\", \"AUX1\"]\n"
    )))
    .unwrap();
    let DaqSection::Alsa(alsa) = &with_map.daq else { panic!("{:?}", with_map.daq) };
    assert_eq!(alsa.channel_map.as_deref(), Some(&["AUX0".to_owned(), "AUX1".to_owned()][..]));
    let full_scale = format!("full_scale_v = {range_v:?}\n");
    for (daq, key) in [
        (format!("device = \"hw:0\"\n{full_scale}channel_map = []\n"), "daq.channel_map"),
        (format!("device = \"hw:0\"\n{full_scale}channel_map = [\"FL\", \" \"]\n"), "daq.channel_map"),
    ] {
        let err = parse(&with_daq(&format!("[daq]\nbackend = \"alsa\"\n{daq}"))).unwrap_err();
        assert!(matches!(&err, HardwareError::File { key: k, .. } if k.starts_with(key)), "{daq}: {err}");
    }
    for (daq, key) in [
        ("device = \"hw:0\"\nfull_scale_v = -1.0\n", "daq.full_scale_v"),
        ("device = \"hw:0\"\nfull_scale_v = 1.737\n", "wiring.daq_range_v"),
        ("device = \"hw:0\"\n", "daq"),
    ] {
        let err = parse(&with_daq(&format!("[daq]\nbackend = \"alsa\"\n{daq}"))).unwrap_err();
        assert!(matches!(&err, HardwareError::File { key: k, .. } if k.starts_with(key)), "{daq}: {err}");
    }
}

/// The example with an NI DAQ `Dev1` and the `[daq]` keys `rest` (which may open `[daq.inputs.aiN]` tables).
fn ni(rest: &str) -> String {
    with_daq(&format!("[daq]\nbackend = \"nidaqmx\"\ndevice = \"Dev1\"\n{rest}"))
}

#[test]
fn nidaqmx_terminal_configuration_range_trigger_and_library_reach_the_settings() {
    use metaplate_daq::{NiInput, StartTrigger, TerminalConfig};
    let text = ni("terminal = \"NRSE\"\ntrigger = \"PFI0\"\nlibrary = \"lib/libnidaqmx.so\"\n\
                   [daq.inputs.ai0]\nterminal = \"diff\"\nrange_v = 5.0\n[daq.inputs.ai3]\nrange_v = 0.2\n");
    let file = HardwareFile::parse(&text, Path::new("/lab/rig.toml")).unwrap();
    let DaqSection::Nidaqmx(section) = &file.daq else { panic!("{:?}", file.daq) };
    let settings = section.settings(&file.path).unwrap();
    assert_eq!(settings.terminal, TerminalConfig::Nrse);
    assert_eq!(settings.trigger, StartTrigger::Terminal("/Dev1/PFI0".into()));
    assert_eq!(settings.library.as_deref(), Some(Path::new("/lab/lib/libnidaqmx.so")), "relative to the file");
    assert_eq!(settings.input(0), NiInput { terminal: TerminalConfig::Differential, range_v: Some(5.0) });
    assert_eq!(settings.input(3), NiInput { terminal: TerminalConfig::Nrse, range_v: Some(0.2) });
    assert_eq!(settings.input(1), NiInput { terminal: TerminalConfig::Nrse, range_v: None });
    let ao = ni("trigger = \"ao\"\n");
    let DaqSection::Nidaqmx(section) = &parse(&ao).unwrap().daq else { panic!() };
    assert_eq!(
        section.settings(Path::new("rig.toml")).unwrap().trigger.source("Dev1").as_deref(),
        Some("/Dev1/ao/StartTrigger")
    );
}

/// The example with an analog vibrometer of range line `range` in place of the Polytec.
fn analog(range: &str) -> String {
    let start = EXAMPLE.find("[ldv]").unwrap();
    let end = EXAMPLE.find("# A vibrometer without a remote interface").unwrap();
    let section = format!("[ldv]\nbackend = \"analog\"\n{range}\nvendor = \"Polytec\"\nmodel = \"OFV-505\"\n");
    format!("{}{section}{}", &EXAMPLE[..start], &EXAMPLE[end..])
}

#[test]
fn polytec_decoder_choices_and_an_analog_vibrometer_are_read() {
    use metaplate_drivers::LdvSection;
    use metaplate_ldv::DecoderChoice;
    for (line, want) in [
        ("", DecoderChoice::First),
        ("decoder = \"VD-09\"", DecoderChoice::Name("VD-09".into())),
        ("decoder = 1", DecoderChoice::Index(1)),
    ] {
        let file = parse(&EXAMPLE.replace("baud = 115200", &format!("baud = 115200\n{line}"))).unwrap();
        let LdvSection::Polytec(polytec) = &file.ldv else { panic!("{:?}", file.ldv) };
        assert_eq!(polytec.config().unwrap().decoder, want, "{line}");
    }
    let file = parse(&analog("range = \"25mm/s/V\"")).unwrap();
    let LdvSection::Analog(ldv) = &file.ldv else { panic!("{:?}", file.ldv) };
    assert_eq!((ldv.range.as_str(), ldv.identity().model.as_str()), ("25mm/s/V", "OFV-505"));
    assert_eq!(file.backends()[0].1, "analog");
}

/// Each bad file is refused with the file, the key in error and a reason containing `expected`.
#[test]
fn bad_files_name_the_key_and_the_reason() {
    let cases: Vec<(String, &str, &str)> = vec![
        (
            EXAMPLE.replace("backend = \"labjack-u6\"", "backend = \"usb-bulk\""),
            "daq.backend",
            "one of labjack-u6, nidaqmx",
        ),
        (EXAMPLE.replace("backend = \"polytec\"\n", ""), "ldv.backend", "missing"),
        (EXAMPLE.replace("baud = 115200", "baud = 115200\ndecoder = 9"), "ldv", "an index is 0 to 7"),
        (EXAMPLE.replace("baud = 115200", "baud = 115200\nautofocus = \"Wide\""), "ldv", "\"Full\""),
        (analog("range = \"25 furlongs\""), "ldv.range", "not a velocity range"),
        (EXAMPLE.replace("backend = \"alsa\"", "backend = 3"), "audio.backend", "not a backend name"),
        (EXAMPLE.replace("baud = 115200", "baud = 9600"), "ldv.baud", "115200 baud"),
        (EXAMPLE.replace("serial = \"360012345\"", "serial = \"SN0001\""), "daq.serial", "not a U6 serial number"),
        (
            EXAMPLE.replace("serial = \"360012345\"", "serial = \"360012345\"\nresolution_index = 9"),
            "daq.resolution_index",
            "0-8",
        ),
        (EXAMPLE.replace("serial = \"360012345\"", "serial = \"360012345\"\ninterface = 0"), "daq", "interface"),
        (with_daq("[daq]\nbackend = \"nidaqmx\"\ndevice = \"Dev1\"\nusb = \"1209:0001:SN1\"\n"), "daq", "usb"),
        (
            with_daq("[daq]\nbackend = \"nidaqmx\"\ndevice = \"Dev1\"\nread_timeout_s = -1.0\n"),
            "daq.read_timeout_s",
            "-1",
        ),
        (ni("terminal = \"single\"\n"), "daq.terminal", "not a terminal configuration: one of default, rse"),
        (ni("trigger = \"start\"\n"), "daq.trigger", "not a start trigger"),
        (ni("[daq.inputs.ai0]\nterminal = \"psuedo\"\n"), "daq.inputs.ai0.terminal", "\"psuedo\""),
        (ni("[daq.inputs.ai1]\nrange_v = 0.0\n"), "daq.inputs.ai1.range_v", "not a positive voltage"),
        (ni("[daq.inputs.x1]\nrange_v = 1.0\n"), "daq.inputs.x1", "not an analog input"),
        (ni("[daq.inputs.ai0]\ngain = 1.0\n"), "daq", "gain"),
        (EXAMPLE.to_string() + "\n[keypad]\nbackend = \"hidraw\"\nusb = \"046d\"\n", "keypad.usb", "not VID:PID"),
        (EXAMPLE.replace("loopback_channel = 8", "loopback_channel = 3"), "wiring", "used twice"),
        (EXAMPLE.replace("plate = ", "plates = "), "(file)", "plates"),
    ];
    for (text, key, expected) in cases {
        match parse(&text) {
            Err(error @ HardwareError::File { .. }) => {
                let HardwareError::File { path, key: got, reason } = &error else { unreachable!() };
                assert_eq!((path.as_path(), got.as_str()), (Path::new("rig.toml"), key), "{error}");
                assert!(reason.contains(expected), "{key}: {error}");
                assert!(error.to_string().starts_with("hardware file rig.toml: "), "{error}");
            }
            other => panic!("{key}: {other:?}"),
        }
    }
}

#[test]
fn every_capability_has_a_table_and_every_backend_a_feature() {
    for capability in Capability::ALL {
        assert!(backends::of(capability).count() >= 1, "{capability:?}");
    }
    for backend in BACKENDS {
        assert!(!backend.needs.is_empty() && !backend.feature.is_empty(), "{backend:?}");
        assert_eq!(backend.available, backend.missing_reason().is_none(), "{backend:?}");
        // Listing never fails for want of devices; backends that do not enumerate yet list nothing.
        if !matches!(backend.name, "polytec" | "labjack-u6") {
            assert_eq!(backend.list(), Ok(Vec::new()), "{backend:?}");
        }
    }
    assert_eq!(backends::find(Capability::Daq, "nidaqmx").map(|b| b.feature), Some("nidaqmx"));
    assert!(backends::find(Capability::Daq, "serial").is_none());
}

/// Without a backend, a file naming it is refused before any device is opened, saying so.
#[test]
fn a_backend_missing_from_this_build_is_named() {
    let file = parse(EXAMPLE).unwrap();
    let missing: Vec<_> = file
        .backends()
        .into_iter()
        .filter_map(|(capability, name)| backends::find(capability, name))
        .filter(|b| !b.available)
        .collect();
    let Some(first) = missing.first() else {
        return; // This build has every backend the example names: nothing to refuse.
    };
    match open_rig(&file, OpenPurpose::Check) {
        Err(error @ HardwareError::NotInThisBuild { .. }) => {
            let message = error.to_string();
            assert!(message.contains(first.name) && message.contains(&first.missing_reason().unwrap()), "{message}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
}

/// The example with `edit` applied, written in a temporary directory.
fn edited(edit: impl Fn(String) -> String) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hardware.toml");
    std::fs::write(&path, edit(EXAMPLE.to_string())).unwrap();
    (dir, path)
}

#[test]
fn the_examples_wiring_fits_its_plate() {
    let file = parse(EXAMPLE).unwrap();
    assert_eq!(file.plate, "metamaterial");
    let wiring = file.wiring();
    assert_eq!(wiring.actuator_channels, (0..8).collect::<Vec<u32>>());
    assert_eq!((wiring.loopback_channel, wiring.audio_channels), (8, 10));
}

/// Every instrument is tried whatever became of the others, so one error names each that cannot be opened: here
/// all three of the example's (no such serial port, U6 or sound card on this machine).
#[test]
#[cfg(all(feature = "serial", feature = "labjack-u6", feature = "alsa", target_os = "linux"))]
fn every_instrument_that_cannot_be_opened_is_named_in_one_error() {
    let missing = "/dev/metaplate-no-such-port";
    let (_dir, path) = edited(|text| {
        let start = text.find("port = ").unwrap();
        let end = start + text[start..].find('\n').unwrap();
        format!("{}port = \"{missing}\"{}", &text[..start], &text[end..])
    });
    let error = metaplate_drivers::open_plate_rig(&path, OpenPurpose::Check).err().unwrap();
    let HardwareError::Devices { failures } = &error else { panic!("{error:?}") };
    assert!(matches!(failures[0], HardwareError::Device { device: "LDV", .. }), "{failures:?}");
    let failed = error.failed_instruments();
    let sections: Vec<&str> = failed.iter().map(|(section, _)| *section).collect();
    assert_eq!(sections, ["ldv", "daq", "audio"], "{error}");
    assert!(failed[0].1.contains("LDV") && failed[0].1.contains(missing), "{}", failed[0].1);
    assert!(failed[1].1.contains("360012345") && failed[2].1.contains("hw:CARD=24Ao"), "{error}");
    let message = error.to_string();
    assert!(failed.iter().all(|(_, m)| message.contains(m.as_str())), "one message names them all: {message}");
    // A measurement or a playback stops at the first instrument that fails: nothing after it is opened.
    for purpose in [OpenPurpose::Measure, OpenPurpose::Play] {
        let first = metaplate_drivers::open_plate_rig(&path, purpose).err().unwrap();
        let sections: Vec<&str> = first.failed_instruments().iter().map(|(s, _)| *s).collect();
        assert_eq!(sections, ["ldv"], "{purpose:?}: {first}");
    }
    // An error of the file opens nothing, so it names no instrument.
    let (_bad, bad) = edited(|text| text.replace("[ldv]", "[ldv_typo]"));
    assert!(metaplate_drivers::open_plate_rig(&bad, OpenPurpose::Check).err().unwrap().failed_instruments().is_empty());
}

#[test]
fn a_wiring_that_does_not_fit_the_plate_is_refused_before_opening_anything() {
    let (_dir, path) = edited(|text| text.replace("[0, 1, 2, 3, 4, 5, 6, 7]", "[0, 1, 2, 3, 4, 5, 6]"));
    let error = metaplate_drivers::open_plate_rig(&path, OpenPurpose::Check).err().unwrap();
    let message = error.to_string();
    assert!(message.contains("lists 7 actuators") && message.contains("has 8"), "{message}");
}

#[test]
fn usb_ids_parse_in_one_place() {
    let ids = metaplate_drivers::UsbIds::parse("ffff:ffff:none").unwrap();
    assert_eq!((ids.vendor_id, ids.product_id, ids.serial.as_deref()), (0xFFFF, 0xFFFF, Some("none")));
    assert_eq!(metaplate_drivers::UsbIds::parse("046d:c31c").unwrap().serial, None);
    for bad in ["", "12", "zz:01", "1234:12345", "1234:5678:"] {
        assert!(metaplate_drivers::UsbIds::parse(bad).is_err(), "{bad:?}");
    }
}

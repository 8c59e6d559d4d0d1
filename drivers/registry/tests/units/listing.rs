#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_drivers::HardwareFile;
use metaplate_drivers::backends::{BACKENDS, Capability, Found};
use std::path::Path;

use metaplate_drivers::listing::*;

#[test]
fn a_draft_from_nothing_parses_and_marks_every_choice() {
    let listings: Vec<Listing> =
        BACKENDS.iter().map(|backend| Listing { backend, found: Vec::new(), problem: None }).collect();
    let text = draft_hardware_file(&listings, Path::new("draft.toml")).unwrap();
    assert!(text.contains("port = \"/dev/ttyUSB0\"   # CHOOSE"), "{text}");
    let json = serde_json::to_string(&listings_json(&listings)).unwrap();
    // Sections in key order: `aim` (which lists nothing: its outputs are listed as what they are) first.
    assert!(json.starts_with("{\"aim\":[{\"backend\":\"galvo\",\"found\":[],\"in_this_build\":true"), "{json}");
    assert!(json.contains("\"audio\":[{\"backend\":\"alsa\",\"found\":[],\"in_this_build\":"), "{json}");
}

#[test]
fn an_ni_device_drafts_galvo_mirrors_on_its_outputs_that_parse_once_uncommented() {
    let mut listings: Vec<Listing> =
        BACKENDS.iter().map(|backend| Listing { backend, found: Vec::new(), problem: None }).collect();
    let ni = Found { key: "daq.device", value: "Dev2".into(), description: "USB-6211 s/n 01A2B3C4".into() };
    let at = listings.iter().position(|l| l.backend.name == "nidaqmx").unwrap();
    listings[at].found = vec![ni];
    let text = draft_hardware_file(&listings, Path::new("draft.toml")).unwrap();
    assert!(text.contains("device = \"Dev2\"   # CHECK: the only one found"), "the DAQ on it: {text}");
    assert!(text.contains("# NI-DAQmx device Dev2 found: USB-6211 s/n 01A2B3C4.\n# CHOOSE: uncomment"), "{text}");
    // The galvo section uncommented (from its `[aim]` to the end of the commented block) is a valid `[aim]` on
    // the same device.
    let mut inside = false;
    let uncommented: String = text
        .lines()
        .map(|line| {
            inside = (inside || line == "# [aim]") && line.starts_with("# ");
            format!("{}\n", if inside { &line[2..] } else { line })
        })
        .collect();
    assert!(uncommented.contains("[aim.outputs]\nbackend = \"nidaqmx\"\ndevice = \"Dev2\"\n"), "{uncommented}");
    let file = HardwareFile::parse(&uncommented, Path::new("draft.toml")).unwrap();
    assert!(file.aim.is_some(), "{uncommented}");
}

#[test]
fn a_capture_pcm_is_named_as_the_alternative_not_taken_for_an_ni_device() {
    let mut listings: Vec<Listing> =
        BACKENDS.iter().map(|backend| Listing { backend, found: Vec::new(), problem: None }).collect();
    let pcm = Found { key: "daq.device", value: "hw:CARD=24Ao,DEV=0".into(), description: "MOTU 24Ao".into() };
    let at = listings.iter().position(|l| l.backend.name == "alsa" && l.backend.capability == Capability::Daq);
    listings[at.unwrap()].found = vec![pcm];
    let text = draft_hardware_file(&listings, Path::new("draft.toml")).unwrap();
    assert!(text.contains("backend = \"labjack-u6\""), "no NI device was found: {text}");
    assert!(!text.contains("# [aim]\n# backend = \"galvo\""), "no galvo outputs on a sound card: {text}");
    assert!(text.contains("# or the audio interface's inputs: backend = \"alsa\", device = \"hw:CARD=24Ao,DEV=0\""));
}

#[test]
fn found_devices_fill_the_draft_first_one_first() {
    let found = |value: &str| Found { key: "ldv.port", value: value.into(), description: "FTDI".into() };
    let mut listings: Vec<Listing> =
        BACKENDS.iter().map(|backend| Listing { backend, found: Vec::new(), problem: None }).collect();
    listings[0].found = vec![found("/dev/ttyUSB1"), found("/dev/ttyUSB2")];
    let text = draft_hardware_file(&listings, Path::new("draft.toml")).unwrap();
    assert!(text.contains("port = \"/dev/ttyUSB1\"   # CHOOSE: the first of these: FTDI"), "{text}");
    assert!(text.contains("# port = \"/dev/ttyUSB2\"   # or this one"), "{text}");
    assert!(listings_text(&listings).contains("2 found\n  ldv.port = \"/dev/ttyUSB1\""));
}

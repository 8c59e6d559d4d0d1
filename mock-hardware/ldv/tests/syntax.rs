//! The mock answers Polytec's syntax as the public sources show it: each exchange with its source (*PLACE*:
//! github.com/PALab/place `place/plugins/polytec/polytec.py`; *PLACE (old)*: its `place/automate/polytec/
//! vibrometer.py` before commit 42a86fb; *OFV-3001 E.2.4*: the OFV-3001 manual's RS-232 appendix).

use std::sync::Arc;

use metaplate_core::clock::VirtualClock;
use metaplate_mock_ldv::{FaultSchedule, UnitSpec};

use crate::common;

/// Sends each line and returns what the device answered to it.
fn exchange(unit: UnitSpec, lines: &[&str]) -> Vec<String> {
    let device = common::device(unit, FaultSchedule::none(), Arc::new(VirtualClock::new()));
    let mut device = device.lock().unwrap();
    lines
        .iter()
        .map(|line| {
            device.receive(format!("{line}\n").as_bytes());
            String::from_utf8(device.take_output()).unwrap()
        })
        .collect()
}

#[test]
fn place_session_against_the_place_example_unit() {
    let got = exchange(
        UnitSpec::place_example(),
        &[
            "GetDevInfo,Controller,0,Name",  // PLACE _get_controller_name
            "Set,Interface,0,Echo,Off",      // PLACE (old) setEcho: echoed while echo is still on
            "GetDevInfo,VeloDec,1,Name",     // PLACE (old) get_dev_name: VD-09 is 'VeloDec,1'
            "Set,VeloDec,1,Range,5mm/s/V",   // PLACE _set_range: no reply
            "Get,VeloDec,1,Range",           // PLACE _get_range
            "Get,VeloDec,1,Range,x",         // malformed: ignored (OFV-3001 E.2.4)
            "GetDevInfo,VeloDec,2,Name",     // a third decoder: none
            "GetDevInfo,SensorHead,0,Focus", // not modelled: Not Available
        ],
    );
    assert_eq!(
        got,
        [
            // Echo is on at power-up on this unit (OFV-3001 E.2.4's "Answer with ECHOON").
            "GetDevInfo,Controller,0,Name\nOFV-5000 Vibrometer Controller\n",
            "Set,Interface,0,Echo,Off\n",
            "VD-09\n",
            "",
            "5mm/s/V\n",
            "",
            "Not Available\n",
            "Not Available\n",
        ]
    );
}

#[test]
fn ranges_filters_remote_and_autofocus_on_the_lab_unit() {
    let got = exchange(
        UnitSpec::lab_default(),
        &[
            "GetDevInfo,VeloDec,0,Range",
            "Set,VeloDec,0,Range,125mm/s/V",
            "Get,VeloDec,0,Range",
            "Set,VeloDec,0,Range,7mm/s/V", // not on the decoder: ignored
            "Get,VeloDec,0,Range",
            "Set,VeloDec,0,Range,1m/s/V", // the same scale as 1000mm/s/V, spelt otherwise
            "Get,VeloDec,0,Range",
            "Set,VeloDec,0,TrackingFilter,Fast",
            "Get,VeloDec,0,TrackingFilter",
            "GetDevInfo,VeloDec,0,LowPass",
            "Set,Controller,0,Remote,On",
            "Get,Controller,0,Remote",
            "Set,SensorHead,0,AutoFocusSpan,Full", // PLACE _autofocus_vibrometer
            "Set,SensorHead,0,AutoFocus,Search",
            "Get,SensorHead,0,AutoFocusResult",
            "Get,SensorHead,0,AutoFocusResult",
            "Get,SensorHead,0,AutoFocusResult",
            "GetDevInfo,SignalLevel,0,Value",
        ],
    );
    let want = [
        "1mm/s/V,5mm/s/V,25mm/s/V,125mm/s/V,1000mm/s/V\n",
        "",
        "125mm/s/V\n",
        "",
        "125mm/s/V\n",
        "",
        "1000mm/s/V\n",
        "",
        "Fast\n",
        "Off,1.5kHz,20kHz,100kHz\n",
        "",
        "On\n",
        "",
        "",
        "Searching\n",
        "Searching\n",
        "Found\n",
        "0,100\n",
    ];
    assert_eq!(got, want);
}

#[test]
fn the_signal_level_is_the_speckle_at_the_beam() {
    let device = common::device(UnitSpec::lab_default(), FaultSchedule::none(), Arc::new(VirtualClock::new()));
    let mut device = device.lock().unwrap();
    let expected = (device.controller().speckle_level() * 100.0).round();
    device.receive(b"Get,SignalLevel,0,Value\n");
    let level: f64 = String::from_utf8(device.take_output()).unwrap().trim().parse().unwrap();
    assert_eq!(level, expected);
    assert!(level > 0.0, "the scene's mean level is 0.7");
}

//! Instrument faults through the real backends: the Polytec controller and Zaber stages on pseudo-terminals the
//! mock controller and the mock stages answer on (the real serial transport), NI-DAQmx through the stand-in library
//! (run-time loading, NI's status codes). Each is named, by the hardware file's section, in the one error that
//! opening the rig gives (what `metaplate check --hardware` turns into failed checks).

use std::path::Path;

use metaplate_drivers::{HardwareFile, OpenPurpose, open_rig};

const EXAMPLE: &str = include_str!("../../../crates/cli/hardware.example.toml");

/// The example with its `[daq]` replaced by `daq` (a whole section, header and keys).
fn with_daq(daq: &str) -> HardwareFile {
    let start = EXAMPLE.find("[daq]").unwrap();
    let end = start + EXAMPLE[start..].find("\n[audio]").unwrap();
    let text = format!("{}{daq}\n{}", &EXAMPLE[..start], &EXAMPLE[end..]);
    HardwareFile::parse(&text, Path::new("/lab/rig.toml")).unwrap()
}

/// A DAQmx call that fails when the DAQ opens is named with NI's status code and text: here a device the system
/// does not have (-200220).
#[cfg(all(feature = "nidaqmx", feature = "serial", feature = "alsa", target_os = "linux"))]
#[test]
fn a_daqmx_call_that_fails_is_named_with_nis_code() {
    let library = metaplate_fixtures::nidaqmx_stand_in();
    let ni = |device: &str| {
        format!("[daq]\nbackend = \"nidaqmx\"\ndevice = \"{device}\"\nlibrary = \"{}\"\n", library.display())
    };
    let error = open_rig(&with_daq(&ni("Dev9")), OpenPurpose::Check).err().unwrap();
    let daq: Vec<String> =
        error.failed_instruments().into_iter().filter(|(s, _)| *s == "daq").map(|(_, m)| m).collect();
    assert_eq!(daq.len(), 1, "{error}");
    assert!(daq[0].contains("Dev9") && daq[0].contains("-200220"), "{}", daq[0]);
    // Dev7 exists: the DAQ opens, and only the example's absent instruments are named.
    let error = open_rig(&with_daq(&ni("Dev7")), OpenPurpose::Check).err().unwrap();
    let sections: Vec<&str> = error.failed_instruments().iter().map(|(s, _)| *s).collect();
    assert_eq!(sections, ["ldv", "audio"], "{error}");
}

/// The example with its LDV on `ldv_port` asking for `decoder`, and Zaber stages on `zaber_port`.
#[cfg(all(feature = "serial", feature = "zaber", feature = "labjack-u6", feature = "alsa", target_os = "linux"))]
fn rig_file(ldv_port: &Path, decoder: &str, zaber_port: &Path) -> HardwareFile {
    let start = EXAMPLE.find("port = ").unwrap();
    let end = start + EXAMPLE[start..].find('\n').unwrap();
    let ldv = format!("port = \"{}\"\ndecoder = \"{decoder}\"", ldv_port.display());
    let aim = format!(
        "\n[aim]\nbackend = \"zaber\"\nport = \"{}\"\nmoves = \"head\"\n\n[aim.x]\ndevice = 1\nmicrostep_um = \
         0.047625\norigin_mm = 50.0\n\n[aim.y]\ndevice = 2\nmicrostep_um = 0.047625\norigin_mm = 50.0\n",
        zaber_port.display()
    );
    let text = format!("{}{ldv}{}{aim}", &EXAMPLE[..start], &EXAMPLE[end..]);
    HardwareFile::parse(&text, Path::new("/lab/rig.toml")).unwrap()
}

#[cfg(all(feature = "serial", feature = "zaber", feature = "labjack-u6", feature = "alsa", target_os = "linux"))]
#[test]
fn a_decoder_the_unit_lacks_and_an_axis_that_will_not_home_are_named() {
    use std::sync::{Arc, Mutex};

    use metaplate_core::clock::{RealClock, VirtualClock};
    use metaplate_mock_ldv::{FaultSchedule, MockController, MockDevice, PtyServer, UnitSpec, quiet_spec};
    use metaplate_mock_zaber::{ArmedFault, ChainSpec, MockChain};
    use metaplate_zaber_protocol::WarningFlag;

    // The lab's unit carries a VD-02 only (`UnitSpec::lab_default`).
    let controller = MockController::new(UnitSpec::lab_default(), &quiet_spec(), 11);
    let clock = Arc::new(VirtualClock::new());
    let device = Arc::new(Mutex::new(MockDevice::new(controller, FaultSchedule::none()).with_clock(clock)));
    let ldv = PtyServer::spawn(device).unwrap();
    // Two 100 mm stages at 200 mm/s; the y axis stalls on its way home.
    let chain = Arc::new(Mutex::new(MockChain::new(ChainSpec::xy_lsm100(200.0), Arc::new(RealClock::new()))));
    let stall = ArmedFault { flag: WarningFlag::parse("FS").unwrap_or(WarningFlag::NONE), fraction: 0.3 };
    assert!(chain.lock().unwrap().arm_fault(2, 1, stall));
    let stages = PtyServer::spawn(chain).unwrap();

    let error = open_rig(&rig_file(ldv.path(), "VD-09", stages.path()), OpenPurpose::Check).err().unwrap();
    let failed = error.failed_instruments();
    let message = |section: &str| {
        failed.iter().find(|(s, _)| *s == section).map(|(_, m)| m.clone()).unwrap_or_else(|| panic!("{error}"))
    };
    let ldv_message = message("ldv");
    assert!(ldv_message.contains("VD-09") && ldv_message.contains("VD-02"), "{ldv_message}");
    let aim_message = message("aim");
    assert!(aim_message.contains("zaber") && aim_message.contains("FS (stalled and stopped)"), "{aim_message}");
    // The example's U6 and sound card are not on this machine: named too, in the file's order.
    let sections: Vec<&str> = failed.iter().map(|(s, _)| *s).collect();
    assert_eq!(sections, ["ldv", "daq", "audio", "aim"], "{error}");
}

//! Faults of the serial instruments, opened through the real serial transport on pseudo-terminals the mock
//! controller and the mock stages answer on: each is named, by the hardware file's section, in the one error that
//! opening the rig gives (what `metaplate check --hardware` turns into failed checks).

#![cfg(all(unix, feature = "serial", feature = "zaber"))]

use std::path::Path;
use std::sync::{Arc, Mutex};

use metaplate_core::clock::{RealClock, VirtualClock};
use metaplate_drivers::{HardwareFile, open_rig};
use metaplate_mock_ldv::{FaultSchedule, MockController, MockDevice, PtyServer, UnitSpec, quiet_spec};
use metaplate_mock_zaber::{ArmedFault, ChainSpec, MockChain};
use metaplate_zaber_protocol::WarningFlag;

const EXAMPLE: &str = include_str!("../../../crates/cli/hardware.example.toml");

/// The example with its LDV on `ldv_port` asking for `decoder`, and Zaber stages on `zaber_port`.
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

#[test]
fn a_decoder_the_unit_lacks_and_an_axis_that_will_not_home_are_named() {
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

    let error = open_rig(&rig_file(ldv.path(), "VD-09", stages.path())).err().unwrap();
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

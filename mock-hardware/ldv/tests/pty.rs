//! The real serial transport (`SerialPortLine`, serialport without libudev) against the mock controller on a
//! pseudo-terminal. Timeouts are real here, so the driver's are scaled down to 0.2 x its default (50 ms) and
//! every test bounds its wall time.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![cfg(unix)] // pseudo-terminals
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use metaplate_core::clock::VirtualClock;
use metaplate_core::vibrometer::{Tracking, Vibrometer};
use metaplate_ldv::{LineError, PolytecConfig, PolytecDriver, PortSelector, RetryPolicy, SerialLine, SerialPortLine};
use metaplate_mock_ldv::{Fault, FaultSchedule, MockDevice, PtyServer, UnitSpec};

use crate::common;

fn serve(faults: FaultSchedule) -> (PtyServer, Arc<Mutex<MockDevice>>) {
    let device = common::device(UnitSpec::lab_default(), faults, Arc::new(VirtualClock::new()));
    (PtyServer::spawn(device.clone()).unwrap(), device)
}

fn open_driver(server: &PtyServer) -> PolytecDriver<SerialPortLine> {
    let line = SerialPortLine::open(PortSelector::Path(server.path().to_path_buf())).unwrap();
    let policy = RetryPolicy { timeout_scale: 0.2, ..RetryPolicy::default() };
    PolytecDriver::new(line, policy, PolytecConfig::default()).unwrap()
}

#[test]
fn a_session_over_the_pty_is_byte_exact() {
    let wall = Instant::now();
    let (server, device) = serve(FaultSchedule::none());
    let mut ldv = open_driver(&server);
    ldv.set_velocity_range(0.05).unwrap();
    ldv.set_tracking(Tracking::Fast).unwrap();
    let level = ldv.signal_level().unwrap();
    assert!((0.0..=1.0).contains(&level));
    assert_eq!(ldv.identify().unwrap().vendor, "Polytec");
    let log = common::host_log(&device);
    let connect = "Set,Interface,0,Echo,Off\nSet,Controller,0,Remote,On\nGet,Controller,0,Remote\n\
                   GetDevInfo,VeloDec,0,Name\nGetDevInfo,VeloDec,0,Range\nGetDevInfo,SignalLevel,0,Value\n";
    assert!(log.starts_with(connect), "{log}");
    assert_eq!(device.lock().unwrap().controller().velocity_range(0).unwrap().text(), "5mm/s/V");
    // Reopening the real port (closed first: it is opened exclusively) connects again and re-applies the settings.
    ldv.reconnect().unwrap();
    assert!(common::host_log(&device).ends_with("Set,VeloDec,0,TrackingFilter,Fast\nGet,VeloDec,0,TrackingFilter\n"));
    // A dozen exchanges and a reopen over a pty: milliseconds; 5 s allows for a loaded 2-core machine.
    assert!(wall.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn real_timeouts_and_garbage_over_the_pty_are_recovered() {
    let wall = Instant::now();
    // Lines 0-5 connect; 6 the level query (lost: a real 50 ms timeout), 7 again (garbled), 8 answered.
    let faults = FaultSchedule::scripted(5, [(6, Fault::NoReply), (7, Fault::GarbledReply)]);
    let (server, _device) = serve(faults);
    let mut ldv = open_driver(&server);
    let level = ldv.signal_level();
    assert!(matches!(level, Ok(l) if l > 0.0), "{level:?}");
    assert!(wall.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn the_serial_transport_times_out_in_about_the_time_asked() {
    let (server, _device) = serve(FaultSchedule::none());
    let mut line = SerialPortLine::open(PortSelector::Path(server.path().to_path_buf())).unwrap();
    let mut buf = [0u8; 16];
    for timeout_s in [0.0, 0.05] {
        let t0 = Instant::now();
        assert_eq!(line.read(&mut buf, timeout_s), Err(LineError::Timeout));
        let waited = t0.elapsed().as_secs_f64();
        // Never early; late by at most scheduling noise (1 s is generous).
        assert!(waited >= timeout_s && waited < timeout_s + 1.0, "asked {timeout_s} s, waited {waited} s");
    }
    // Bad timeouts wait nothing rather than forever.
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        let t0 = Instant::now();
        assert_eq!(line.read(&mut buf, bad), Err(LineError::Timeout));
        assert!(t0.elapsed().as_secs_f64() < 1.0, "timeout {bad}");
    }
}

#[test]
fn a_missing_port_is_a_disconnect() {
    let missing = PortSelector::Path(PathBuf::from("/dev/metaplate-no-such-port"));
    assert!(matches!(SerialPortLine::open(missing), Err(LineError::Disconnected { .. })));
    let unknown = PortSelector::UsbSerial("metaplate-no-such-serial".into());
    assert!(matches!(SerialPortLine::open(unknown), Err(LineError::Disconnected { .. })));
}

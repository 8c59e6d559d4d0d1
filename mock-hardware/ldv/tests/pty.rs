//! The real serial transport (`SerialPortLine`, serialport without libudev) against the mock controller on a
//! pseudo-terminal. Timeouts are real here, so the driver's are scaled down to 0.2 x the specification's (50 ms)
//! and every test bounds its wall time.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![cfg(unix)] // pseudo-terminals
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use metaplate_core::clock::VirtualClock;
use metaplate_core::scene::LdvSpec;
use metaplate_core::vibrometer::{Tracking, Vibrometer};
use metaplate_ldv::{LdvDriver, LineError, PortSelector, RetryPolicy, SerialLine, SerialPortLine};
use metaplate_ldv_protocol::{LaserState, PlatePoint, VelocityRange};
use metaplate_mock_ldv::{Fault, FaultSchedule, MockController, MockDevice, PtyServer};

fn serve(faults: FaultSchedule) -> (PtyServer, Arc<Mutex<MockDevice>>) {
    let spec = LdvSpec {
        noise_rms_m_s: 1e-6,
        speckle_mean_level: 0.7,
        speckle_spread: 0.2,
        dropout_probability: 0.0,
        max_velocity_m_s: 0.25,
        aim_error_rms_m: 0.0,
    };
    let controller = MockController::new(&spec, 3, "SN04512").unwrap();
    let device = Arc::new(Mutex::new(MockDevice::new(controller, faults)));
    (PtyServer::spawn(device.clone()).unwrap(), device)
}

fn open_driver(server: &PtyServer) -> LdvDriver<SerialPortLine> {
    let line = SerialPortLine::open(PortSelector::Path(server.path().to_path_buf())).unwrap();
    let policy = RetryPolicy { timeout_scale: 0.2, ..RetryPolicy::default() };
    LdvDriver::new(line, Arc::new(VirtualClock::new()), policy).unwrap()
}

#[test]
fn a_session_over_the_pty_is_byte_exact() {
    let wall = Instant::now();
    let (server, device) = serve(FaultSchedule::none());
    let mut ldv = open_driver(&server);
    assert_eq!(ldv.identify().unwrap().serial, "SN04512");
    ldv.set_laser(true).unwrap();
    ldv.set_velocity_range(0.05).unwrap();
    ldv.set_tracking(Tracking::Fast).unwrap();
    ldv.move_to(0.012, -0.0355).unwrap();
    let level = ldv.signal_level().unwrap();
    assert!((0.0..=1.0).contains(&level));
    {
        let device = device.lock().unwrap();
        assert_eq!(
            String::from_utf8_lossy(device.host_log()),
            "SYNC 1\r*IDN?\rLASER ON\rVRANGE 5\rTRACK FAST\rPOS 12.000 -35.500\rSIG?\r"
        );
        assert_eq!(device.controller().laser(), LaserState::On);
        assert_eq!(device.controller().velocity_range(), VelocityRange::MmPerS5);
        assert_eq!(device.controller().position(), PlatePoint::from_m(0.012, -0.0355).unwrap());
    }
    // Reopening the real port (closed first: it is opened exclusively) and re-applying the settings.
    ldv.reconnect().unwrap();
    assert!(
        String::from_utf8_lossy(device.lock().unwrap().host_log())
            .ends_with("SIG?\rSYNC 2\rVRANGE 5\rTRACK FAST\rLASER ON\rPOS 12.000 -35.500\r")
    );
    // Seven exchanges and a reopen over a pty: milliseconds; 5 s allows for a loaded 2-core machine.
    assert!(wall.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn real_timeouts_and_garbage_over_the_pty_are_recovered() {
    let wall = Instant::now();
    // 0 SYNC 1, 1 SIG? (no reply: a real 50 ms timeout), 2 SYNC 2, 3 SIG? (garbled), 4 SYNC 3, 5 SIG?.
    let faults = FaultSchedule::scripted(5, [(1, Fault::NoReply), (3, Fault::GarbledReply)]);
    let (server, device) = serve(faults);
    let mut ldv = open_driver(&server);
    // The laser is off at power-on: SIG? is a typed device error once the line works again.
    let err = ldv.signal_level().unwrap_err();
    assert!(matches!(err, metaplate_core::vibrometer::VibrometerError::Device { code: 6, .. }), "{err}");
    assert_eq!(
        String::from_utf8_lossy(device.lock().unwrap().host_log()),
        "SYNC 1\rSIG?\rSYNC 2\rSIG?\rSYNC 3\rSIG?\r"
    );
    // One 50 ms timeout, the rest milliseconds; 5 s allows for a loaded machine.
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

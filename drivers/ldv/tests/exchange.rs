//! Byte-exact exchanges, PyMeasure style: each `Vibrometer` call against a script of (bytes the driver must
//! write, bytes the controller answers). A write that differs from the script fails the test at once.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![allow(clippy::unwrap_used)]

use std::collections::VecDeque;
use std::sync::Arc;

use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::vibrometer::{Tracking, Vibrometer, VibrometerError};
use metaplate_ldv::{LdvDriver, LineError, RetryPolicy, SerialLine};

/// A line that plays a script: every write must equal the next expected line, which queues its reply.
struct ScriptedLine {
    script: VecDeque<(&'static [u8], &'static [u8])>,
    pending: Vec<u8>,
}

impl ScriptedLine {
    fn new(script: &[(&'static str, &'static str)]) -> Self {
        let script = script.iter().map(|(w, r)| (w.as_bytes(), r.as_bytes())).collect();
        Self { script, pending: Vec::new() }
    }
}

impl SerialLine for ScriptedLine {
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), LineError> {
        let (expected, reply) = self.script.pop_front().unwrap_or_else(|| {
            panic!("unscripted write {:?}", String::from_utf8_lossy(bytes));
        });
        assert_eq!(String::from_utf8_lossy(bytes), String::from_utf8_lossy(expected));
        self.pending.extend_from_slice(reply);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], _timeout_s: f64) -> Result<usize, LineError> {
        if self.pending.is_empty() {
            return Err(LineError::Timeout);
        }
        let n = self.pending.len().min(buf.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }

    fn reopen(&mut self) -> Result<(), LineError> {
        Ok(())
    }
}

fn driver(script: &[(&'static str, &'static str)]) -> (LdvDriver<ScriptedLine>, Arc<VirtualClock>) {
    let clock = Arc::new(VirtualClock::new());
    let driver = LdvDriver::new(ScriptedLine::new(script), clock.clone(), RetryPolicy::default()).unwrap();
    (driver, clock)
}

fn assert_script_done(driver: &LdvDriver<ScriptedLine>) {
    let left: Vec<_> = driver.line().script.iter().map(|(w, _)| String::from_utf8_lossy(w)).collect();
    assert!(left.is_empty(), "script not played to the end: {left:?}");
}

#[test]
fn every_call_writes_its_documented_bytes() {
    let (mut ldv, clock) = driver(&[
        // The first command of a session is preceded by a resynchronisation.
        ("SYNC 1\r", "SYNC 1\r\n"),
        ("*IDN?\r", "IDN Ometron,8330,SN04512,2.14\r\n"),
        ("LASER ON\r", "OK\r\n"),
        ("VRANGE 5\r", "OK\r\n"),
        ("TRACK MEDIUM\r", "OK\r\n"),
        ("POS 12.000 -35.500\r", "OK\r\n"),
        // The decoder accepts a bare LF as well as CR LF.
        ("SIG?\r", "SIG 87\n"),
        ("POS -500.000 500.000\r", "OK\r\n"),
        ("VRANGE 1\r", "OK\r\n"),
        ("VRANGE 1000\r", "OK\r\n"),
        ("TRACK OFF\r", "OK\r\n"),
        ("LASER OFF\r", "OK\r\n"),
    ]);
    let id = ldv.identify().unwrap();
    assert_eq!(
        (id.vendor.as_str(), id.model.as_str(), id.serial.as_str(), id.firmware.as_str()),
        ("Ometron", "8330", "SN04512", "2.14")
    );
    ldv.set_laser(true).unwrap();
    let scale = ldv.set_velocity_range(0.03).unwrap();
    // Exact: 5 mm/s/V is 5e-3 (m/s)/V by one multiplication in both the driver and here.
    assert_eq!((scale.m_s_per_v, scale.full_scale_m_s), (5.0 * 1e-3, 5.0 * 1e-3 * 10.0));
    ldv.set_tracking(Tracking::Medium).unwrap();
    ldv.move_to(0.012, -0.0355).unwrap();
    // Exact: 87 / 100 in both places.
    assert_eq!(ldv.signal_level().unwrap(), 87.0 / 100.0);
    // The field's corners and the range ladder's ends.
    ldv.move_to(-0.5, 0.5).unwrap();
    ldv.set_velocity_range(1e-9).unwrap();
    ldv.set_velocity_range(10.0).unwrap();
    ldv.set_tracking(Tracking::Off).unwrap();
    ldv.set_laser(false).unwrap();
    assert_script_done(&ldv);
    // Nothing in this session had to wait.
    assert_eq!(clock.now_s(), 0.0);
}

#[test]
fn device_errors_are_typed_and_bad_arguments_send_nothing() {
    let (mut ldv, _) = driver(&[
        ("SYNC 1\r", "SYNC 1\r\n"),
        ("SIG?\r", "ERR 6 laser is off\r\n"),
        ("POS 0.000 0.000\r", "ERR 5 no plate calibration in force\r\n"),
    ]);
    let err = ldv.signal_level().unwrap_err();
    assert!(matches!(&err, VibrometerError::Device { code: 6, message } if message.contains("laser is off")), "{err}");
    let err = ldv.move_to(0.0, 0.0).unwrap_err();
    assert!(matches!(err, VibrometerError::Device { code: 5, .. }), "{err}");
    // Nothing of these reaches the line (the script has no line left for them).
    for (x, y) in [(f64::NAN, 0.0), (0.0, f64::INFINITY), (0.500_001, 0.0), (0.0, -0.6)] {
        assert!(matches!(ldv.move_to(x, y), Err(VibrometerError::InvalidArgument { .. })), "({x}, {y})");
    }
    for v in [0.0, -0.1, 10.1, f64::NAN] {
        assert!(matches!(ldv.set_velocity_range(v), Err(VibrometerError::InvalidArgument { .. })), "{v} m/s");
    }
    // A failed move is not a setting to re-apply.
    assert_eq!(ldv.settings().position, None);
    assert_script_done(&ldv);
}

#[test]
fn busy_is_waited_out_on_the_clock_then_reported() {
    let (mut ldv, clock) = driver(&[
        ("SYNC 1\r", "SYNC 1\r\n"),
        ("VRANGE 25\r", "ERR 7 front panel\r\n"),
        ("VRANGE 25\r", "ERR 7 front panel\r\n"),
        ("VRANGE 25\r", "OK\r\n"),
    ]);
    ldv.set_velocity_range(0.25).unwrap();
    // Two busy waits of the specification's 100 ms, in virtual time; 1e-12 covers the two additions' rounding.
    assert!((clock.now_s() - 0.2).abs() < 1e-12, "waited {} s", clock.now_s());
    assert_script_done(&ldv);

    // With no busy retries left, busy is the device's error.
    let policy = RetryPolicy { busy_retries: 0, ..RetryPolicy::default() };
    let line = ScriptedLine::new(&[("SYNC 1\r", "SYNC 1\r\n"), ("LASER OFF\r", "ERR 7 self-test\r\n")]);
    let mut ldv = LdvDriver::new(line, Arc::new(VirtualClock::new()), policy).unwrap();
    assert!(matches!(ldv.set_laser(false), Err(VibrometerError::Device { code: 7, .. })));
}

#[test]
fn a_stale_reply_is_drained_with_sync_before_the_retry() {
    let (mut ldv, _) = driver(&[
        ("SYNC 1\r", "SYNC 1\r\n"),
        // A late OK (answer to some earlier move) arrives where SIG? expects SIG: stale.
        ("SIG?\r", "OK\r\n"),
        // The resynchronisation discards everything before its echo: another stale line and garbage.
        ("SYNC 2\r", "SIG 12\r\n\x01\x02junk\r\nSYNC 2\r\n"),
        ("SIG?\r", "SIG 55\r\n"),
    ]);
    assert_eq!(ldv.signal_level().unwrap(), 55.0 / 100.0);
    assert_script_done(&ldv);
}

#[test]
fn invalid_policies_are_refused() {
    let bad = RetryPolicy { attempts: 0, ..RetryPolicy::default() };
    let made = LdvDriver::new(ScriptedLine::new(&[]), Arc::new(VirtualClock::new()), bad);
    assert!(matches!(made, Err(VibrometerError::InvalidArgument { .. })));
}

//! Each fault type against the real driver over the in-process mock: the driver recovers or reports the typed
//! error. The in-process line times out at once, so a wall-time bound of a second catches any real wait.

use std::sync::Arc;
use std::time::Instant;

use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_core::vibrometer::{Tracking, Vibrometer, VibrometerError};
use metaplate_ldv::{PolytecConfig, PolytecDriver, RetryPolicy};
use metaplate_mock_ldv::{DROPOUT_LEVEL_PERCENT, Fault, FaultSchedule, MockDevice, MockLine, UnitSpec};

use crate::common;

fn rig(faults: FaultSchedule) -> (PolytecDriver<MockLine>, Arc<std::sync::Mutex<MockDevice>>, Arc<VirtualClock>) {
    let clock = Arc::new(VirtualClock::new());
    let device = common::device(UnitSpec::lab_default(), faults, clock.clone());
    let driver =
        PolytecDriver::new(MockLine::new(device.clone()), RetryPolicy::default(), PolytecConfig::default()).unwrap();
    (driver, device, clock)
}

/// Lines of connecting to the lab unit: echo, remote set and read back, decoder name and ranges, signal bounds.
const CONNECT_LINES: u64 = 6;

fn clean_level() -> f64 {
    rig(FaultSchedule::none()).0.signal_level().unwrap()
}

#[test]
fn silence_is_retried_then_a_typed_timeout() {
    let wall = Instant::now();
    let first = CONNECT_LINES;
    let (mut ldv, device, _) = rig(FaultSchedule::scripted(1, (first..first + 3).map(|l| (l, Fault::NoReply))));
    let err = ldv.signal_level().unwrap_err();
    assert!(
        matches!(&err, VibrometerError::Timeout { command, detail } if command == "Get,SignalLevel,0,Value" && detail.contains("3 attempts")),
        "{err}"
    );
    assert!(err.suggests_reconnect());
    assert!(common::host_log(&device).ends_with("Get,SignalLevel,0,Value\n".repeat(3).as_str()));
    assert!(wall.elapsed().as_secs_f64() < 1.0);
}

#[test]
fn garbled_late_and_partial_replies_are_retried_to_the_clean_answer() {
    let expected = clean_level();
    for seed in 0..10 {
        for fault in [Fault::GarbledReply, Fault::PartialReply, Fault::LateReply] {
            let (mut ldv, _, _) = rig(FaultSchedule::scripted(seed, [(CONNECT_LINES, fault)]));
            assert_eq!(ldv.signal_level().unwrap(), expected, "{fault:?} seed {seed}");
            // The next request gets its own answer, not a stale one.
            assert_eq!(ldv.set_velocity_range(1.0).unwrap().m_s_per_v, 0.125, "{fault:?} seed {seed}");
        }
    }
}

#[test]
fn a_lost_set_is_caught_by_its_read_back_and_sent_again() {
    // Line 6 is the Set of the range: lost; its Get reads the power-on 25 mm/s/V, so the Set goes again.
    let (mut ldv, device, _) = rig(FaultSchedule::scripted(1, [(CONNECT_LINES, Fault::NoReply)]));
    assert_eq!(ldv.set_velocity_range(0.05).unwrap().m_s_per_v, 0.005);
    assert_eq!(device.lock().unwrap().controller().velocity_range(0).unwrap().text(), "5mm/s/V");
    assert_eq!(common::host_log(&device).matches("Set,VeloDec,0,Range,5mm/s/V\n").count(), 2);
}

#[test]
fn a_power_cycle_is_recovered_by_reconnect_with_the_settings_reapplied() {
    let after = CONNECT_LINES + 5; // range (2 lines) and tracking (3 lines) set, then the level query drops
    let (mut ldv, device, _) = rig(FaultSchedule::scripted(1, [(after, Fault::Disconnect { power_cycle: true })]));
    ldv.set_velocity_range(1.0).unwrap();
    ldv.set_tracking(Tracking::Slow).unwrap();
    let err = ldv.signal_level().unwrap_err();
    assert!(matches!(err, VibrometerError::Disconnected { .. }), "{err}");
    assert_eq!(device.lock().unwrap().controller().remote(), "Local");
    ldv.reconnect().unwrap();
    let device = device.lock().unwrap();
    let controller = device.controller();
    assert_eq!((controller.remote(), controller.tracking(0)), ("On", Some("Slow")));
    assert_eq!(controller.velocity_range(0).unwrap().text(), "125mm/s/V");
}

#[test]
fn a_dropout_reads_low_until_the_beam_moves() {
    let (mut ldv, device, _) = rig(FaultSchedule::scripted(1, [(CONNECT_LINES, Fault::Dropout { queries: 2 })]));
    let low = f64::from(DROPOUT_LEVEL_PERCENT) / 100.0;
    // The faulty line itself is answered normally; the next two queries read low.
    assert!(ldv.signal_level().unwrap() > low);
    assert_eq!(ldv.signal_level().unwrap(), low);
    assert_eq!(ldv.signal_level().unwrap(), low);
    assert!(ldv.signal_level().unwrap() > low);
    device.lock().unwrap().controller_mut().start_dropout(5);
    device.lock().unwrap().controller_mut().set_beam(0.01, 0.01);
    assert!(ldv.signal_level().unwrap() > low, "a new spot is tracked afresh");
}

#[test]
fn random_faults_never_hang_and_only_typed_errors_escape() {
    let kinds = [Fault::NoReply, Fault::GarbledReply, Fault::PartialReply, Fault::LateReply];
    let wall = Instant::now();
    for seed in 0..20 {
        let (mut ldv, _, clock) = rig(FaultSchedule::random(seed, 0.2, 500, &kinds));
        for _ in 0..20 {
            match ldv.signal_level() {
                Ok(level) => assert!((0.0..=1.0).contains(&level)),
                Err(e) => assert!(matches!(e, VibrometerError::Timeout { .. } | VibrometerError::Device { .. }), "{e}"),
            }
        }
        assert!(clock.now_s() < 60.0);
    }
    assert!(wall.elapsed().as_secs_f64() < 2.0);
}

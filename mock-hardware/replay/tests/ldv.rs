//! An LDV session recorded against the mock Polytec controller, replayed through a fresh `PolytecDriver` over
//! `ReplayLine`:
//! clean, with faults the driver absorbs, with faults it reports, and with a driver that deviates. Every test is
//! bounded: replay and the in-process mock answer at once (a read never waits), and the driver's loops are
//! bounded by its retry policy.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![allow(clippy::unwrap_used)]

use std::sync::{Arc, Mutex};

use metaplate_cassette::{Body, Cassette, DeviceIdentity, DeviceKind, Header};
use metaplate_core::clock::VirtualClock;
use metaplate_core::vibrometer::{Tracking, Vibrometer, VibrometerError};
use metaplate_ldv::{PolytecConfig, PolytecDriver, RetryPolicy};
use metaplate_mock_ldv::{FaultSchedule, MockController, MockDevice, MockLine, UnitSpec};
use metaplate_polytec_protocol::{Device, Request};
use metaplate_replay::{
    Deviation, FaultKind, Recorder, RecordingLine, ReplayError, ReplayFaults, ReplayLine, ReplayTransport, load_bytes,
};

/// The session: every kind of call, its results as text (values and errors alike).
fn session(ldv: &mut impl Vibrometer) -> Vec<String> {
    vec![
        format!("{:?}", ldv.identify()),
        format!("{:?}", ldv.set_velocity_range(0.1)),
        format!("{:?}", ldv.set_tracking(Tracking::Fast)),
        format!("{:?}", ldv.signal_level()),
        format!("{:?}", ldv.set_velocity_range(1.0)),
        format!("{:?}", ldv.signal_level()),
        // A range beyond the decoder's largest full scale (10 m/s) is refused before anything is sent: a typed
        // error that must replay too.
        format!("{:?}", ldv.set_velocity_range(100.0)),
        format!("{:?}", ldv.signal_level()),
    ]
}

/// Records [`session`] against the mock controller: the cassette's bytes and the results.
fn record() -> (Vec<u8>, Vec<String>) {
    let mut controller = MockController::new(UnitSpec::lab_default(), &metaplate_mock_ldv::quiet_spec(), 5);
    controller.set_beam(0.012, -0.034);
    let clock = Arc::new(VirtualClock::new());
    let device = Arc::new(Mutex::new(MockDevice::new(controller, FaultSchedule::none()).with_clock(clock.clone())));
    let header = Header { device_kind: DeviceKind::LdvSerial, identity: DeviceIdentity::default(), start_unix_ns: 0 };
    let recorder = Recorder::start(Vec::new(), &header, clock.clone()).unwrap();
    let line = RecordingLine::new(MockLine::new(device), recorder.clone());
    let mut ldv = PolytecDriver::new(line, RetryPolicy::default(), PolytecConfig::default()).unwrap();
    let results = session(&mut ldv);
    recorder.finish().unwrap();
    (recorder.with_writer(|w| w.clone()).unwrap(), results)
}

fn cassette() -> (Cassette, Vec<String>) {
    let (bytes, results) = record();
    (Cassette::from_bytes(&bytes).unwrap(), results)
}

fn replay_driver(cassette: &Cassette, faults: ReplayFaults) -> PolytecDriver<ReplayLine> {
    PolytecDriver::new(ReplayLine::new(cassette, faults).unwrap(), RetryPolicy::default(), PolytecConfig::default())
        .unwrap()
}

fn signal_query() -> Request {
    Request::get(Device::SignalLevel, 0, "Value").unwrap()
}

/// Index of the first device-to-host record after the host first wrote `request`'s bytes.
fn reply_record(cassette: &Cassette, request: &Request) -> usize {
    let sent = request.encode();
    let write = cassette.records.iter().position(|r| r.body == Body::HostToDevice(sent.clone())).unwrap();
    write + 1 + cassette.records[write + 1..].iter().position(|r| matches!(r.body, Body::DeviceToHost(_))).unwrap()
}

fn read_records(cassette: &Cassette) -> Vec<usize> {
    (0..cassette.records.len()).filter(|&i| matches!(cassette.records[i].body, Body::DeviceToHost(_))).collect()
}

#[test]
fn recording_timestamps_follow_the_mock_clock() {
    let (cassette, results) = cassette();
    // The session itself ran fine, but for the range beyond the decoder's: a typed refusal.
    assert!(results.iter().enumerate().all(|(i, r)| r.starts_with("Ok") == (i != 6)), "{results:?}");
    assert!(results[6].contains("InvalidArgument"), "{}", results[6]);
    let times: Vec<u64> = cassette.records.iter().map(|r| r.t_ns).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    // The mock advances its virtual clock by each request's response time, so the session spans a positive time.
    assert!(*times.last().unwrap() > 0, "{times:?}");
}

#[test]
fn clean_replay_gives_the_same_results_call_for_call() {
    let (cassette, recorded) = cassette();
    let mut ldv = replay_driver(&cassette, ReplayFaults::none());
    assert_eq!(session(&mut ldv), recorded);
    let line = ldv.line();
    assert!(line.mismatch().is_none());
    assert!(line.is_finished());
    let stats = line.stats();
    assert_eq!(stats.played, stats.steps, "every recorded call played once");
    assert_eq!((stats.retries_replayed, stats.synthesized, stats.quiet_reads), (0, 0, 0));
}

#[test]
fn an_injected_timeout_is_absorbed_by_a_resend() {
    let (cassette, recorded) = cassette();
    let k = reply_record(&cassette, &signal_query());
    let mut ldv = replay_driver(&cassette, ReplayFaults::none().with(k, FaultKind::Timeout));
    assert_eq!(session(&mut ldv), recorded);
    let stats = ldv.line().stats();
    assert_eq!(stats.faults_applied, vec![(k, FaultKind::Timeout)]);
    // One resend answered from the recording; nothing made up (the syntax has no resynchronisation command).
    assert_eq!((stats.retries_replayed, stats.synthesized), (1, 0));
    assert!(ldv.line().mismatch().is_none() && ldv.line().is_finished());
}

#[test]
fn a_garbled_reply_is_absorbed() {
    let (cassette, recorded) = cassette();
    let k = reply_record(&cassette, &Request::dev_info(Device::Controller, 0, "Name").unwrap());
    let mut ldv = replay_driver(&cassette, ReplayFaults::none().with(k, FaultKind::Garble));
    assert_eq!(session(&mut ldv), recorded);
    assert_eq!(ldv.line().stats().retries_replayed, 1);
    assert!(ldv.line().mismatch().is_none());
}

#[test]
fn every_read_faulted_in_turn_gives_the_same_results() {
    // The strongest form: each recorded read, hit by each absorbable fault kind, one at a time.
    let (cassette, recorded) = cassette();
    for k in read_records(&cassette) {
        for kind in [FaultKind::Timeout, FaultKind::Stall, FaultKind::Garble, FaultKind::Truncate, FaultKind::Drop] {
            let mut ldv = replay_driver(&cassette, ReplayFaults::none().with(k, kind));
            assert_eq!(session(&mut ldv), recorded, "{kind:?} at record {k}");
            let line = ldv.line();
            assert!(line.mismatch().is_none(), "{kind:?} at record {k}: {:?}", line.mismatch());
            assert_eq!(line.stats().faults_applied, vec![(k, kind)]);
        }
    }
}

#[test]
fn an_injected_disconnect_is_the_drivers_typed_error() {
    let (cassette, _) = cassette();
    let k = reply_record(&cassette, &signal_query());
    let mut ldv = replay_driver(&cassette, ReplayFaults::none().with(k, FaultKind::Disconnect));
    let results = session(&mut ldv);
    // Calls before the faulted one are unaffected; it and every later one that reaches the line report the lost
    // line (the refused range never reaches it).
    assert!(results[..3].iter().all(|r| r.starts_with("Ok")), "{results:?}");
    assert!(results[3..].iter().enumerate().all(|(i, r)| r.contains("Disconnected") || i + 3 == 6), "{results:?}");
    assert!(ldv.line().mismatch().is_none());
}

#[test]
fn after_an_injected_disconnect_reconnect_and_retry_recover_the_session() {
    let (cassette, recorded) = cassette();
    let k = reply_record(&cassette, &signal_query());
    let mut ldv = replay_driver(&cassette, ReplayFaults::none().with(k, FaultKind::Disconnect));
    let mut results = session_until_signal(&mut ldv);
    assert!(results.last().unwrap().contains("Disconnected"), "{results:?}");
    // Reconnect connects again and re-applies range and tracking: requests the recording made earlier, answered
    // with their recorded replies; then the failed call is retried and the session goes on as recorded.
    ldv.reconnect().unwrap();
    results.pop();
    results.extend(session_after_signal(&mut ldv));
    assert_eq!(results, recorded);
    assert!(ldv.line().mismatch().is_none() && ldv.line().is_finished());
}

fn session_until_signal(ldv: &mut impl Vibrometer) -> Vec<String> {
    let mut results = session(&mut Prefix { inner: ldv, calls_left: 4 });
    results.truncate(4);
    results
}

fn session_after_signal(ldv: &mut impl Vibrometer) -> Vec<String> {
    vec![
        format!("{:?}", ldv.signal_level()),
        format!("{:?}", ldv.set_velocity_range(1.0)),
        format!("{:?}", ldv.signal_level()),
        format!("{:?}", ldv.set_velocity_range(100.0)),
        format!("{:?}", ldv.signal_level()),
    ]
}

/// Passes the first `calls_left` calls to `inner`; later calls fail without reaching it.
struct Prefix<'a, V: Vibrometer> {
    inner: &'a mut V,
    calls_left: usize,
}

impl<V: Vibrometer> Prefix<'_, V> {
    fn gate(&mut self) -> Result<(), VibrometerError> {
        if self.calls_left == 0 {
            return Err(VibrometerError::InvalidArgument { detail: "past the prefix".into() });
        }
        self.calls_left -= 1;
        Ok(())
    }
}

impl<V: Vibrometer> Vibrometer for Prefix<'_, V> {
    fn identify(&mut self) -> Result<metaplate_core::vibrometer::VibrometerIdentity, VibrometerError> {
        self.gate()?;
        self.inner.identify()
    }
    fn signal_level(&mut self) -> Result<f64, VibrometerError> {
        self.gate()?;
        self.inner.signal_level()
    }
    fn set_velocity_range(
        &mut self,
        max_velocity_m_s: f64,
    ) -> Result<metaplate_core::vibrometer::VelocityScale, VibrometerError> {
        self.gate()?;
        self.inner.set_velocity_range(max_velocity_m_s)
    }
    fn set_tracking(&mut self, tracking: Tracking) -> Result<(), VibrometerError> {
        self.gate()?;
        self.inner.set_tracking(tracking)
    }
    fn reconnect(&mut self) -> Result<(), VibrometerError> {
        self.gate()?;
        self.inner.reconnect()
    }
}

#[test]
fn a_driver_that_deviates_gets_the_mismatch() {
    let (cassette, _) = cassette();
    let mut ldv = replay_driver(&cassette, ReplayFaults::none());
    ldv.identify().unwrap();
    // The recording set the range for 0.1 m/s (the 25 mm/s/V range, full scale 0.25 m/s); this driver asks for
    // 1 m/s.
    let err = ldv.set_velocity_range(1.0).unwrap_err();
    assert!(matches!(&err, VibrometerError::Disconnected { reason } if reason.contains("replay mismatch")), "{err}");
    let m = ldv.line().mismatch().unwrap().clone();
    assert_eq!(m.deviation, Deviation::Bytes);
    let expected = Request::set(Device::VeloDec, 0, "Range", "25mm/s/V").unwrap().encode();
    assert_eq!(m.expected, expected);
    assert_eq!(cassette.records[m.record].body, Body::HostToDevice(expected.clone()));
    let first = m.first_difference.unwrap();
    assert_ne!(m.expected.get(first), m.got.get(first));
    assert_eq!(m.expected[..first], m.got[..first]);
    // The driver stays stopped: every later call fails the same way, no panic.
    assert!(ldv.signal_level().is_err());
}

#[test]
fn a_cassette_of_another_device_is_refused() {
    let (cassette, _) = cassette();
    assert!(matches!(
        ReplayTransport::new(&cassette, ReplayFaults::none()),
        Err(ReplayError::WrongDevice { expected: DeviceKind::DaqUsb, found: DeviceKind::LdvSerial })
    ));
}

#[test]
fn truncated_or_corrupt_cassettes_are_typed_errors_never_panics() {
    let (bytes, recorded) = record();
    let wall = std::time::Instant::now();
    for cut in 0..bytes.len() {
        let prefix = &bytes[..cut];
        // Strict loading refuses every cut-short file.
        assert!(matches!(load_bytes(prefix, true), Err(ReplayError::Cassette(_))), "cut at {cut}");
        // Lenient loading keeps the records before the cut; replaying them never panics, and the driver's
        // results match the recording up to the cut (a call past it fails).
        if let Ok(loaded) = load_bytes(prefix, false) {
            assert!(!loaded.complete);
            let mut ldv = replay_driver(&loaded.cassette, ReplayFaults::none());
            let results = session(&mut ldv);
            let same = results.iter().zip(&recorded).take_while(|(a, b)| a == b).count();
            assert!(results[same..].iter().all(|r| r.starts_with("Err")), "cut at {cut}: {results:?}");
        }
    }
    // Corruption: one flipped byte at a time (every 3rd byte, to bound the time); the decoder reports it and
    // the replay of what remains never panics.
    for at in (0..bytes.len()).step_by(3) {
        let mut bad = bytes.clone();
        bad[at] ^= 0x5a;
        if let Ok(loaded) = load_bytes(&bad, false) {
            let mut ldv = replay_driver_any(&loaded.cassette);
            if let Some(ldv) = ldv.as_mut() {
                let _ = session(ldv);
            }
        } else {
            assert!(at < 64, "only a header defect refuses the whole file (byte {at})");
        }
    }
    // Bound: the whole sweep replays a few thousand short sessions; a real wait anywhere would blow this.
    assert!(wall.elapsed().as_secs_f64() < 60.0, "{:?}", wall.elapsed());
}

/// A replay driver, or `None` when corruption changed the header's device kind.
fn replay_driver_any(cassette: &Cassette) -> Option<PolytecDriver<ReplayLine>> {
    let line = ReplayLine::new(cassette, ReplayFaults::none()).ok()?;
    PolytecDriver::new(line, RetryPolicy::default(), PolytecConfig::default()).ok()
}

//! The keypad driver over a scripted fake transport and a virtual clock.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use std::sync::Arc;

use metaplate_core::clock::{Clock, VirtualClock};
use metaplate_keypad::{
    Key, KeyAction, Keypad, KeypadError, ReportError, ReportPrefix, ScriptStep, ScriptedHid, TransportError,
};

fn report(after_s: f64, bytes: [u8; 8]) -> ScriptStep {
    ScriptStep::boot_report(after_s, bytes)
}

fn keypad(script: Vec<ScriptStep>) -> (Keypad<ScriptedHid>, Arc<VirtualClock>) {
    let clock = Arc::new(VirtualClock::new());
    let clock_dyn: Arc<dyn Clock> = clock.clone();
    (Keypad::new(ScriptedHid::new(&clock, script), clock_dyn, ReportPrefix::None), clock)
}

fn key(usage: u8) -> Key {
    Key::new(usage).unwrap()
}

#[test]
fn events_carry_the_time_their_report_arrived() {
    // Times are sums of binary fractions (0.25, 0.125, 0.5): exact in f64, so compared exactly.
    let (mut pad, _clock) = keypad(vec![
        report(0.25, [0, 0, 0x1E, 0, 0, 0, 0, 0]),
        report(0.125, [0, 0, 0x1E, 0, 0, 0, 0, 0]),
        report(0.5, [0, 0, 0x1F, 0, 0, 0, 0, 0]),
    ]);
    let event = pad.next_event(1.0).unwrap().unwrap();
    assert_eq!((event.key, event.action, event.time_s), (key(0x1E), KeyAction::Down, 0.25));
    // The repeated report is skipped; both changes of the third report carry its time.
    let first = pad.next_event(1.0).unwrap().unwrap();
    let second = pad.next_event(0.0).unwrap().unwrap();
    assert_eq!((first.key, first.action, first.time_s), (key(0x1E), KeyAction::Up, 0.875));
    assert_eq!((second.key, second.action, second.time_s), (key(0x1F), KeyAction::Down, 0.875));
    assert_eq!(pad.held().collect::<Vec<_>>(), [key(0x1F)]);
}

#[test]
fn nothing_in_time_is_none_and_the_wait_is_bounded() {
    let (mut pad, clock) = keypad(vec![report(2.0, [0, 0, 0x04, 0, 0, 0, 0, 0])]);
    assert_eq!(pad.next_event(1.5).unwrap(), None);
    assert_eq!(clock.now_s(), 1.5);
    // The report that was not due yet arrives 0.5 s into the next wait.
    let event = pad.next_event(1.0).unwrap().unwrap();
    assert_eq!((event.key, event.time_s), (key(0x04), 2.0));
    assert_eq!(pad.transport().timeouts_s, [1.5, 1.0]);
}

#[test]
fn repeats_do_not_extend_the_wait() {
    // A device re-sending the same report every 0.25 s must not keep the driver past its deadline.
    let repeats = (0..10).map(|_| report(0.25, [0; 8])).collect();
    let (mut pad, clock) = keypad(repeats);
    assert_eq!(pad.next_event(1.0).unwrap(), None);
    assert_eq!(clock.now_s(), 1.0);
    // Each read asked only for what was left: 1, 0.75, 0.5, 0.25 (exact binary fractions).
    assert_eq!(pad.transport().timeouts_s, [1.0, 0.75, 0.5, 0.25]);
}

#[test]
fn roll_over_is_counted_and_skipped() {
    let (mut pad, _clock) = keypad(vec![
        report(0.0, [0, 0, 0x04, 0, 0, 0, 0, 0]),
        report(0.0, [0, 0, 1, 1, 1, 1, 1, 1]),
        report(0.0, [0, 0, 0, 0, 0, 0, 0, 0]),
    ]);
    assert_eq!(pad.next_event(1.0).unwrap().unwrap().action, KeyAction::Down);
    let event = pad.next_event(1.0).unwrap().unwrap();
    assert_eq!((event.key, event.action), (key(0x04), KeyAction::Up));
    assert_eq!(pad.roll_overs(), 1);
}

#[test]
fn bad_reports_and_bad_timeouts_are_typed_errors() {
    let (mut pad, _clock) = keypad(vec![
        ScriptStep::Report { after_s: 0.0, bytes: vec![0; 7] },
        report(0.0, [0, 0, 0x02, 0, 0, 0, 0, 0]),
        report(0.0, [0, 0, 0x05, 0, 0, 0, 0, 0]),
    ]);
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(pad.next_event(bad), Err(KeypadError::Request(_))), "{bad}");
    }
    assert_eq!(pad.next_event(1.0), Err(KeypadError::Report(ReportError::WrongLength { len: 7 })));
    assert_eq!(pad.next_event(1.0), Err(KeypadError::Report(ReportError::DeviceError { code: 2 })));
    // Nothing after them was lost.
    assert_eq!(pad.next_event(1.0).unwrap().unwrap().key, key(0x05));
}

#[test]
fn report_ids_are_stripped_and_other_reports_ignored() {
    let clock = Arc::new(VirtualClock::new());
    let script = vec![
        // Report 2 (a consumer-control report of a composite device): ignored.
        ScriptStep::Report { after_s: 0.0, bytes: vec![2, 0xE9, 0] },
        ScriptStep::Report { after_s: 0.0, bytes: vec![1, 0, 0, 0x27, 0, 0, 0, 0, 0] },
    ];
    let mut pad = Keypad::new(ScriptedHid::new(&clock, script), clock.clone(), ReportPrefix::ReportId(1));
    let event = pad.next_event(1.0).unwrap().unwrap();
    assert_eq!((event.key, event.action), (key(0x27), KeyAction::Down));
}

#[test]
fn a_disconnect_suggests_reopen_which_forgets_held_keys() {
    let (mut pad, _clock) = keypad(vec![
        report(0.0, [0, 0, 0x04, 0x05, 0, 0, 0, 0]),
        ScriptStep::Fail(TransportError::Disconnected("unplugged".into())),
        report(0.0, [0, 0, 0x05, 0, 0, 0, 0, 0]),
    ]);
    assert_eq!(pad.next_event(1.0).unwrap().unwrap().key, key(0x04));
    assert_eq!(pad.next_event(1.0).unwrap().unwrap().key, key(0x05));
    let err = pad.next_event(1.0).unwrap_err();
    assert!(err.suggests_reopen(), "{err}");
    assert!(!KeypadError::Transport(TransportError::Io("EPERM".into())).suggests_reopen());
    assert!(!KeypadError::Report(ReportError::RollOver).suggests_reopen());
    pad.reopen().unwrap();
    assert_eq!(pad.transport().reopens, 1);
    assert_eq!(pad.held().count(), 0);
    // Held keys were forgotten: after the reopen, 0x05 held is a new press (and 0x04 gets no release).
    let event = pad.next_event(1.0).unwrap().unwrap();
    assert_eq!((event.key, event.action), (key(0x05), KeyAction::Down));
    assert_eq!(pad.next_event(0.0).unwrap(), None);
}

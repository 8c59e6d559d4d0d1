//! Each fault kind of a scene's schedule, seen through the drivers as the typed error or flag a real device gives,
//! and recovery after its window.
#![allow(clippy::unwrap_used, clippy::expect_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_core::daq::DaqError;
use metaplate_core::rig::Rig;
use metaplate_core::scene::{FaultKind, FaultSpec};
use metaplate_core::vibrometer::VibrometerError;
use metaplate_lab::session::{configure, play_and_record};

fn at(kind: FaultKind, at_s: f64, duration_s: f64) -> FaultSpec {
    FaultSpec { kind, at_s, duration_s }
}

/// Sleeps the rig's clock until `t_s`.
fn until(rig: &Rig, t_s: f64) {
    rig.clock.sleep_s(t_s - rig.clock.now_s());
}

#[test]
fn c_every_fault_kind_is_seen_through_the_drivers_and_recovered_from() {
    let scene = common::scene(
        vec![
            at(FaultKind::SerialTimeout, 100.0, 10.0),
            at(FaultKind::GarbledReply, 120.0, 10.0),
            at(FaultKind::PartialReply, 140.0, 10.0),
            at(FaultKind::LdvDropout, 160.0, 10.0),
            at(FaultKind::UsbStall, 200.0, 60.0),
            at(FaultKind::DaqOverrun, 300.0, 0.1),
            at(FaultKind::AudioUnderrun, 400.0, 0.05),
            at(FaultKind::Disconnect, 500.0, 10.0),
        ],
        false,
    );
    let lab = common::lab(&scene, None);
    let mut rig = lab.rig().unwrap();
    configure(&mut rig, 2400).unwrap();
    rig.aim.aim_at(0.0, 0.0).unwrap();
    assert!(rig.vibrometer.signal_level().unwrap() > 0.2);

    // LDV serial faults: every attempt fails inside the window (timeouts cost virtual time, well under 10 s).
    for (start, name) in [(100.0, "serial timeout"), (120.0, "garbled"), (140.0, "partial")] {
        until(&rig, start + 0.5);
        let err = rig.vibrometer.signal_level().unwrap_err();
        assert!(matches!(err, VibrometerError::Timeout { .. }), "{name}: {err}");
        assert!(rig.clock.now_s() < start + 10.0, "{name}: the window must still be open");
        until(&rig, start + 10.5);
        rig.vibrometer.reconnect().unwrap();
        assert!(rig.vibrometer.signal_level().unwrap() > 0.2, "{name}: recovered");
    }
    // LDV dropout: the signal level reads 2 % inside the window, normal after.
    until(&rig, 160.5);
    assert_eq!(rig.vibrometer.signal_level().unwrap(), 0.02);
    until(&rig, 170.5);
    assert!(rig.vibrometer.signal_level().unwrap() > 0.2);

    // USB stall: reads time out (each costing its 1 s timeout) until the driver's retries are spent.
    until(&rig, 199.0);
    rig.daq.start().unwrap();
    until(&rig, 200.5);
    let err = rig.daq.read_block().unwrap_err();
    assert!(matches!(err, DaqError::Timeout { .. }), "{err}");
    until(&rig, 261.0);
    let _ = rig.daq.stop();
    rig.daq.reopen().unwrap();
    rig.daq.start().unwrap();
    assert!(rig.daq.read_block().unwrap().integrity.is_contiguous());
    rig.daq.stop().unwrap();

    // DAQ overrun: a block flagged, samples missing, and the stream goes on.
    until(&rig, 299.9);
    rig.daq.start().unwrap();
    let mut flagged = None;
    for _ in 0..10 {
        let block = rig.daq.read_block().unwrap();
        if block.integrity.overrun {
            flagged = Some(block.integrity);
            break;
        }
    }
    let integrity = flagged.expect("an overrun-flagged block");
    assert!(integrity.samples_missing > 0);
    rig.daq.stop().unwrap();

    // Audio underrun: counted, and the playback lasts longer by the gap (0.05 s at 48 kHz).
    until(&rig, 399.9);
    let tone = vec![0.25; 24_000];
    let rec = play_and_record(&mut rig, 0, &tone, &tone, 14_400).unwrap();
    assert_eq!(rec.underruns, 1);
    // The loopback shows the gap: samples at 0 V while the tone is on.
    let silent = rec.loopback_v.iter().skip(2_400).take(9_000).filter(|v| v.abs() < 1e-3).count();
    assert!((1_150..=1_250).contains(&silent), "{silent} silent samples, 0.05 s = 1200 expected");

    // Disconnect: every device fails at its next use, reopening fails inside the window and works after it.
    until(&rig, 500.5);
    assert!(matches!(rig.daq.start().unwrap_err(), DaqError::Disconnected { .. }));
    assert!(matches!(rig.daq.reopen().unwrap_err(), DaqError::Disconnected { .. }));
    assert!(matches!(rig.vibrometer.signal_level().unwrap_err(), VibrometerError::Disconnected { .. }));
    assert!(matches!(rig.vibrometer.reconnect().unwrap_err(), VibrometerError::Disconnected { .. }));
    let channels = vec![vec![0.0; 480]; rig.wiring.audio_channels as usize];
    assert!(rig.audio.start(&channels).unwrap_err().suggests_reopen());
    assert!(rig.audio.reopen().is_err());
    until(&rig, 510.5);
    rig.daq.reopen().unwrap();
    rig.vibrometer.reconnect().unwrap();
    rig.audio.reopen().unwrap();
    assert!(rig.vibrometer.signal_level().unwrap() > 0.2);
    let rec = play_and_record(&mut rig, 0, &tone, &tone, 12_000).unwrap();
    assert_eq!(rec.underruns, 0);
}

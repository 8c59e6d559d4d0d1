//! A scan through every fault the mock lab injects: it completes; points hit by a fault are re-measured or
//! flagged, never dropped; the others still match the truth; a disconnect longer than the pause limit pauses the
//! scan, which keeps polling and completes; every recovery is followed by a re-measure of a committed reference.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use std::sync::Arc;

use common::{error_db, lab_and_plan, median_and_worst, metamaterial, output, prefix, quick_config};
use metaplate_core::clock::Clock;
use metaplate_core::scene::{FaultKind, FaultSpec};
use metaplate_recipes::RecoveryPolicy;
use metaplate_recipes::scan::{ScanConfig, scan};
use metaplate_recipes::{Event, Phase, RunControl};
use metaplate_store::{Dataset, Status};

fn at(kind: FaultKind, at_s: f64, duration_s: f64) -> FaultSpec {
    FaultSpec { kind, at_s, duration_s }
}

/// The pause limit of the test, s: the disconnect below lasts longer, the LDV windows (25 s) cannot stall a
/// scan that long (the stall lasts from the first use inside the window to its end).
const PAUSE_AFTER_S: f64 = 30.0;

/// LDV windows: the LDV is only talked to when aiming at a point, every ~21 s of the quick protocol, so each
/// window is 25 s long to be sure to meet one aim.
const LDV_WINDOWS: [(FaultKind, f64); 3] =
    [(FaultKind::SerialTimeout, 10.0), (FaultKind::GarbledReply, 50.0), (FaultKind::PartialReply, 90.0)];
/// Faults that spoil a recording (detected as a gap, a clip or a low SNR), at these times; each window is longer
/// than the silent gap between two playbacks (under 0.2 s), so it meets a recording. They are 25 s apart, more than
/// a point (~21 s), so that each meets a point of its own: a point hit twice is re-measured once.
const DATA_FAULTS: [(FaultKind, f64, f64); 3] =
    [(FaultKind::DaqOverrun, 140.0, 0.5), (FaultKind::AudioUnderrun, 165.0, 0.3), (FaultKind::LdvDropout, 190.0, 1.0)];
const USB_STALL: (f64, f64) = (125.0, 3.0);
const DISCONNECT: (f64, f64) = (215.0, 45.0);

#[test]
fn a_scan_through_every_fault_kind_completes_and_remeasures_or_flags_what_they_hit() {
    let mut scene = metamaterial();
    scene.faults = LDV_WINDOWS.iter().map(|&(kind, t)| at(kind, t, 25.0)).collect();
    scene.faults.extend(DATA_FAULTS.iter().map(|&(kind, t, d)| at(kind, t, d)));
    scene.faults.push(at(FaultKind::UsbStall, USB_STALL.0, USB_STALL.1));
    scene.faults.push(at(FaultKind::Disconnect, DISCONNECT.0, DISCONNECT.1));
    let (lab, plan) = lab_and_plan(&scene, 7, 5);
    // 16 points of ~21 s each, plus the stalls: the scan outlasts the last fault window (260 s).
    let plan = prefix(&plan, 16);
    let mut rig = lab.rig().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cfg = ScanConfig {
        recovery: RecoveryPolicy { pause_after_s: PAUSE_AFTER_S, ..RecoveryPolicy::default() },
        ..quick_config()
    };
    let clock: Arc<dyn Clock> = lab.clock().clone();
    let mut events: Vec<(f64, Event)> = Vec::new();
    let mut record = |e: &Event| events.push((clock.now_s(), e.clone()));
    let summary =
        scan(&mut rig, &plan, None, &cfg, &output(dir.path(), &scene, false), &RunControl::new(), &mut record).unwrap();
    for (t, e) in &events {
        eprintln!("{t:7.2} s {e:?}");
    }
    eprintln!("{summary:?}");
    let last_fault_end_s = DISCONNECT.0 + DISCONNECT.1;
    assert!(summary.clock_s > last_fault_end_s + 20.0, "the scan outlasts the schedule: {:.0} s", summary.clock_s);

    // Never dropped: every point and actuator committed once (the reader refuses duplicates).
    let dataset = Dataset::open(dir.path()).unwrap();
    let actuators = scene.actuators.len();
    assert_eq!(summary.committed, plan.points.len());
    assert_eq!(dataset.len(), plan.points.len() * actuators, "one row per point and actuator, none dropped");

    let times = |pred: &dyn Fn(&Event) -> bool| -> Vec<f64> {
        events.iter().filter(|(_, e)| pred(e)).map(|(t, _)| *t).collect()
    };
    let recovered =
        |device: &'static str| times(&move |e| matches!(e, Event::Recovered { detail } if detail.starts_with(device)));
    // Link faults: each LDV window met an aim and was recovered from by the window's end (+ one poll and the
    // reconnect, 5 s); the USB stall likewise; the disconnect after its end, within 10 s: a 2 s poll, then all
    // three devices reopened in turn (the LDV's reconnect costs its serial timeouts in virtual time).
    let ldv = recovered("Vibrometer");
    for (kind, start) in LDV_WINDOWS {
        assert!(
            ldv.iter().any(|t| (start..start + 30.0).contains(t)),
            "{kind:?} at {start} s: LDV recovered at {ldv:?}"
        );
    }
    let daq = recovered("Daq");
    assert!(daq.iter().any(|t| (USB_STALL.0..USB_STALL.0 + USB_STALL.1 + 5.0).contains(t)), "stall: {daq:?}");
    let all = times(&|e| matches!(e, Event::Recovered { .. }));
    assert!(all.iter().any(|t| (last_fault_end_s..last_fault_end_s + 10.0).contains(t)), "disconnect: {all:?}");
    // The disconnect outlasted the pause limit: paused once, PAUSE_AFTER_S into it (+ one 2 s poll), and polled on.
    let paused = times(&|e| matches!(e, Event::Paused { .. }));
    assert_eq!(paused.len(), 1, "paused once: {paused:?}");
    let pause_at = DISCONNECT.0 + PAUSE_AFTER_S;
    assert!((pause_at..pause_at + 5.0).contains(&paused[0]), "paused at {:.1} s", paused[0]);

    // Data faults: the point whose recording met the window is retried, at once when the acquisition sees the
    // fault (an overrun, an underrun) or when the point is processed, after the next point's acquisition (a
    // dropout, caught by the SNR gate); it is committed as re-measured or flagged, never as valid.
    let playing_at = |t_s: f64| -> usize {
        events
            .iter()
            .filter(|(t, e)| *t <= t_s && matches!(e, Event::Phase { phase: Phase::Playing, .. }))
            .filter_map(|(_, e)| match e {
                Event::Phase { unit, .. } => Some(*unit),
                _ => None,
            })
            .next_back()
            .unwrap()
    };
    let status_of = |point: usize| {
        events.iter().find_map(|(_, e)| match e {
            Event::Committed { unit, status, .. } if *unit == point => Some(status.clone()),
            _ => None,
        })
    };
    for (kind, start, duration) in DATA_FAULTS {
        let point = playing_at(start + duration / 2.0);
        let retried =
            events.iter().any(|(t, e)| matches!(e, Event::Retry { unit, .. } if *unit == point && *t >= start));
        assert!(retried, "{kind:?} at {start} s met point {point}'s recording: no retry of it");
        let status = status_of(point).unwrap();
        assert_ne!(status, "valid", "{kind:?} hit point {point}, committed {status}");
    }

    // Reference checks: after every recovery that follows the first commit, before the scan ends, a committed
    // point re-measured; each within the default limit (-20 dB): the rig came back as it was.
    let first_commit = times(&|e| matches!(e, Event::Committed { .. }))[0];
    let checks: Vec<(f64, f64)> = events
        .iter()
        .filter_map(|(t, e)| match e {
            Event::ReferenceChecked { deviation_db, .. } => Some((*t, *deviation_db)),
            _ => None,
        })
        .collect();
    for t in all.iter().filter(|t| **t > first_commit) {
        assert!(checks.iter().any(|(c, _)| c > t), "no reference check after the recovery at {t:.1} s: {checks:?}");
    }
    let limit = RecoveryPolicy::default().reference_limit_db;
    assert!(checks.iter().all(|(_, d)| *d < limit), "reference deviations {checks:?}");

    // Rows measured well (valid, re-measured) match the truth with scan_mock's budget (median -30 dB, worst
    // -15 dB): a fault never leaves a bad response under a good status.
    let mut errors = Vec::new();
    for (row, meta) in dataset.rows().iter().enumerate() {
        let status = meta.status.unwrap();
        assert!(!matches!(status, Status::GroundTruth), "row {row}: a measured status");
        if matches!(status, Status::Valid | Status::ReMeasured) {
            let ir = dataset.row_ir(row).unwrap();
            errors.push(error_db(
                &lab,
                meta.point_index as usize,
                meta.actuator as usize,
                ir,
                dataset.sample_rate_hz(),
            ));
        }
    }
    let (median, worst) = median_and_worst(&mut errors);
    eprintln!("{} good rows: median {median:.1} dB, worst {worst:.1} dB", errors.len());
    assert!(median < -30.0 && worst < -15.0, "median {median:.1} dB, worst {worst:.1} dB");
}

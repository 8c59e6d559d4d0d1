//! Resumption: a scan stopped after several commits and abandoned in the middle of a point, resumed each time on a
//! restarted lab, ends with the dataset of an uninterrupted run, point for point; a changed configuration is
//! refused (saying what changed) unless forced.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use std::sync::atomic::{AtomicBool, Ordering};

use common::{
    Recorder, assert_same_rows, image, metamaterial, output, quick_config, run_scan, run_scan_with, small_plan,
};
use metaplate_recipes::scan::{ScanConfig, ScanPoints, scan};
use metaplate_recipes::{Event, RecipeError, RunControl, Silent};
use metaplate_store::{Dataset, StoreError};

/// Points of the test plan: enough for three stops and a remainder.
const POINTS: usize = 9;

/// `Started { done }` of a run's events.
fn started_done(events: &[Event]) -> usize {
    events.iter().find_map(|e| if let Event::Started { done, .. } = e { Some(*done) } else { None }).unwrap()
}

#[test]
fn stopped_and_abandoned_runs_resume_to_the_uninterrupted_dataset() {
    let scene = metamaterial();
    let plan = small_plan(POINTS);
    let reference_dir = tempfile::tempdir().unwrap();
    run_scan(&plan, &output(reference_dir.path(), &scene, false), &RunControl::new(), &mut Silent).unwrap();
    let reference = image(reference_dir.path());
    // Two uninterrupted runs are bit-identical: what differs after a resume is only the absolute clock time.
    let again_dir = tempfile::tempdir().unwrap();
    run_scan(&plan, &output(again_dir.path(), &scene, false), &RunControl::new(), &mut Silent).unwrap();
    assert!(image(again_dir.path()) == reference, "two uninterrupted runs with one seed are bit-identical");

    let dir = tempfile::tempdir().unwrap();
    let mut committed_so_far = 0;
    // Stops after 2, then 3 commits (Ctrl-C once, right after a commit): the point in flight (recorded while the
    // previous one was processed) is finished and committed too, so each run commits one more.
    for (k, stop_after) in [2, 3].into_iter().enumerate() {
        let control = RunControl::new();
        control.stop_after_commits(stop_after);
        let mut events = Recorder::default();
        let err = run_scan(&plan, &output(dir.path(), &scene, k > 0), &control, &mut events).unwrap_err();
        assert_eq!(started_done(&events.0), committed_so_far, "resume starts after the last commit");
        committed_so_far += stop_after + 1;
        assert!(matches!(err, RecipeError::Interrupted { committed } if committed == committed_so_far), "{err}");
    }

    // Ctrl-C twice in the middle of a point: a watcher raises level 2 once the rig's clock is half way into the
    // second point of this run (a point takes ~21 s of quick protocol). No event is emitted inside a point's
    // acquisition without faults (an observer raising it at a commit finds the next point already recorded, which
    // is then committed whole), so the watcher follows the lab's clock from its own thread.
    let (lab, _) = common::lab_and_plan(&scene, 7, 5);
    let mut rig = lab.rig().unwrap();
    let control = RunControl::new();
    let finished = AtomicBool::new(false);
    let clock = lab.clock().clone();
    let (result, raised_at_s) = std::thread::scope(|scope| {
        let watcher = scope.spawn(|| {
            while !finished.load(Ordering::Acquire) {
                let now_s = metaplate_core::clock::Clock::now_s(clock.as_ref());
                if now_s > 32.0 {
                    control.request_stop();
                    control.request_stop();
                    return Some(now_s);
                }
                std::thread::sleep(std::time::Duration::from_micros(200));
            }
            None
        });
        let out = output(dir.path(), &scene, true);
        let result = scan(&mut rig, &plan, None, &quick_config(), &out, &control, &mut Silent);
        finished.store(true, Ordering::Release);
        (result, watcher.join().unwrap())
    });
    let raised_at_s = raised_at_s.expect("the stop was raised during the run");
    let RecipeError::Interrupted { committed } = result.unwrap_err() else { panic!("not an interruption") };
    eprintln!("level 2 raised at {raised_at_s:.2} s; {committed} committed");
    // The first point of this run was in processing and is committed; the second is abandoned.
    assert!(committed > committed_so_far && committed < POINTS, "{committed} committed after an abandon");
    committed_so_far = committed;

    // The rest, uninterrupted.
    let mut events = Recorder::default();
    let summary = run_scan(&plan, &output(dir.path(), &scene, true), &RunControl::new(), &mut events).unwrap();
    assert_eq!(started_done(&events.0), committed_so_far);
    assert_eq!(summary.committed_now, POINTS - committed_so_far, "only what was missing is measured");
    assert_eq!(summary.committed, POINTS);

    // No duplicates (the reader refuses them), no gaps (the same keys), the same bits and statuses.
    let resumed = image(dir.path());
    assert_eq!(resumed.len(), POINTS * scene.actuators.len());
    assert_same_rows(&reference, &resumed, "resumed vs uninterrupted");
}

/// A 3-point metamaterial scan stopped after its first commit: the scene, the plan, the dataset's directory and
/// the points committed.
fn scan_stopped_after_one_point() -> (metaplate_core::scene::Scene, ScanPoints, tempfile::TempDir, usize) {
    let scene = metamaterial();
    let plan = small_plan(3);
    let dir = tempfile::tempdir().unwrap();
    let control = RunControl::new();
    control.stop_after_commits(1);
    let err = run_scan(&plan, &output(dir.path(), &scene, false), &control, &mut Silent).unwrap_err();
    let RecipeError::Interrupted { committed } = err else { panic!("{err}") };
    (scene, plan, dir, committed)
}

#[test]
fn a_changed_configuration_is_refused_saying_what_changed_and_proceeds_when_forced() {
    let (scene, plan, dir, committed) = scan_stopped_after_one_point();

    let changed = ScanConfig { min_snr_db: 25.0, ..quick_config() };
    let err =
        run_scan_with(&plan, &changed, &output(dir.path(), &scene, true), &RunControl::new(), &mut Silent).unwrap_err();
    let message = err.to_string();
    let RecipeError::Store(StoreError::ConfigChanged { differences, .. }) = &err else { panic!("{message}") };
    // Exactly the one key changed, named with its old and new values.
    assert_eq!(differences.len(), 1, "{differences:?}");
    assert!(message.contains("min_snr_db") && message.contains("20") && message.contains("25"), "{message}");
    assert!(message.contains("force"), "the message says how to proceed: {message}");
    assert_eq!(Dataset::open(dir.path()).unwrap().points().len(), committed, "a refused resume changes nothing");

    let forced = metaplate_recipes::Output { force: true, ..output(dir.path(), &scene, true) };
    let summary = run_scan_with(&plan, &changed, &forced, &RunControl::new(), &mut Silent).unwrap();
    assert_eq!((summary.committed_now, summary.committed), (3 - committed, 3));
    assert_eq!(Dataset::open(dir.path()).unwrap().len(), 3 * scene.actuators.len());
}

#[test]
fn a_resume_on_other_wiring_is_refused_naming_it() {
    let (scene, plan, dir, _) = scan_stopped_after_one_point();
    // The dataset records the rig it was measured on.
    let rig_recorded = Dataset::open(dir.path()).unwrap().manifest().meta.config["rig"].clone();
    // The mock lab's Polytec controller, as the driver identifies it (its RS-232 interface reports no serial).
    assert_eq!(rig_recorded["vibrometer"]["vendor"], "Polytec", "{rig_recorded}");
    assert_eq!(
        rig_recorded["vibrometer"]["model"], "OFV-5000 Vibrometer Controller; sensor head OFV-505; VeloDec,0 VD-02",
        "{rig_recorded}"
    );
    assert_eq!(rig_recorded["wiring"]["loopback_channel"], 8, "{rig_recorded}");
    assert_eq!(rig_recorded["aim"], "the mock lab's beam (in-process, no mirrors or stages)", "{rig_recorded}");

    // The same lab with actuators 0 and 1 cabled the other way round.
    let (lab, _) = common::lab_and_plan(&scene, 7, 5);
    let mut rig = lab.rig().unwrap();
    rig.wiring.actuator_channels.swap(0, 1);
    let err = scan(
        &mut rig,
        &plan,
        None,
        &quick_config(),
        &output(dir.path(), &scene, true),
        &RunControl::new(),
        &mut Silent,
    )
    .unwrap_err();
    let message = err.to_string();
    let RecipeError::Store(StoreError::ConfigChanged { differences, .. }) = &err else { panic!("{message}") };
    assert_eq!(differences.len(), 1, "{differences:?}");
    assert!(differences[0].contains("rig.wiring.actuator_channels"), "{differences:?}");
    assert!(message.contains("force"), "{message}");
}

/// One scan run of the first `points` of the homogeneous scene's 7 x 5 plan on a fresh lab (a restarted program).
fn run_homogeneous(
    points: usize,
    out_dir: &std::path::Path,
    resume: bool,
    control: &RunControl,
    observer: &mut dyn metaplate_recipes::Observer,
) -> Result<metaplate_recipes::scan::ScanSummary, RecipeError> {
    let scene = metaplate_core::scene::Scene::builtin("homogeneous").unwrap();
    let (lab, plan) = common::lab_and_plan(&scene, 7, 5);
    let mut rig = lab.rig().unwrap();
    let plan = common::prefix(&plan, points);
    scan(&mut rig, &plan, None, &quick_config(), &output(out_dir, &scene, resume), control, observer)
}

#[test]
fn a_resumed_run_continues_at_the_velocity_range_the_interrupted_one_had_widened_to() {
    // The homogeneous plate clips at the configured 0.1 m/s: the first point widens the range, kept for the run.
    const POINTS: usize = 4;
    let reference_dir = tempfile::tempdir().unwrap();
    run_homogeneous(POINTS, reference_dir.path(), false, &RunControl::new(), &mut Silent).unwrap();

    let dir = tempfile::tempdir().unwrap();
    let control = RunControl::new();
    control.stop_after_commits(1);
    let mut events = Recorder::default();
    let err = run_homogeneous(POINTS, dir.path(), false, &control, &mut events).unwrap_err();
    assert!(matches!(err, RecipeError::Interrupted { committed: 2 }), "{err}");
    let widened = events.0.iter().any(|e| matches!(e, Event::Retry { reason, .. } if reason == "clipped"));
    assert!(widened, "the interrupted run widened the range before it stopped");

    let mut events = Recorder::default();
    run_homogeneous(POINTS, dir.path(), true, &RunControl::new(), &mut events).unwrap();
    assert_eq!(started_done(&events.0), 2);
    let clipped_again = events.0.iter().any(|e| matches!(e, Event::Retry { reason, .. } if reason == "clipped"));
    assert!(!clipped_again, "the resumed run starts at the widened range, so it does not clip again");
    assert_same_rows(&image(reference_dir.path()), &image(dir.path()), "resumed at the widened range vs uninterrupted");
}

#[test]
fn a_rig_that_cannot_reach_a_point_stops_before_the_run_starts() {
    // An aimer that refuses every point (a hardware rig without an aiming backend): the run stops at the reach
    // check, naming why, before a dataset is created.
    let scene = metamaterial();
    let plan = small_plan(3);
    let dir = tempfile::tempdir().unwrap();
    let (lab, _) = common::lab_and_plan(&scene, 7, 5);
    let mut rig = lab.rig().unwrap();
    rig.aim = Box::new(metaplate_core::aim::NoAimer { detail: "no aiming backend in this test".into() });
    let out = output(&dir.path().join("run"), &scene, false);
    let err = scan(&mut rig, &plan, None, &quick_config(), &out, &RunControl::new(), &mut Silent).unwrap_err();
    assert!(
        matches!(&err, RecipeError::Aim(metaplate_core::aim::AimError::Unavailable { detail }) if detail.contains("no aiming")),
        "{err}"
    );
    assert!(!dir.path().join("run").exists(), "nothing written before the reach check");
}

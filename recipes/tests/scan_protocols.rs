//! Simultaneous protocols in the scan, on the mock lab with its full noise, drift and actuator nonlinearity: the
//! Green's functions must match the ground truth about as well as the sequential `quick` protocol's, in less
//! rig-clock time per point.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_recipes::scan::{ScanConfig, ScanSummary, scan};
use metaplate_recipes::{Event, Observer, RunControl};
use metaplate_store::{Dataset, Status};

/// Runs `protocol` on the first `points` points of the metamaterial scene's 7 x 5 plan (the Green's functions the
/// other scan tests share, cached); returns the sorted errors (dB), the rig-clock seconds per point, the summary
/// and the rows' statuses.
fn run(protocol: &str, points: usize) -> (Vec<f64>, f64, ScanSummary, Vec<Status>) {
    let scene = common::metamaterial();
    let (lab, plan) = common::lab_and_plan(&scene, 7, 5);
    let plan = common::prefix(&plan, points);
    let mut rig = lab.rig().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = common::output(dir.path(), &scene, false);
    let cfg = ScanConfig { protocol: ExcitationProtocol::by_name(protocol).unwrap(), seed: 7, ..ScanConfig::default() };
    let summary = scan(&mut rig, &plan, None, &cfg, &out, &RunControl::new(), &mut Reasons).unwrap();
    let dataset = Dataset::open(dir.path()).unwrap();
    let (mut errors, mut statuses) = (Vec::new(), Vec::new());
    for &p in &plan.points {
        for a in 0..scene.actuators.len() {
            let ir: Vec<f64> = dataset.ir(p as u32, a as u16).unwrap().iter().map(|v| f64::from(*v)).collect();
            let ir = metaplate_lab::time_zero_first(
                &ir,
                dataset.manifest().meta.description.as_ref().unwrap().pre_samples as usize,
            );
            errors.push(lab.response_error_db(p, a, &ir, dataset.sample_rate_hz(), ERROR_BAND_HZ, None).unwrap());
        }
    }
    for row in dataset.rows() {
        statuses.push(row.status.unwrap_or(Status::Valid));
    }
    errors.sort_by(f64::total_cmp);
    let per_point_s = summary.clock_s / plan.points.len() as f64;
    (errors, per_point_s, summary, statuses)
}

/// Prints why points were retried or deferred (shown with --nocapture when a test fails).
struct Reasons;

impl Observer for Reasons {
    fn event(&mut self, event: &Event) {
        if let Event::Retry { reason, .. } = event {
            eprintln!("retry: {reason}");
        }
    }
}

#[test]
fn hadamard_matches_quick_in_less_time_per_point() {
    let (quick, t_quick, _, _) = run("quick", 4);
    let (had, t_had, summary, _) = run("hadamard:0.6x1", 4);
    let median = |e: &[f64]| e[e.len() / 2];
    eprintln!(
        "quick: median {:.1} dB, worst {:.1} dB, {t_quick:.1} s/point; hadamard:0.6x1: median {:.1} dB, worst {:.1} dB, \
         {t_had:.1} s/point; {summary:?}",
        median(&quick),
        quick[quick.len() - 1],
        median(&had),
        had[had.len() - 1]
    );
    // Equal accuracy: the Hadamard shots give each actuator 8 x 0.6 s = 4.8 s of sweep against quick's 2 x 1 s, so
    // noise alone would favour it by 4 dB; the voice coils' distortion and the deconvolution's bias are the same
    // for both (about -44 dB). One 1x1 run measured -34.4 dB for both. Its median must be within 1.5 dB of quick's
    // (the spread of two noise draws over 32 rows) or better, and no row may fail.
    assert!(median(&had) < median(&quick) + 1.5, "median {:.1} vs {:.1} dB", median(&had), median(&quick));
    assert!(had[had.len() - 1] < -15.0, "worst {:.1} dB (the sequential test's bound)", had[had.len() - 1]);
    assert_eq!(summary.statuses.get("failed"), None, "{summary:?}");
    // Less time: nominal 8.8 s of playing against 20 s; beam moves and recording margins add about the same to
    // both, so the measured ratio must stay well under 0.75.
    assert!(t_had < 0.75 * t_quick, "{t_had:.1} s vs {t_quick:.1} s per point");
}

#[test]
fn an_unreachable_snr_target_costs_bounded_time_then_flags_the_rows() {
    // 200 dB is beyond any recording's 16-bit DAQ; 2 rounds at most: every row failed, in about twice the time of
    // one round (8 x 1.1 s nominal each), not more.
    let (_, t, summary, statuses) = run("adaptive:0.6x2@200/2", 1);
    assert!(statuses.iter().all(|s| *s == Status::Failed), "{statuses:?}");
    assert_eq!(summary.deferred, 0, "a bounded adaptive failure is final, not deferred: {summary:?}");
    // Nominal: 2 rounds x 8 shots x (1.2 + 0.5) s = 27.2 s; beam moves and recording margins add a few seconds.
    assert!(t < 40.0, "{t:.1} s per point");
}

#[test]
fn staggered_sweeps_match_quick_in_one_shot_per_point() {
    // staggered:4.8x2: every actuator gets 9.6 s of sweep in one 9.6 s shot (its own 0.6 s slot of the period),
    // against quick's 2 s in 8 shots: noise favours it by 7 dB, and the coils' distortion and the deconvolution's
    // bias are the same (about -44 dB) or, the distortion spreading over the whole period, shared among the slots.
    // Its median must be within 1.5 dB of quick's or better (two noise draws over 32 rows), no row may fail, and
    // the shot's one ring-out makes it the faster: nominal 10.1 s against 20 s.
    let (quick, t_quick, _, _) = run("quick", 4);
    let (one, t_one, summary, _) = run("staggered:4.8x2", 4);
    let median = |e: &[f64]| e[e.len() / 2];
    eprintln!(
        "quick: median {:.1} dB, {t_quick:.1} s/point; staggered:4.8x2: median {:.1} dB, worst {:.1} dB, {t_one:.1} \
         s/point; {summary:?}",
        median(&quick),
        median(&one),
        one[one.len() - 1]
    );
    assert!(median(&one) < median(&quick) + 1.5, "median {:.1} vs {:.1} dB", median(&one), median(&quick));
    assert!(one[one.len() - 1] < -15.0, "worst {:.1} dB (the sequential test's bound)", one[one.len() - 1]);
    assert_eq!(summary.statuses.get("failed"), None, "{summary:?}");
    assert!(t_one < 0.75 * t_quick, "{t_one:.1} s vs {t_quick:.1} s per point");
}

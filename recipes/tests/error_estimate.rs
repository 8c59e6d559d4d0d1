//! Each committed row's estimated error (from the spread of its repetitions or shots) against its true error on the
//! mock lab: close where the noise sets the error (the plate without retroreflective tape), a lower bound where a
//! bias every repetition shares sets it (the taped plate, whose voice coils' distortion none of them shows).

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_core::scene::{Imperfection, Scene};
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_recipes::scan::{ScanConfig, scan};
use metaplate_recipes::{RunControl, Silent};
use metaplate_store::{Dataset, Status};

/// Scans the first 6 points of `scene`'s 7 x 5 plan with `protocol` (seed 7); per row, the estimated and the true
/// error, dB, and its status; and the rig-clock seconds per point.
fn estimated_and_true(scene: &Scene, protocol: &str) -> (Vec<(f64, f64)>, Vec<Option<Status>>, f64) {
    let (lab, plan) = common::lab_and_plan(scene, 7, 5);
    let plan = common::prefix(&plan, 6);
    let dir = tempfile::tempdir().unwrap();
    let out = common::output(dir.path(), scene, false);
    let cfg = ScanConfig { protocol: ExcitationProtocol::by_name(protocol).unwrap(), seed: 7, ..ScanConfig::default() };
    let mut rig = lab.rig().unwrap();
    let summary = scan(&mut rig, &plan, None, &cfg, &out, &RunControl::new(), &mut Silent).unwrap();
    let dataset = Dataset::open(dir.path()).unwrap();
    let pre = dataset.manifest().meta.description.as_ref().unwrap().pre_samples as usize;
    let rows = dataset
        .rows()
        .iter()
        .zip(dataset.irs().chunks_exact(dataset.ir_len()))
        .map(|(meta, ir)| {
            let ir: Vec<f64> = ir.iter().map(|v| f64::from(*v)).collect();
            let ir = metaplate_lab::time_zero_first(&ir, pre);
            let truth = lab
                .response_error_db(
                    meta.point_index as usize,
                    usize::from(meta.actuator),
                    &ir,
                    meta.sample_rate_hz,
                    common::BAND_HZ,
                    None,
                )
                .unwrap();
            let estimate = meta.estimated_error_db.unwrap_or_else(|| panic!("row {meta:?} has no estimate"));
            (estimate, truth)
        })
        .collect();
    let statuses = dataset.rows().iter().map(|r| r.status).collect();
    (rows, statuses, summary.clock_s / plan.points.len() as f64)
}

/// The untaped plate with its light and speckle (the noise varies over the plate) and every other imperfection
/// off, its noise floor set so that the noise lies well above the metamaterial's processing floor (about -45 dB:
/// its response outlasting the stored window, `metaplate budget`): the `quick` protocol's rows lie between -33 and
/// -8 dB, median -20 dB, so the error is the noise's, row by row.
fn noisy() -> Scene {
    let untaped = Scene::builtin("metamaterial-untaped").unwrap();
    let mut scene = untaped.with_only(&[Imperfection::LdvNoise, Imperfection::Speckle]);
    scene.ldv.noise_rms_m_s = 2e-4;
    scene
}

fn share(rows: &[(f64, f64)], ok: impl Fn(f64, f64) -> bool) -> f64 {
    rows.iter().filter(|(e, t)| ok(*e, *t)).count() as f64 / rows.len() as f64
}

#[test]
fn where_noise_sets_the_error_the_estimate_is_within_3_db_of_it() {
    let scene = noisy();
    for protocol in ["quick", "hadamard:0.6x2"] {
        let (rows, _, _) = estimated_and_true(&scene, protocol);
        for (e, t) in &rows {
            eprintln!("{protocol}: estimated {e:6.1} dB, true {t:6.1} dB");
        }
        // The bar: within 3 dB of the true error for 90 % of rows. Two draws of the noise over a row's
        // 80..600 Hz bins scatter the true error by well under 1 dB; the estimate's own spread from 2 periods
        // (a thousand-odd bins, one degree of freedom each) is of the same order.
        let close = share(&rows, |e, t| (e - t).abs() <= 3.0);
        assert!(close >= 0.9, "{protocol}: {:.0} % of {} rows within 3 dB", close * 100.0, rows.len());
    }
}

#[test]
fn where_a_shared_bias_sets_the_error_the_estimate_is_a_lower_bound() {
    // The taped plate: the noise is some 40 dB below the coils' distortion (-44.5 dB on 0.8's plate, `metaplate budget`), which
    // every period repeats, so no spread sees it. The estimate is then the noise's part alone: below the truth,
    // never above it by more than its own scatter.
    let (rows, _, _) = estimated_and_true(&common::metamaterial(), "quick");
    let below = share(&rows, |e, t| e <= t + 3.0);
    assert!(below >= 0.9, "{:.0} % of rows at or below their true error", below * 100.0);
    assert!(share(&rows, |e, t| e < t - 10.0) > 0.5, "the estimate sees the noise only: far below a biased truth");
}

#[test]
fn sequential_adaptive_rounds_stop_each_row_at_its_target() {
    // Each actuator is played until its own estimated error reaches -22 dB (at most 6 x 2 periods of 0.6 s, a
    // first shot of 2, then shots of the periods its estimate says are missing): every row ends at or below the
    // target or is flagged as short of it, and the true errors follow (the estimate is within 3 dB of them, the
    // first test), with rows taking different numbers of periods, so a point costs less than if every row took its
    // whole budget. The target lies 2 dB below the `quick` protocol's median error on this plate (-20 dB, the first
    // test's rows, from 2 s of sweep); the budget's 7.2 s gives up to 5.6 dB more than that: within reach for most
    // rows, not for the weakest (measured: 88 % reach it).
    const TARGET_DB: f64 = -22.0;
    let (rows, statuses, per_point_s) = estimated_and_true(&noisy(), "sequential-adaptive:0.6x2@-22/6");
    assert_eq!(statuses.len(), rows.len());
    for ((e, t), status) in rows.iter().zip(&statuses) {
        // A row short of the target after its 6 shots is flagged, never passed off as reaching it.
        assert!(*e <= TARGET_DB || *status == Some(Status::Failed), "estimated {e:.1} dB, true {t:.1} dB, {status:?}");
    }
    let at_target = share(&rows, |e, _| e <= TARGET_DB);
    eprintln!("{:.0} % of rows reached the target", at_target * 100.0);
    assert!(at_target >= 0.75, "{:.0} % of rows reached the target", at_target * 100.0);
    let reached: Vec<(f64, f64)> = rows.iter().copied().filter(|(e, _)| *e <= TARGET_DB).collect();
    let true_ok = share(&reached, |_, t| t <= TARGET_DB + 3.0);
    assert!(true_ok >= 0.9, "{:.0} % of the rows at the target truly within 3 dB of it", true_ok * 100.0);
    // Every row's whole budget, 12 periods (7.2 s) in three shots (3 x 0.6 s of ring-out and margin), for all 8
    // actuators would be 72 s per point, beam moves aside.
    assert!(per_point_s < 0.8 * 72.0, "{per_point_s:.1} s per point");
}

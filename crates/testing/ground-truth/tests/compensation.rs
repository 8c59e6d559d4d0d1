//! The compensated ground truth: each actuator's response at its magnet is flat (as the calibration recipe
//! requires of a measured one), the uncompensated one is not, and contradictory options are refused.

#![allow(clippy::unwrap_used)] // tests may unwrap

use std::path::{Path, PathBuf};

use metaplate_dsp::smooth::smoothed_levels_db;
use metaplate_ground_truth::{CompensationConfig, GroundTruth, GroundTruthError, GroundTruthOptions};

fn cache() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache")
}

/// Largest excursion of the third-octave-smoothed level from its median over 62 to 625 Hz, dB.
fn deviation_db(ir: &[f64], fs: f64) -> f64 {
    let mut levels: Vec<f64> =
        smoothed_levels_db(ir, fs, 3.0, (62.0, 625.0)).unwrap().into_iter().map(|(_, db)| db).collect();
    levels.sort_unstable_by(f64::total_cmp);
    let median = levels[levels.len() / 2];
    (levels[levels.len() - 1] - median).max(median - levels[0])
}

#[test]
fn every_magnet_response_is_flat_once_compensated() {
    let options = GroundTruthOptions::default();
    let truth = GroundTruth::builtin("metamaterial", &options, Some(&cache())).unwrap();
    let raw =
        GroundTruth::builtin("metamaterial", &GroundTruthOptions { compensation: None, ..options }, Some(&cache()))
            .unwrap();
    let fs = truth.driving_points.sample_rate_hz;
    assert_eq!(truth.equalisers.len(), 8);
    assert!(raw.equalisers.is_empty());
    for a in 0..8 {
        let compensated = deviation_db(truth.driving_points.ir(a, a).unwrap(), fs);
        let uncompensated = deviation_db(raw.driving_points.ir(a, a).unwrap(), fs);
        eprintln!("actuator {a}: {uncompensated:.1} dB uncompensated, {compensated:.2} dB compensated");
        // The recipe's requirement on a measured verification (+/-1 dB); the response here is the equaliser's own
        // prediction but truncated to 0.5 s with a fade, and through the coil at the lab's rate, so not identical.
        assert!(compensated <= 1.0, "actuator {a}: {compensated} dB");
        // The magnet responses fall about 30 dB over the band: compensation had work to do.
        assert!(uncompensated > 10.0, "actuator {a}: {uncompensated} dB uncompensated");
    }
    // Same points, same actuators, same length as the uncompensated chain.
    assert_eq!(truth.responses.points, raw.responses.points);
    assert_eq!(truth.responses.data.len(), raw.responses.data.len());
    assert!(truth.responses.data.iter().all(|v| v.is_finite()));
}

#[test]
fn contradictory_options_are_refused() {
    let scene = || metaplate_core::scene::Scene::builtin("homogeneous").unwrap();
    let at_24k =
        GroundTruthOptions { compensation: Some(CompensationConfig::calibration(24_000.0)), ..Default::default() };
    let err = GroundTruth::new(scene(), &at_24k, None).unwrap_err();
    assert!(
        matches!(err, GroundTruthError::InvalidOption { name: "compensation.equaliser.kirkeby.sample_rate_hz", .. }),
        "{err}"
    );
    let mut wide = CompensationConfig::calibration(2000.0);
    wide.equaliser.band_hz = (20.0, 625.0);
    let err = GroundTruth::new(scene(), &GroundTruthOptions { compensation: Some(wide), ..Default::default() }, None)
        .unwrap_err();
    assert!(matches!(err, GroundTruthError::InvalidOption { name: "compensation.equaliser.band_hz", .. }), "{err}");
    assert!(matches!(
        GroundTruth::builtin("no-such-plate", &GroundTruthOptions::default(), None),
        Err(GroundTruthError::Scene(_))
    ));
}

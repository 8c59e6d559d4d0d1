//! Green's functions: determinism, the no-time-aliasing rule, the cache, and refusals.
#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_core::scene::Scene;
use metaplate_plate::{GreensRequest, ModelOptions, PlateError, PlateModel, SpectralPlan, greens_functions};

fn small_request(scene: &Scene, duration_s: f64) -> GreensRequest {
    let points = scene.measured_points();
    GreensRequest {
        points: vec![points[40], points[500], points[900]],
        actuators: vec![1, 6],
        band_hz: (300.0, 400.0),
        duration_s,
        sample_rate_hz: 24_000.0,
    }
}

#[test]
fn same_scene_and_seed_give_bit_identical_results_whatever_the_threads() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let request = small_request(&scene, 0.1);
    let one = PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 1 }).unwrap();
    let two = PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 2 }).unwrap();
    let a = one.greens_functions(&request).unwrap();
    let b = two.greens_functions(&request).unwrap();
    assert_eq!(a, b);
    assert!(a.data.iter().any(|&v| v != 0.0));
}

#[test]
fn the_frequency_grid_does_not_time_alias() {
    // The rule makes the FFT period long enough for a 60 dB ring-down. Compute the same responses with a period
    // 2.5 times longer (by asking for a longer duration) and compare their common first 90 ms: they may differ only
    // by what folded back in the shorter period, at most 1e-3 of each mode's initial amplitude. A few modes share
    // the 300-400 Hz band (the plate has about one per 47 Hz), so their folded tails add to a few 1e-3 of the peak.
    let scene = Scene::builtin("homogeneous").unwrap();
    let model = PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 2 }).unwrap();
    let short = small_request(&scene, 0.1);
    let long = small_request(&scene, 0.6);
    let plan = SpectralPlan::new(&short, &|f| model.loss_factor_bound(f)).unwrap();
    assert!(plan.fft_len as f64 > 0.2 * 24_000.0, "the ring-down rule, not the duration, sets this FFT");
    let (a, b) = (model.greens_functions(&short).unwrap(), model.greens_functions(&long).unwrap());
    let keep = (0.09 * 24_000.0) as usize;
    for p in 0..3 {
        for k in 0..2 {
            let (x, y) = (&a.ir(p, k).unwrap()[..keep], &b.ir(p, k).unwrap()[..keep]);
            let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let err = x.iter().zip(y).fold(0.0f64, |m, (u, v)| m.max((u - v).abs()));
            assert!(err < 3e-3 * peak, "point {p} actuator {k}: error {err}, peak {peak}");
        }
    }
}

#[test]
fn cache_round_trips_and_ignores_a_corrupt_file() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let options = ModelOptions { refinement: 1, threads: 2 };
    let request = small_request(&scene, 0.05);
    let dir = std::env::temp_dir().join(format!("metaplate-plate-cache-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let computed = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "one cache file, no temporary left behind: {files:?}");
    let cached = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
    assert_eq!(computed, cached);
    // Truncate the file: it must be ignored and rewritten, not trusted.
    let bytes = std::fs::read(&files[0]).unwrap();
    std::fs::write(&files[0], &bytes[..bytes.len() / 2]).unwrap();
    assert_eq!(greens_functions(&scene, &options, &request, Some(&dir)).unwrap(), computed);
    assert_eq!(std::fs::read(&files[0]).unwrap(), bytes);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn refuses_bad_requests() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let model = PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 1 }).unwrap();
    let ok = small_request(&scene, 0.05);
    let bad = |r: GreensRequest| model.greens_functions(&r).unwrap_err();
    assert!(matches!(bad(GreensRequest { band_hz: (0.0, 400.0), ..ok.clone() }), PlateError::InvalidParameter { .. }));
    assert!(matches!(
        bad(GreensRequest { band_hz: (400.0, 300.0), ..ok.clone() }),
        PlateError::InvalidParameter { .. }
    ));
    assert!(matches!(
        bad(GreensRequest { band_hz: (300.0, 12_001.0), ..ok.clone() }),
        PlateError::InvalidParameter { .. }
    ));
    assert!(matches!(
        bad(GreensRequest { band_hz: (f64::NAN, 400.0), ..ok.clone() }),
        PlateError::InvalidParameter { .. }
    ));
    assert!(matches!(bad(GreensRequest { duration_s: 0.0, ..ok.clone() }), PlateError::InvalidParameter { .. }));
    assert!(matches!(bad(GreensRequest { sample_rate_hz: f64::INFINITY, ..ok.clone() }), PlateError::Dsp(_)));
    assert!(matches!(bad(GreensRequest { actuators: vec![8], ..ok.clone() }), PlateError::IndexOutOfRange { .. }));
    assert!(matches!(bad(GreensRequest { points: vec![0], ..ok.clone() }), PlateError::OffPlate { .. }), "corner");
    assert!(matches!(bad(GreensRequest { points: vec![], ..ok.clone() }), PlateError::InvalidParameter { .. }));
    // A lossless plate rings forever: no finite frequency grid avoids aliasing.
    let mut lossless = scene.clone();
    lossless.plate.loss_factor = 0.0;
    let m = PlateModel::from_scene(&lossless, &ModelOptions { refinement: 1, threads: 1 }).unwrap();
    assert!(matches!(m.greens_functions(&ok), Err(PlateError::InvalidParameter { name: "loss_factor", .. })));
    // Frequencies at the ends of the valid range.
    let p = &ok.points[..1];
    assert!(model.frequency_response(0.0, &[0], p).is_err());
    assert!(model.frequency_response(f64::NAN, &[0], p).is_err());
    assert!(model.frequency_response(24_000.0, &[0], p).is_ok());
    assert!(model.frequency_response(1e-3, &[0], p).is_ok());
    assert!(PlateModel::from_scene(&scene, &ModelOptions { refinement: 0, threads: 1 }).is_err());
    assert!(PlateModel::from_scene(&scene, &ModelOptions { refinement: 1, threads: 0 }).is_err());
}

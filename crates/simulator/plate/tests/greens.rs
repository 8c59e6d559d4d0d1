//! Green's functions: determinism, the no-time-aliasing rule, the cache (one entry per settings, every request cut
//! from it bit for bit), and refusals.
#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_core::scene::Scene;
use metaplate_plate::{
    EntrySettings, GreensFunctions, GreensRequest, ModelOptions, PlateError, PlateModel, SpectralPlan, cache_key,
    greens_functions, greens_functions_within,
};

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

/// A fresh scratch cache directory of this process, under the target's temporary directory.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("metaplate-plate-cache-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The samples' bit patterns (`==` on f64 would let 0.0 equal -0.0).
fn bits(g: &GreensFunctions) -> Vec<u64> {
    g.data.iter().map(|v| v.to_bits()).collect()
}

/// The cache's one file in `dir` (no temporary or claim left behind).
fn only_file(dir: &std::path::Path) -> std::path::PathBuf {
    let files: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "one entry file, nothing else: {files:?}");
    files[0].clone()
}

/// The representation word of an entry file's header (0 impulse responses, 1 band spectra; see the format).
fn representation(path: &std::path::Path) -> u64 {
    let bytes = std::fs::read(path).unwrap();
    u64::from_le_bytes(bytes[40..48].try_into().unwrap())
}

#[test]
fn every_request_is_cut_from_one_entry_bit_for_bit_as_computed_alone() {
    // The default lattice: there a sparse solve's last bits depend on how many right-hand sides it has, so this
    // also checks that every solve is made for all actuators (a request for two equals the full entry's).
    let scene = Scene::builtin("homogeneous").unwrap();
    let options = ModelOptions { refinement: 2, threads: 2 };
    let model = PlateModel::from_scene(&scene, &options).unwrap();
    let (grid_len, measured) = (scene.grid.len(), scene.measured_points());
    // At 24 kHz the entry holds band spectra (synthesised at each cut), at 800 Hz impulse responses (copied).
    for (sample_rate_hz, duration_s, stored_as) in [(24_000.0, 0.05, 1), (800.0, 0.04, 0)] {
        let dir = scratch(&format!("cut-{sample_rate_hz}"));
        let request = GreensRequest {
            // Out of order, repeated, a driving point among grid points; actuators out of order, a subset.
            points: vec![measured[500], grid_len + 3, measured[40], measured[500]],
            actuators: vec![6, 1],
            band_hz: (300.0, 400.0),
            duration_s,
            sample_rate_hz,
        };
        let direct = model.greens_functions(&request).unwrap();
        let computed = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
        let loaded = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
        assert_eq!(
            (&computed.points, &computed.actuators, computed.ir_len),
            (&direct.points, &direct.actuators, direct.ir_len)
        );
        assert_eq!(bits(&computed), bits(&direct), "{sample_rate_hz} Hz: the entry's cut equals the request alone");
        assert_eq!(bits(&loaded), bits(&direct), "{sample_rate_hz} Hz: and so does the cut from the file");
        let file = only_file(&dir);
        assert_eq!(representation(&file), stored_as, "{sample_rate_hz} Hz");
        // Another subset, all actuators: served by the same entry (no second file), still bit for bit.
        let other = GreensRequest { points: vec![measured[900], grid_len], actuators: (0..8).collect(), ..request };
        let cut = greens_functions(&scene, &options, &other, Some(&dir)).unwrap();
        assert_eq!(bits(&cut), bits(&model.greens_functions(&other).unwrap()), "{sample_rate_hz} Hz");
        assert_eq!(only_file(&dir), file);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// Whether every bin of `request`'s plan lies on one of `entry`'s, at the same frequency bit for bit.
fn bins_fall_on(model: &PlateModel, request: &GreensRequest, entry: &EntrySettings) -> bool {
    let bound = |f| model.loss_factor_bound(f);
    let plan = SpectralPlan::new(request, &bound).unwrap();
    let entry_request = GreensRequest {
        band_hz: entry.band_hz,
        duration_s: entry.duration_s,
        sample_rate_hz: entry.sample_rate_hz,
        ..request.clone()
    };
    let entry_plan = SpectralPlan::new(&entry_request, &bound).unwrap();
    plan.bins.iter().all(|&(_, f, _)| entry_plan.bins.iter().any(|&(_, g, _)| g.to_bits() == f.to_bits()))
}

#[test]
fn a_request_whose_bins_fall_on_another_entrys_is_cut_from_it_bit_for_bit() {
    // As the ground truth (2 kHz, 40 to 700 Hz) shares the mock lab's entry (24 kHz, 40 to 800 Hz): here a
    // narrower band at the entry's rate, whose FFT the same ring-down sets, so its bins are a subset of the entry's.
    let scene = Scene::builtin("homogeneous").unwrap();
    let options = ModelOptions { refinement: 1, threads: 2 };
    let model = PlateModel::from_scene(&scene, &options).unwrap();
    let entry = EntrySettings { band_hz: (300.0, 400.0), duration_s: 0.05, sample_rate_hz: 24_000.0 };
    let measured = scene.measured_points();
    let request = GreensRequest {
        points: vec![measured[700], measured[40]],
        actuators: vec![5, 2],
        band_hz: (300.0, 380.0),
        duration_s: 0.05,
        sample_rate_hz: 24_000.0,
    };
    assert!(bins_fall_on(&model, &request, &entry), "the test's premise: the request's bins are the entry's");
    let dir = scratch("within");
    let direct = model.greens_functions(&request).unwrap();
    let computed = greens_functions_within(&scene, &options, &request, &entry, Some(&dir)).unwrap();
    assert_eq!(bits(&computed), bits(&direct), "cut on the request's own plan: as computed alone");
    assert_eq!(computed.ir_len, direct.ir_len);
    let file = only_file(&dir);
    assert_eq!(representation(&file), 1, "the entry holds band spectra");
    // The entry is the one its own settings key: a request with them is served by the same file.
    let own = GreensRequest { band_hz: entry.band_hz, ..request.clone() };
    let from_entry = greens_functions(&scene, &options, &own, Some(&dir)).unwrap();
    assert_eq!(bits(&from_entry), bits(&model.greens_functions(&own).unwrap()));
    let loaded = greens_functions_within(&scene, &options, &request, &entry, Some(&dir)).unwrap();
    assert_eq!(bits(&loaded), bits(&direct), "and again from the file");
    assert_eq!(only_file(&dir), file, "no second entry");
    // Bins that do not fall on the entry's (a duration that sets a longer FFT): an entry of the request's own.
    let other = GreensRequest { duration_s: 0.5, ..request };
    assert!(!bins_fall_on(&model, &other, &entry), "the premise: another grid");
    let got = greens_functions_within(&scene, &options, &other, &entry, Some(&dir)).unwrap();
    assert_eq!(bits(&got), bits(&model.greens_functions(&other).unwrap()));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2, "the entry and the request's own");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cache_round_trips_and_ignores_a_truncated_damaged_or_stale_file() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let options = ModelOptions { refinement: 1, threads: 2 };
    let request = small_request(&scene, 0.05);
    let dir = scratch("round-trip");
    let computed = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
    let file = only_file(&dir);
    let cached = greens_functions(&scene, &options, &request, Some(&dir)).unwrap();
    assert_eq!(computed, cached);
    let bytes = std::fs::read(&file).unwrap();
    // Truncated, a flipped bit in a block (the last one: not necessarily a requested point's, so look the whole
    // entry up), a flipped bit in the header, another format's file: each is ignored and the entry rewritten.
    let mut damaged_block = bytes.clone();
    *damaged_block.last_mut().unwrap() ^= 0x10;
    let mut damaged_header = bytes.clone();
    damaged_header[80] ^= 0x01; // the first bin's frequency: only the header's checksum tells
    let mut stale = bytes.clone();
    stale[..8].copy_from_slice(b"MPGREEN1");
    let mut all_points = scene.measured_points();
    all_points.extend((0..scene.actuators.len()).map(|k| scene.grid.len() + k));
    let everything = GreensRequest { points: all_points, ..request.clone() };
    for (what, content) in [
        ("truncated", &bytes[..bytes.len() / 2]),
        ("damaged block", &damaged_block[..]),
        ("damaged header", &damaged_header[..]),
        ("stale format", &stale[..]),
    ] {
        std::fs::write(&file, content).unwrap();
        let got = greens_functions(&scene, &options, &everything, Some(&dir)).unwrap();
        assert!(got.data.iter().all(|v| v.is_finite()), "{what}");
        assert_eq!(std::fs::read(&file).unwrap(), bytes, "{what}: the entry is rewritten whole");
        assert_eq!(greens_functions(&scene, &options, &request, Some(&dir)).unwrap(), computed, "{what}");
    }
    // The key ignores the points and actuators, and nothing else of the request.
    let key = |r: &GreensRequest| cache_key(scene.physics_hash(), &options, r);
    assert_eq!(key(&request), key(&GreensRequest { points: vec![1], actuators: vec![0], ..request.clone() }));
    assert_ne!(key(&request), key(&GreensRequest { duration_s: 0.06, ..request.clone() }));
    assert_ne!(key(&request), key(&GreensRequest { band_hz: (300.0, 401.0), ..request.clone() }));
    assert_ne!(key(&request), key(&GreensRequest { sample_rate_hz: 48_000.0, ..request.clone() }));
    assert_ne!(key(&request), cache_key(scene.physics_hash(), &ModelOptions { refinement: 2, ..options }, &request));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_request_the_model_refuses_is_refused_through_the_cache_too() {
    let scene = Scene::builtin("homogeneous").unwrap();
    let options = ModelOptions { refinement: 1, threads: 2 };
    let ok = small_request(&scene, 0.05);
    let dir = scratch("refuse");
    // Before the entry exists (refused before any computation: no file) and once it does.
    for stored in [false, true] {
        let bad = |r: GreensRequest| greens_functions(&scene, &options, &r, Some(&dir)).unwrap_err();
        assert!(matches!(bad(GreensRequest { points: vec![0], ..ok.clone() }), PlateError::OffPlate { .. }), "corner");
        assert!(matches!(bad(GreensRequest { actuators: vec![8], ..ok.clone() }), PlateError::IndexOutOfRange { .. }));
        assert!(matches!(
            bad(GreensRequest { points: vec![scene.grid.len() + 8], ..ok.clone() }),
            PlateError::IndexOutOfRange { .. }
        ));
        assert!(matches!(bad(GreensRequest { points: vec![], ..ok.clone() }), PlateError::InvalidParameter { .. }));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), usize::from(stored));
        if !stored {
            greens_functions(&scene, &options, &ok, Some(&dir)).unwrap();
        }
    }
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

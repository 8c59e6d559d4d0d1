//! Multi-pixel control on the metamaterial plate's ground truth (paper Fig. 7): five pixels with distinct targets
//! (impulse, sine, noise, wavelet train, null), each active pixel's predicted waveform against its target, and the
//! nulled pixel's suppression; plus the single-pixel focal-field GEMM against the general solve.
//!
//! Ground truth: the plate model's Green's functions at every measured point, 8 actuators, 0.5 s at 2 kHz (the band
//! 75 to 400 Hz is far below 1 kHz), cached under the target directory with the same request as the analysis
//! crate's tests, so one cache serves all.

#![allow(clippy::unwrap_used)] // tests may unwrap

use metaplate_control::PropagationMatrices;
use metaplate_control::focal::single_pixel_focal_fields;
use metaplate_control::render::{FocusOptions, predicted_field, solve_drives};
use metaplate_control::target::{PixelTarget, Waveform, band_signal, spectrum};
use metaplate_core::scene::Scene;
use metaplate_ground_truth::{GroundTruth, GroundTruthOptions};

/// The metamaterial plate's compensated ground truth over the operating band.
fn ground_truth() -> (Scene, PropagationMatrices) {
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    let truth = GroundTruth::builtin("metamaterial", &GroundTruthOptions::default(), Some(&cache)).unwrap();
    let g = truth.propagation((75.0, 400.0)).unwrap();
    (truth.scene, g)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    dot / (a.iter().map(|x| x * x).sum::<f64>() * b.iter().map(|y| y * y).sum::<f64>()).sqrt()
}

#[test]
fn five_pixels_follow_five_targets_and_the_null_is_suppressed() {
    let (scene, g) = ground_truth();
    // Five pixels about 3.5 cm apart around the centre (the paper's fingertips are 3.2 cm apart).
    let at = |ix: usize, iy: usize| scene.grid.index(ix, iy) as u32;
    let waveforms = [
        Waveform::Impulse { time_s: 0.25 },
        Waveform::Sine { freq_hz: 200.0, start_s: 0.1, duration_s: 0.3 },
        Waveform::Noise { start_s: 0.1, duration_s: 0.3, seed: 7 },
        Waveform::WaveletTrain { freq_hz: 250.0, cycles: 5.0, times_s: vec![0.15, 0.3, 0.35] },
        Waveform::Null,
    ];
    let pixels = [at(24, 12), at(17, 12), at(31, 12), at(20, 18), at(28, 6)];
    let targets: Vec<PixelTarget> = pixels
        .iter()
        .zip(waveforms)
        .map(|(&point_index, waveform)| PixelTarget { point_index, waveform, amplitude: 1.0 })
        .collect();
    let options = FocusOptions::default();
    let drives = solve_drives(&g, &targets, &options).unwrap();
    let rows: Vec<usize> = pixels.iter().map(|&p| g.row_of(p).unwrap()).collect();
    let field = predicted_field(&g, &drives, Some(&rows), 1.0).unwrap();
    let gains = options.target_band.gains(&g).unwrap();
    let mut active_rms = Vec::new();
    for (target, v) in targets.iter().zip(&field).take(4) {
        let wanted = band_signal(&spectrum(target, &g, &gains).unwrap(), &g).unwrap();
        let r = correlation(v, &wanted);
        eprintln!("{:?}: correlation {r:.4}, rms {:.3e} (target {:.3e})", target.waveform, rms(v), rms(&wanted));
        // The bound: 0.9. Five pixels on eight actuators leave three spare degrees of freedom per bin; the
        // miss is the regularisation's (the default alpha, 0.005 s_max) and the band edges'.
        assert!(r >= 0.9, "{:?}: correlation {r}", target.waveform);
        active_rms.push(rms(v));
    }
    let null_rms = rms(&field[4]);
    let weakest = active_rms.iter().copied().fold(f64::INFINITY, f64::min);
    let suppression_db = 20.0 * (weakest / null_rms).log10();
    eprintln!("null pixel: rms {null_rms:.3e}, {suppression_db:.1} dB below the weakest active pixel");
    // The bound: 20 dB below every active pixel (RMS over the period). Measured 31.4 dB; the null's leak is
    // the regularisation's (19.9 dB at alpha = 0.01 s_max, 40 dB at 0.003).
    assert!(suppression_db >= 20.0, "null only {suppression_db:.1} dB down");
}

#[test]
fn the_focal_field_gemm_agrees_with_the_general_solve_at_focus_time() {
    let (scene, g) = ground_truth();
    let options = FocusOptions::default();
    let gains = options.target_band.gains(&g).unwrap();
    let target_rows: Vec<usize> =
        [scene.grid.index(24, 12), scene.grid.index(10, 8)].iter().map(|&p| g.row_of(p as u32).unwrap()).collect();
    let fields =
        single_pixel_focal_fields(&g, &target_rows, &gains, options.regularisation, options.method, 2).unwrap();
    let time_s = 0.25;
    let sample = (time_s * g.sample_rate_hz()).round() as usize;
    for (t, &row) in target_rows.iter().enumerate() {
        // The focal fields are per unit target gain (band-limited impulse of spectrum `gains`, not peak-normalised);
        // the general solve's impulse is normalised to peak 1, so compare shapes through the ratio at the target.
        let target =
            PixelTarget { point_index: g.points()[row], waveform: Waveform::Impulse { time_s }, amplitude: 1.0 };
        let drives = solve_drives(&g, std::slice::from_ref(&target), &options).unwrap();
        let v = predicted_field(&g, &drives, None, 1.0).unwrap();
        let at_focus: Vec<f64> = v.iter().map(|x| x[sample]).collect();
        let gemm = fields.field(t).unwrap();
        let scale = at_focus[row] / gemm[row];
        let max = gemm.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let worst = gemm.iter().zip(&at_focus).map(|(a, b)| (a * scale - b).abs()).fold(0.0, f64::max) / (max * scale);
        // Same arithmetic by two routes (closed form in a GEMM against SVD solve plus inverse FFT): agreement to
        // 1e-9 of the field's peak is far above f64 rounding over ~1300 bins and far below any formula error.
        assert!(worst < 1e-9, "target {row}: mismatch {worst:e} of the peak");
    }
}

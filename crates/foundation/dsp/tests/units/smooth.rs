#![allow(clippy::unwrap_used)]

use metaplate_dsp::error::DspError;
use metaplate_dsp::fft;
use num_complex::Complex64;

use metaplate_dsp::smooth::*;

#[test]
fn smoothing_keeps_a_flat_spectrum_and_averages_a_notch_away() {
    let n = 4096;
    let bins = fft::bin_count(n);
    let flat = vec![2.0; bins];
    for fraction in [1.0, 3.0, 24.0] {
        let s = fractional_octave_power(&flat, n, 24_000.0, fraction).unwrap();
        assert!(s.iter().all(|v| (v - 2.0).abs() < 1e-12), "a flat spectrum stays flat");
    }
    // A one-bin notch at bin 1000, where the triangle (weight 1 at its peak) spans bins 794..=1259: the notch
    // costs 1 / (sum of the weights), some 1/233 of the power (-0.02 dB); unsmoothed it is -inf dB.
    let mut notched = vec![1.0; bins];
    notched[1000] = 0.0;
    let s = fractional_octave_power(&notched, n, 24_000.0, 3.0).unwrap();
    let (left, right) = (1000.0 / 2f64.powf(1.0 / 3.0), 1000.0 * 2f64.powf(1.0 / 3.0));
    let weights: f64 = (1..bins)
        .map(|j| j as f64)
        .map(|j| if j <= 1000.0 { (j - left) / (1000.0 - left) } else { (right - j) / (right - 1000.0) })
        .filter(|w| *w > 0.0)
        .sum();
    assert!((220.0..250.0).contains(&weights), "{weights}");
    assert!((s[1000] - (1.0 - 1.0 / weights)).abs() < 1e-12, "{} against {}", s[1000], 1.0 - 1.0 / weights);
    // A strong narrow mode (100 times the floor at bin 1000) enters and leaves the windows of the bins around
    // it without a step: neighbouring bins' smoothed levels differ by at most one triangle-weight increment,
    // 100 / (k - left) / 233 < 0.01 of the floor, where a rectangle would step by 100 / 233 = 0.43.
    let mut mode = vec![1.0; bins];
    mode[1000] = 101.0;
    let s = fractional_octave_power(&mode, n, 24_000.0, 3.0).unwrap();
    let largest_step = s[700..1400].windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
    assert!(largest_step < 0.01, "{largest_step}");
    // A response that is 1 over 500..2000 Hz and 0 outside: smoothed within that band it stays exactly 1 up to
    // both edges; smoothed plainly, the edges fall to about half (the triangle's half outside the band).
    let boxed: Vec<f64> = (0..bins)
        .map(|k| if (500.0..=2000.0).contains(&(k as f64 * 24_000.0 / n as f64)) { 1.0 } else { 0.0 })
        .collect();
    let inside = fractional_octave_power_in_band(&boxed, n, 24_000.0, 3.0, (500.0, 2000.0)).unwrap();
    let plain = fractional_octave_power(&boxed, n, 24_000.0, 3.0).unwrap();
    let edge = (2000.0 * n as f64 / 24_000.0) as usize;
    assert!((86..=edge).all(|k| (inside[k] - 1.0).abs() < 1e-12), "in-band smoothing keeps the band flat");
    assert!((0.4..0.6).contains(&plain[edge]), "{}", plain[edge]);
    // The extremes: bin 0 is kept; the top bin averages only what lies below it.
    assert_eq!(s[0], 1.0);
    assert!((s[bins - 1] - 1.0).abs() < 1e-12);
}

#[test]
fn smoothing_refuses_bad_arguments() {
    let p = vec![1.0; 5];
    assert!(matches!(fractional_octave_power(&p, 16, 1.0, 3.0), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(fractional_octave_power(&p, 8, 1.0, 0.5), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(fractional_octave_power(&p, 8, 0.0, 3.0), Err(DspError::InvalidParameter { .. })));
    let neg = [1.0, -1.0, 1.0, 1.0, 1.0];
    assert!(matches!(fractional_octave_power(&neg, 8, 1.0, 3.0), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(minimum_phase_response(&[1.0; 5], 8, 2, 2), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(minimum_phase_response(&[1.0; 5], 8, 12, 2), Err(DspError::InvalidParameter { .. })));
    assert!(minimum_phase_response(&[0.0; 5], 8, 4, 0).is_err(), "all zero: no magnitude to give a phase");
    assert!(fractional_octave_power_in_band(&p, 8, 1.0, 3.0, (0.4, 0.1)).is_err(), "band upside down");
}

#[test]
fn a_smooth_minimum_phase_response_comes_back_unchanged() {
    // A one-pole low-pass (minimum phase, smooth magnitude) with 16 pre-samples: smoothing over a 24th of an
    // octave barely changes its magnitude, and its minimum phase is its own phase.
    let pre = 16;
    let mut ir = vec![0.0; 2048];
    for (i, v) in ir[pre..].iter_mut().enumerate() {
        *v = 0.1 * 0.9f64.powi(i as i32);
    }
    let n = fft::fast_len(2 * ir.len()).unwrap();
    let power: Vec<f64> = fft::forward(&ir, n).unwrap().iter().map(Complex64::norm_sqr).collect();
    let smoothed = fractional_octave_power(&power, n, 24_000.0, 24.0).unwrap();
    let magnitude: Vec<f64> = smoothed.iter().map(|p| p.sqrt()).collect();
    let out = minimum_phase_response(&magnitude, n, ir.len(), pre).unwrap();
    assert!(out[..pre].iter().all(|v| *v == 0.0));
    let error: f64 = out.iter().zip(&ir).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
    let energy: f64 = ir.iter().map(|v| v * v).sum();
    // Smoothing a 1/(1 - 0.9 z^-1) magnitude over 1/24 octave changes it by under 0.1 % where it matters.
    assert!(error / energy < 1e-4, "relative error energy {}", error / energy);
}

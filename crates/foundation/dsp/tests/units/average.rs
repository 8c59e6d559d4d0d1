use metaplate_core::rng::SplitMix64;
use metaplate_dsp::error::DspError;
use num_complex::Complex64;

use metaplate_dsp::average::*;

#[test]
fn mean_of_exact_repetitions_is_the_signal_and_snr_is_unbounded() {
    let x = [1.0, -2.0, 0.5];
    let avg = average(&[&x, &x, &x]).unwrap();
    assert_eq!(avg.mean, x.to_vec());
    assert_eq!(avg.noise_energy, Some(0.0));
    assert_eq!(avg.snr_db(), None);
}

#[test]
fn one_repetition_gives_the_mean_and_no_snr() {
    let avg = average(&[&[3.0, 4.0]]).unwrap();
    assert_eq!(avg.mean, vec![3.0, 4.0]);
    assert_eq!(avg.noise_energy, None);
    assert_eq!(avg.snr_db(), None);
}

#[test]
fn noise_and_snr_estimates_match_the_truth() {
    // 8 repetitions of 20 000 samples: the noise estimate has 7 * 20 000 degrees of freedom, a relative standard
    // deviation of sqrt(2 / 140 000) = 0.4 %; 3 % (0.13 dB) is over 7 sigma.
    let mut rng = SplitMix64::new(7, 0);
    let n = 20_000;
    let signal: Vec<f64> = (0..n).map(|i| (i as f64 * 0.01).sin()).collect();
    let sigma = 0.3;
    let reps: Vec<Vec<f64>> = (0..8).map(|_| signal.iter().map(|s| s + sigma * rng.normal()).collect()).collect();
    let refs: Vec<&[f64]> = reps.iter().map(Vec::as_slice).collect();
    let avg = average(&refs).unwrap();
    let true_noise = sigma * sigma * n as f64 / 8.0;
    let true_signal: f64 = signal.iter().map(|s| s * s).sum();
    let noise = avg.noise_energy.unwrap();
    assert!((noise / true_noise - 1.0).abs() < 0.03, "noise {noise} vs {true_noise}");
    let true_snr = 10.0 * (true_signal / true_noise).log10();
    let snr = avg.snr_db().unwrap();
    assert!((snr - true_snr).abs() < 0.15, "snr {snr} vs {true_snr}");
    // The mean is closer to the signal than any repetition: its error energy is the noise energy left in it.
    let err: f64 = avg.mean.iter().zip(&signal).map(|(m, s)| (m - s).powi(2)).sum();
    assert!((err / true_noise - 1.0).abs() < 0.05, "error {err} vs {true_noise}");
}

#[test]
fn weights_follow_inverse_noise_variance() {
    // Two repetitions, the second with 4x the noise variance: weights 1 and 1/4. The residual-based estimate is
    // unbiased for the unit-weight variance; averaged over 200 trials of 1000 samples its relative standard
    // deviation is about sqrt(2 / 200 000) = 0.3 %; 3 % is 10 sigma.
    let mut rng = SplitMix64::new(3, 0);
    let n = 1000;
    let mut ratio_sum = 0.0;
    let trials = 200;
    for _ in 0..trials {
        let a: Vec<f64> = (0..n).map(|_| (rng.uniform() * 2.0 - 1.0) * 3f64.sqrt()).collect();
        let b: Vec<f64> = (0..n).map(|_| (rng.uniform() * 2.0 - 1.0) * 2.0 * 3f64.sqrt()).collect();
        let avg = weighted_average(&[&a, &b], &[1.0, 0.25]).unwrap();
        // Noise energy in the mean: n * 1 / W with unit variance for weight 1, W = 1.25.
        ratio_sum += avg.noise_energy.unwrap() / (n as f64 / 1.25);
        assert!((avg.mean[0] - (a[0] + 0.25 * b[0]) / 1.25).abs() < 1e-12);
    }
    let ratio = ratio_sum / trials as f64;
    assert!((ratio - 1.0).abs() < 0.03, "mean ratio {ratio}");
}

#[test]
fn spectra_count_only_the_band() {
    // Noise only in bin 1 (outside the band, gain 0): the in-band noise is zero, the SNR unbounded.
    let a = [Complex64::new(1.0, 0.0), Complex64::new(5.0, 1.0)];
    let b = [Complex64::new(1.0, 0.0), Complex64::new(-5.0, 2.0)];
    let avg = average_spectra(&[&a, &b], &[1.0, 1.0], Some(&[1.0, 0.0])).unwrap();
    assert_eq!(avg.noise_energy, Some(0.0));
    assert_eq!(avg.signal_energy, Some(1.0));
    assert_eq!(avg.mean[1], Complex64::new(0.0, 1.5));
    let all = average_spectra(&[&a, &b], &[1.0, 1.0], None).unwrap();
    // Spread: each differs from the mean by (+-5, -+0.5): energy 25.25 each, sum 50.5, / (K-1) / W = 25.25.
    assert!((all.noise_energy.unwrap() - 25.25).abs() < 1e-12);
}

#[test]
fn pure_noise_has_no_snr() {
    let a = [1.0, -1.0, 1.0, -1.0];
    let b = [-1.0, 1.0, -1.0, 1.0];
    let avg = average(&[&a, &b]).unwrap();
    assert_eq!(avg.signal_energy, Some(0.0));
    assert_eq!(avg.snr_db(), None);
}

#[test]
fn extremes_of_magnitude() {
    // Tiny and huge (but not overflowing) samples average exactly; squares that overflow are an error.
    let tiny = [1e-300, -1e-300];
    assert_eq!(average(&[&tiny, &tiny]).unwrap().mean, tiny.to_vec());
    let big = [1e150, -1e150];
    assert!(average(&[&big, &big]).is_ok());
    let huge = [1e200, -1e200];
    let other = [-1e200, 1e200];
    assert!(matches!(average(&[&huge, &other]), Err(DspError::NonFiniteResult { .. })));
}

#[test]
fn refuses_bad_input() {
    assert!(matches!(average(&[]), Err(DspError::Empty { .. })));
    assert!(matches!(average(&[&[], &[]]), Err(DspError::Empty { .. })));
    assert!(matches!(average(&[&[1.0], &[1.0, 2.0]]), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(average(&[&[1.0], &[f64::NAN]]), Err(DspError::NonFinite { .. })));
    assert!(matches!(weighted_average(&[&[1.0]], &[0.0]), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(weighted_average(&[&[1.0]], &[1.0, 1.0]), Err(DspError::LengthMismatch { .. })));
    let c = [Complex64::new(1.0, 0.0)];
    assert!(matches!(average_spectra(&[&c], &[1.0], Some(&[1.0, 1.0])), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(average_spectra(&[&c], &[1.0], Some(&[-1.0])), Err(DspError::InvalidParameter { .. })));
}

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_dsp::fft;

use metaplate_dsp::noise::*;

/// Gaussian white noise from a fixed-seed generator (Box-Muller over SplitMix64).
fn white(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = metaplate_core::rng::SplitMix64::new(seed, 0x9e11);
    (0..n).map(|_| rng.normal()).collect()
}

/// Mean power spectral density over `[lo, hi)` Hz of `x`, from its periodogram.
fn band_power(x: &[f64], rate_hz: f64, lo: f64, hi: f64) -> f64 {
    let s = fft::forward(x, x.len()).unwrap();
    let bins: Vec<f64> = (0..s.len())
        .filter(|&k| (lo..hi).contains(&fft::bin_freq_hz(k, x.len(), rate_hz)))
        .map(|k| s[k].norm_sqr())
        .collect();
    bins.iter().sum::<f64>() / bins.len() as f64
}

#[test]
fn the_spectrum_falls_3_db_per_octave_and_the_rms_is_as_asked() {
    let rate_hz = 48_000.0;
    let pink = pink_noise(&white(1 << 17, 7), rate_hz, (20.0, 20_000.0), 0.1).unwrap();
    let rms = (pink.iter().map(|v| v * v).sum::<f64>() / pink.len() as f64).sqrt();
    assert!((rms - 0.1).abs() < 1e-12, "{rms}");
    // Octaves from 62.5 Hz to 16 kHz: each octave's mean PSD is half the one below (-3.01 dB). The lowest
    // octave averages 171 periodogram bins (0.37 Hz apart) of exponentially distributed power, so its mean
    // scatters by 1/sqrt(171) = 7.6 % (0.33 dB), a difference of two octaves by 0.4 dB at most: 1.5 dB is
    // almost four of those. The slope fitted over the eight octaves averages them: 0.2 dB.
    let octaves: Vec<f64> = (0..8).map(|k| 62.5 * 2f64.powi(k)).collect();
    let db: Vec<f64> = octaves.iter().map(|&lo| 10.0 * band_power(&pink, rate_hz, lo, 2.0 * lo).log10()).collect();
    for (k, w) in db.windows(2).enumerate() {
        assert!((w[1] - w[0] + 3.01).abs() < 1.5, "octave {k}: {db:?}");
    }
    let (n, mean_x) = (db.len() as f64, (db.len() - 1) as f64 / 2.0);
    let mean_y = db.iter().sum::<f64>() / n;
    let slope = db.iter().enumerate().map(|(k, y)| (k as f64 - mean_x) * (y - mean_y)).sum::<f64>()
        / db.iter().enumerate().map(|(k, _)| (k as f64 - mean_x).powi(2)).sum::<f64>();
    assert!((slope + 3.01).abs() < 0.2, "{slope} dB per octave: {db:?}");
    // Nothing outside the band.
    assert!(band_power(&pink, rate_hz, 0.0, 19.0) < 1e-20);
    assert!(band_power(&pink, rate_hz, 20_001.0, 24_001.0) < 1e-20);
}

#[test]
fn the_extremes_give_finite_noise_or_a_named_error() {
    // Two samples at 48 kHz: bin 1 is Nyquist, inside a band reaching it; the result alternates at the RMS.
    let two = pink_noise(&[1.0, 0.0], 48e3, (10_000.0, 30_000.0), 0.5).unwrap();
    assert!((two[0].abs() - 0.5).abs() < 1e-12 && (two[0] + two[1]).abs() < 1e-12, "{two:?}");
    // A band above the whole spectrum of a long, loud noise: still finite, at the RMS asked.
    let loud: Vec<f64> = white(4096, 3).iter().map(|v| v * 1e150).collect();
    let shaped = pink_noise(&loud, 48e3, (23_000.0, 24_000.0), 1e-6).unwrap();
    assert!(shaped.iter().all(|v| v.is_finite()));
    for (white, rate, band, rms, needle) in [
        (vec![1.0], 48e3, (20.0, 2e4), 0.1, "at least 2 samples"),
        (vec![1.0, f64::NAN], 48e3, (20.0, 2e4), 0.1, "non-finite"),
        (vec![1.0, 0.5], 0.0, (20.0, 2e4), 0.1, "sample_rate_hz"),
        (vec![1.0, 0.5], 48e3, (0.0, 2e4), 0.1, "band_hz"),
        (vec![1.0, 0.5], 48e3, (2e4, 20.0), 0.1, "band_hz"),
        (vec![1.0, 0.5], 48e3, (20.0, 2e4), f64::INFINITY, "rms"),
        // 4 samples at 48 kHz: bins at 0, 12 and 24 kHz; none between 1 and 10 kHz.
        (vec![1.0, 0.5, 0.2, 0.1], 48e3, (1e3, 1e4), 0.1, "holds no frequency bin"),
        (vec![0.0; 8], 48e3, (20.0, 2e4), 0.1, "no energy"),
    ] {
        let err = pink_noise(&white, rate, band, rms).unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
    }
}

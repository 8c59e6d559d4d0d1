//! The truth as a scan's window keeps it (`MockLab::windowed_truth`): the full truth for a response the window holds,
//! short of it by exactly the tail's energy for one the window cuts, and the same full truth as
//! `MockLab::response_error_db` evaluates by its DTFT.

#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use crate::common;

use metaplate_dsp::accuracy::ERROR_BAND_HZ;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::fft;
use metaplate_lab::MockLab;
use metaplate_lab::windowed_truth::{Truth, WindowedTruth};

/// The paper's deconvolution band (62..625 Hz, skirts to 42 and 675 Hz) on a window of `ir_len` samples, `pre` of
/// them before time 0.
fn window(ir_len: usize, pre: usize) -> DeconvConfig {
    DeconvConfig { ir_len, pre_samples: pre, ..DeconvConfig::paper() }
}

/// The response's samples at times `-pre..n - pre` (on the long circle), time 0 first: what a perfect measurement
/// of the window returns, in the form `time_zero_first` gives.
fn cut(truth: &WindowedTruth, n: usize, pre: usize) -> Vec<f64> {
    let r = truth.response();
    let at = |t: isize| r[t.rem_euclid(r.len() as isize) as usize];
    (0..n).map(|i| at(if i < n - pre { i as isize } else { i as isize - n as isize })).collect()
}

/// The response's samples with their signed times (the long circle's second half before time 0).
fn signed(truth: &WindowedTruth) -> impl Iterator<Item = (isize, f64)> + '_ {
    let r = truth.response();
    let len = r.len() as isize;
    r.iter().enumerate().map(move |(i, &v)| (if (i as isize) < len / 2 { i as isize } else { i as isize - len }, v))
}

/// Energy of `x`'s FFT bins (its own length, 24 kHz) within `band_hz`, as the error measure sums them.
fn band_energy(x: &[f64], band_hz: (f64, f64)) -> f64 {
    let spectrum = fft::forward(x, x.len()).unwrap();
    (0..spectrum.len())
        .filter(|&k| (band_hz.0..=band_hz.1).contains(&fft::bin_freq_hz(k, x.len(), 24_000.0)))
        .map(|k| spectrum[k].norm_sqr())
        .sum()
}

/// The response folded modulo `period` samples (index `t mod period` for signed time `t`).
fn fold(truth: &WindowedTruth, period: usize) -> Vec<f64> {
    let mut f = vec![0.0; period];
    for (t, v) in signed(truth) {
        f[t.rem_euclid(period as isize) as usize] += v;
    }
    f
}

/// A perfect measurement of the window (its samples of the response, actuator 2): nothing against the windowed
/// truth (the same samples, so rounding only), and against the full truth the error `response_error_db` finds by
/// the DTFT, an independent path to the same numbers (only rounding differs, far below 1e-6 dB); returns that
/// error over [`ERROR_BAND_HZ`], dB.
fn perfect_measurement(lab: &MockLab, point: usize, truth: &WindowedTruth, n: usize, pre: usize) -> f64 {
    let perfect = cut(truth, n, pre);
    let windowed = truth.error_db(&perfect, Truth::Windowed, ERROR_BAND_HZ).unwrap();
    assert!(windowed < -250.0, "against the windowed truth {windowed} dB");
    let full = truth.error_db(&perfect, Truth::Full, ERROR_BAND_HZ).unwrap();
    let by_dtft = lab.response_error_db(point, 2, &perfect, 24_000.0, ERROR_BAND_HZ, None).unwrap();
    assert!((full - by_dtft).abs() < 1e-6, "full truth {full} dB, by the DTFT {by_dtft} dB");
    full
}

#[test]
fn a_response_the_window_holds_is_the_full_truth() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let point = common::point(&scene);
    // The test lab's Green's functions last 0.25 s: 0.75 s after time 0 and 0.25 s before it hold them and the
    // band limit's smear (its 20 Hz skirt's ringing falls as 1/t^3 after a few 50 ms periods).
    let (n, pre) = (24_000, 6_000);
    let truth = lab.windowed_truth(point, 2, &window(n, pre), None, None).unwrap();
    let truncation = truth.truncation_db(ERROR_BAND_HZ).unwrap();
    assert!(truncation < -100.0, "truncation {truncation} dB");
    // A perfect measurement of the window is the windowed truth, and its error against the full truth the truncation.
    let full = perfect_measurement(&lab, point, &truth, n, pre);
    assert!((full - truncation).abs() < 1e-6, "full truth {full} dB, truncation {truncation} dB");
}

#[test]
fn a_window_that_cuts_the_response_loses_its_tail_energy() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let point = common::point(&scene);
    // 0.146 s after time 0 of a 0.25 s response: the window cuts its tail.
    let (n, pre) = (4_000, 500);
    let truth = lab.windowed_truth(point, 2, &window(n, pre), None, None).unwrap();
    // On the window's bins the full truth is the response folded modulo the window, so the windowed truth misses
    // exactly the part outside it, folded the same way: the tail (and the band limit's smear before -500).
    let mut tail = vec![0.0; n];
    for (t, v) in signed(&truth) {
        if !(-(pre as isize)..(n - pre) as isize).contains(&t) {
            tail[t.rem_euclid(n as isize) as usize] += v;
        }
    }
    // Where the band limit's gain is 1 (62..625 Hz) the full truth is not band-limited by it either: there the
    // truncation is that folded tail's energy relative to the folded response's, bin by bin (rounding only).
    let unity_hz = (62.0, 625.0);
    let expected_db = 10.0 * (band_energy(&tail, unity_hz) / band_energy(&fold(&truth, n), unity_hz)).log10();
    assert!(expected_db > -60.0, "the window should cut a sizeable tail: {expected_db} dB");
    let truncation = truth.truncation_db(unity_hz).unwrap();
    assert!((truncation - expected_db).abs() < 1e-6, "truncation {truncation} dB, tail energy {expected_db} dB");
    // A perfect measurement of the window misses the truncation against the full truth.
    let full = perfect_measurement(&lab, point, &truth, n, pre);
    let in_band = truth.truncation_db(ERROR_BAND_HZ).unwrap();
    assert!((full - in_band).abs() < 1e-9, "full {full} dB, truncation {in_band} dB");
}

#[test]
fn a_period_shorter_than_the_response_wraps_its_tail() {
    let scene = common::scene(vec![], true);
    let lab = common::lab(&scene, None);
    let point = common::point(&scene);
    let (n, pre) = (3_000, 500);
    // A period far longer than the response wraps nothing (only the band limit's far smear, below -100 dB) ...
    let long = lab.windowed_truth(point, 2, &window(n, pre), Some(48_000), None).unwrap();
    let none = long.aliasing_db(ERROR_BAND_HZ).unwrap();
    assert!(none < -100.0, "aliasing {none} dB with a 2 s period");
    // ... one of 0.15 s wraps the 0.25 s response's samples from 3100 on (the period less the 500 kept before time
    // 0) onto the window. The periodic truth is the response folded modulo the period, then cut to the window: the
    // aliasing is the spectral energy that folding adds to the window's samples, relative to theirs.
    let period = 3_600;
    let short = lab.windowed_truth(point, 2, &window(n, pre), Some(period), None).unwrap();
    let (folded, kept) = (fold(&short, period), cut(&short, n, pre));
    let at = |t: isize| folded[t.rem_euclid(period as isize) as usize];
    let added: Vec<f64> =
        (0..n).map(|i| at(if i < n - pre { i as isize } else { i as isize - n as isize }) - kept[i]).collect();
    let whole_hz = (0.0, 12_000.0);
    let expected_db = 10.0 * (band_energy(&added, whole_hz) / band_energy(&kept, whole_hz)).log10();
    assert!(expected_db > -70.0, "the period should wrap a sizeable tail: {expected_db} dB");
    let aliasing = short.aliasing_db(whole_hz).unwrap();
    assert!((aliasing - expected_db).abs() < 1e-6, "aliasing {aliasing} dB, wrapped energy {expected_db} dB");
    let perfect = cut(&short, n, pre);
    let against_windowed = short.error_db(&perfect, Truth::Windowed, ERROR_BAND_HZ).unwrap();
    assert!(against_windowed < -250.0, "{against_windowed} dB");
    assert!(lab.windowed_truth(point, 2, &window(n, pre), Some(n - 1), None).is_err(), "a period under the window");
}

use metaplate_dsp::error::DspError;
use metaplate_dsp::window::*;

// Rounding of cos() near multiples of pi: a few ulps, 1e-15 is safe and still catches any formula slip.
const TOL: f64 = 1e-15;

fn assert_symmetric(w: &[f64]) {
    let n = w.len();
    for i in 0..n {
        assert!((w[i] - w[n - 1 - i]).abs() <= TOL, "w[{i}] = {} vs w[{}] = {}", w[i], n - 1 - i, w[n - 1 - i]);
    }
}

#[test]
fn tiny_lengths() {
    for sym in [Symmetry::Symmetric, Symmetry::Periodic] {
        assert!(hann(0, sym).is_empty());
        assert!(blackman(0, sym).is_empty());
        assert_eq!(hann(1, sym), vec![1.0]);
        assert_eq!(blackman(1, sym), vec![1.0]);
    }
    assert_eq!(hann(2, Symmetry::Symmetric), vec![0.0, 0.0]);
    let p = hann(2, Symmetry::Periodic);
    assert!(p[0].abs() <= TOL && (p[1] - 1.0).abs() <= TOL);
    assert!(tukey(0, 0.5).unwrap().is_empty());
    assert_eq!(tukey(1, 0.5).unwrap(), vec![1.0]);
    assert_eq!(tukey(2, 1.0).unwrap(), vec![0.0, 0.0]);
    assert!(fade_in(0).is_empty());
    assert_eq!(fade_in(1), vec![0.0]);
    assert_eq!(fade_out(1), vec![0.0]);
    let f = fade_in(2);
    assert!(f[0] == 0.0 && (f[1] - 0.5).abs() <= TOL);
}

#[test]
fn symmetric_windows_are_symmetric_with_zero_ends_and_unit_middle() {
    for n in [3usize, 4, 5, 64, 65, 1001] {
        for w in [hann(n, Symmetry::Symmetric), blackman(n, Symmetry::Symmetric), tukey(n, 0.3).unwrap()] {
            assert_eq!(w.len(), n);
            assert_symmetric(&w);
            assert!(w[0].abs() <= TOL, "n = {n}: end {}", w[0]);
            assert!(w.iter().all(|v| (-TOL..=1.0 + TOL).contains(v)));
        }
        if n % 2 == 1 {
            assert!((hann(n, Symmetry::Symmetric)[n / 2] - 1.0).abs() <= TOL);
            assert!((blackman(n, Symmetry::Symmetric)[n / 2] - 1.0).abs() <= TOL);
        }
    }
}

#[test]
fn periodic_is_symmetric_of_one_more_sample_without_its_last() {
    for n in [2usize, 7, 64] {
        for (p, s) in [
            (hann(n, Symmetry::Periodic), hann(n + 1, Symmetry::Symmetric)),
            (blackman(n, Symmetry::Periodic), blackman(n + 1, Symmetry::Symmetric)),
        ] {
            for i in 0..n {
                assert!((p[i] - s[i]).abs() <= TOL);
            }
        }
        // Periodic Hann windows overlapped by half sum to exactly 1 (constant overlap-add).
        if n % 2 == 0 {
            let p = hann(n, Symmetry::Periodic);
            for i in 0..n / 2 {
                assert!((p[i] + p[i + n / 2] - 1.0).abs() <= TOL);
            }
        }
    }
}

#[test]
fn tukey_extremes_are_rectangular_and_hann() {
    assert!(tukey(33, 0.0).unwrap().iter().all(|&v| v == 1.0));
    let t = tukey(33, 1.0).unwrap();
    let h = hann(33, Symmetry::Symmetric);
    for (a, b) in t.iter().zip(&h) {
        assert!((a - b).abs() <= TOL);
    }
    // Ratio 0.5 on 101 samples: tapers cover x < 0.25, i.e. 25 samples each side; the middle is exactly flat.
    let t = tukey(101, 0.5).unwrap();
    assert!(t[24] < 1.0);
    assert!(t[25..=75].iter().all(|&v| v == 1.0));
    for bad in [-0.1, 1.1, f64::NAN] {
        assert!(matches!(tukey(8, bad), Err(DspError::InvalidParameter { .. })));
    }
}

#[test]
fn fades_mirror_each_other_and_join_smoothly() {
    let n = 50;
    let (a, b) = (fade_in(n), fade_out(n));
    assert_eq!(a[0], 0.0);
    assert_eq!(b[n - 1], 0.0);
    for i in 0..n {
        assert_eq!(a[i], b[n - 1 - i]);
    }
    assert!(a.windows(2).all(|w| w[1] > w[0]), "fade-in rises strictly");
    // The step to the 1.0 after the fade equals the fade's first step (raised-cosine symmetry), so no kink.
    assert!(((1.0 - a[n - 1]) - a[1]).abs() <= TOL);
}

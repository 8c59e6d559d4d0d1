use metaplate_dsp::error::DspError;
use metaplate_dsp::fft::*;
use num_complex::Complex64;

#[test]
fn round_trip_small_lengths() {
    for n in 1..40 {
        let x: Vec<f64> = (0..n).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        let y = inverse(&forward(&x, n).unwrap(), n).unwrap();
        for (a, b) in x.iter().zip(&y) {
            assert!((a - b).abs() < 1e-12, "n = {n}");
        }
    }
}

#[test]
fn length_one_is_identity() {
    let spec = forward(&[2.5], 1).unwrap();
    assert_eq!(spec.len(), 1);
    assert_eq!(spec[0].re, 2.5);
    assert_eq!(inverse(&spec, 1).unwrap(), vec![2.5]);
}

#[test]
fn large_prime_length_round_trips() {
    let n = 100_003; // prime
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.001).sin()).collect();
    let y = inverse(&forward(&x, n).unwrap(), n).unwrap();
    let err = x.iter().zip(&y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    // Bluestein's algorithm rounds through three FFTs of about 2^18: 1e-9 is generous for f64.
    assert!(err < 1e-9, "max error {err}");
}

#[test]
fn length_two_to_the_24_round_trips() {
    let n = 1 << 24;
    let mut x = vec![0.0; n];
    x[12_345] = 1.0;
    x[n - 1] = -0.5;
    let spec = forward(&x, n).unwrap();
    // A unit impulse at 12345 has unit magnitude in every bin but for the other impulse's contribution.
    assert!((spec[0].re - 0.5).abs() < 1e-9);
    let y = inverse(&spec, n).unwrap();
    assert!((y[12_345] - 1.0).abs() < 1e-9);
    assert!((y[n - 1] + 0.5).abs() < 1e-9);
    let stray =
        y.iter().enumerate().filter(|(i, _)| *i != 12_345 && *i != n - 1).map(|(_, v)| v.abs()).fold(0.0, f64::max);
    assert!(stray < 1e-9, "stray {stray}");
}

#[test]
fn buffer_variants_match_the_allocating_ones_exactly() {
    // Same plan, same arithmetic: bit-identical results, for an even, an odd and a padded length.
    for (len, n) in [(72, 72), (45, 45), (30, 64)] {
        let x: Vec<f64> = (0..len).map(|i| ((i * 13 + 5) % 17) as f64 - 8.0).collect();
        let expected = forward(&x, n).unwrap();
        let mut spectrum = vec![Complex64::new(9.0, 9.0); bin_count(n)];
        forward_into(&x, n, &mut spectrum).unwrap();
        assert_eq!(spectrum, expected);
        if len == n {
            let mut scratch_input = x.clone();
            forward_destructive(&mut scratch_input, &mut spectrum).unwrap();
            assert_eq!(spectrum, expected);
        }
        let mut output = vec![7.0; n];
        inverse_into(&expected, n, &mut output).unwrap();
        assert_eq!(output, inverse(&expected, n).unwrap());
    }
}

#[test]
fn buffer_variants_refuse_wrong_lengths_and_non_finite_input() {
    let mut spectrum = vec![Complex64::new(0.0, 0.0); 3];
    assert!(matches!(forward_into(&[1.0; 4], 4, &mut spectrum[..2]), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(forward_destructive(&mut [1.0; 6], &mut spectrum), Err(DspError::LengthMismatch { .. })));
    assert!(matches!(forward_destructive(&mut [], &mut spectrum), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(inverse_into(&spectrum, 4, &mut [0.0; 5]), Err(DspError::LengthMismatch { .. })));
    // A NaN or infinity anywhere, in the part checked eight at a time or in the remainder, is named.
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for index in 0..19 {
            let mut x = vec![1.0; 19];
            x[index] = bad;
            let mut bins = vec![Complex64::new(0.0, 0.0); bin_count(19)];
            let err = forward_into(&x, 19, &mut bins).unwrap_err();
            assert!(matches!(err, DspError::NonFinite { index: i, .. } if i == index), "{bad} at {index}: {err}");
            assert!(matches!(forward_destructive(&mut x, &mut bins), Err(DspError::NonFinite { .. })));
        }
    }
    for index in 0..5 {
        let mut bins = vec![Complex64::new(1.0, 0.0); 5];
        bins[index].im = f64::INFINITY;
        let err = inverse_into(&bins, 8, &mut [0.0; 8]).unwrap_err();
        assert!(matches!(err, DspError::NonFinite { index: i, .. } if i == index), "{index}: {err}");
    }
}

#[test]
fn refuses_zero_and_oversized_lengths_and_nan() {
    assert!(matches!(forward(&[1.0], 0), Err(DspError::InvalidParameter { .. })));
    assert!(matches!(forward(&[1.0], MAX_FFT_LEN + 1), Err(DspError::TooLong { .. })));
    assert!(matches!(forward(&[1.0, f64::NAN], 4), Err(DspError::NonFinite { index: 1, .. })));
    assert!(matches!(inverse(&[Complex64::new(1.0, 0.0)], 4), Err(DspError::LengthMismatch { .. })));
}

#[test]
fn fast_len_is_smooth_and_minimal() {
    assert_eq!(fast_len(0).unwrap(), 1);
    assert_eq!(fast_len(1).unwrap(), 1);
    assert_eq!(fast_len(11).unwrap(), 12);
    assert_eq!(fast_len(97).unwrap(), 98);
    assert_eq!(fast_len(1025).unwrap(), 1029);
    fn is_7_smooth(mut k: usize) -> bool {
        for p in [2, 3, 5, 7] {
            while k.is_multiple_of(p) {
                k /= p;
            }
        }
        k == 1
    }
    for n in [13usize, 1000, 72_001, 144_000] {
        let m = fast_len(n).unwrap();
        assert!(m >= n);
        assert!(is_7_smooth(m), "{m} is not 7-smooth");
        // Minimal: no 7-smooth number in [n, m).
        assert!((n..m).all(|k| !is_7_smooth(k)), "a 7-smooth length below {m} exists");
    }
}

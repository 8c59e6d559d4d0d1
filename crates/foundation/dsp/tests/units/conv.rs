use metaplate_dsp::conv::*;
use metaplate_dsp::error::DspError;

#[test]
fn matches_direct_convolution() {
    let a = [1.0, -2.0, 3.0, 0.5];
    let b = [0.25, 1.0, -1.0];
    let mut direct = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            direct[i + j] += x * y;
        }
    }
    let fast = convolve(&a, &b).unwrap();
    assert_eq!(fast.len(), direct.len());
    for (f, d) in fast.iter().zip(&direct) {
        assert!((f - d).abs() < 1e-12);
    }
}

#[test]
fn refuses_empty_and_nan() {
    assert!(matches!(convolve(&[], &[1.0]), Err(DspError::Empty { .. })));
    assert!(matches!(convolve(&[1.0], &[f64::INFINITY]), Err(DspError::NonFinite { .. })));
}

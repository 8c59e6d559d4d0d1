use metaplate_dsp::band::*;

#[test]
fn unity_in_band_zero_beyond_skirts_and_half_mid_skirt() {
    let b = BandLimit::new(100.0, 400.0, 20.0, 50.0).unwrap();
    assert_eq!(b.gain(100.0), 1.0);
    assert_eq!(b.gain(250.0), 1.0);
    assert_eq!(b.gain(400.0), 1.0);
    assert!((b.gain(90.0) - 0.5).abs() < 1e-12);
    assert!((b.gain(425.0) - 0.5).abs() < 1e-12);
    assert_eq!(b.gain(80.0), 0.0);
    assert_eq!(b.gain(450.0), 0.0);
    assert_eq!(b.gain(-250.0), 1.0);
}

#[test]
fn edges_at_zero_and_nyquist() {
    let b = BandLimit::new(0.0, 12_000.0, 0.0, 0.0).unwrap();
    let g = b.bin_gains(16, 24_000.0);
    assert!(g.iter().all(|&v| v == 1.0));
    // A skirt reaching below 0 Hz is cut there, not mirrored.
    let b = BandLimit::new(10.0, 100.0, 40.0, 0.0).unwrap();
    assert!(b.gain(0.0) > 0.0 && b.gain(0.0) < 1.0);
}

#[test]
fn refuses_bad_edges() {
    assert!(BandLimit::new(400.0, 100.0, 0.0, 0.0).is_err());
    assert!(BandLimit::new(100.0, 100.0, 0.0, 0.0).is_err());
    assert!(BandLimit::new(-1.0, 100.0, 0.0, 0.0).is_err());
    assert!(BandLimit::new(1.0, f64::NAN, 0.0, 0.0).is_err());
    assert!(BandLimit::new(1.0, 100.0, -5.0, 0.0).is_err());
}

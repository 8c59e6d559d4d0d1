#![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

use metaplate_control::solve::DEFAULT_RELATIVE_ALPHA;
use metaplate_control::target::Waveform;

use metaplate_control::focus::*;

#[test]
fn pixels_parse_with_their_targets_and_refuse_bad_text() {
    let p = parse_pixel("0.01,-0.02").unwrap();
    assert_eq!((p.x_m, p.y_m, &p.target, p.label.as_str()), (0.01, -0.02, &TargetSpec::ImpulseAtFocus, "impulse"));
    let p: PixelSpec = "0,0:null".parse().unwrap();
    assert_eq!(p.target, TargetSpec::Waveform(Waveform::Null));
    assert_eq!(p.label, "null");
    for (text, reason) in [("0.01", "expected X_M,Y_M"), ("a,0", "`a` is not a number"), ("inf,0", "must be finite")] {
        let e = parse_pixel(text).unwrap_err().to_string();
        assert!(e.contains(reason) && e.contains(text), "{text}: {e}");
    }
    assert!(parse_pixel("0,0:wobble").is_err());
}

#[test]
fn the_default_options_are_the_papers_band_and_alpha() {
    let o = RenderOptions::default();
    assert_eq!((o.band_lo_hz, o.band_hi_hz), DEFAULT_FOCUS_BAND_HZ);
    assert_eq!(o.alpha_relative, DEFAULT_RELATIVE_ALPHA);
    assert!(o.pad_s.is_none() && o.focus_s.is_none() && !o.time_reversal);
}

use metaplate_dsp::excitation::*;

#[test]
fn names_parse_to_their_protocols() {
    let p = parse("paper").unwrap();
    assert_eq!(p, ExcitationProtocol::paper());
    assert_eq!(parse("quick").unwrap(), ExcitationProtocol::quick());
    let h = parse("hadamard:1x2").unwrap();
    assert_eq!((h.scheme, h.repetitions, h.sweep.duration_s), (Scheme::Hadamard, 2, 1.0));
    // 8 shots of 2 s plus 0.5 s ring-out each: 20 s, against the paper's 124 s.
    assert!((h.nominal_time_per_point_s(8) - 20.0).abs() < 1e-9);
    assert!((p.nominal_time_per_point_s(8) - 124.0).abs() < 1e-9);
    let e = parse("sequential-exp:2x1").unwrap();
    assert!(e.sweep.exp_rate_s().is_some() && e.deconv.regularisation == EXP_REGULARISATION);
    let i = parse("interleaved:2").unwrap();
    let Scheme::Interleaved { slot_s } = i.scheme else { panic!("{i:?}") };
    // The slot the DSP protocol requires for 0.5 s responses must be met.
    assert!(i.validate(8, 0.5).is_ok(), "slot {slot_s}");
    let a = parse("adaptive:0.6x2@40/3").unwrap();
    assert_eq!(a.adaptive, Some(Adaptive { target: AdaptiveTarget::SnrDb(40.0), max_rounds: 3 }));
    let e = parse("adaptive-error:0.6x2@-35/6").unwrap();
    assert_eq!(e.adaptive, Some(Adaptive { target: AdaptiveTarget::ErrorDb(-35.0), max_rounds: 6 }));
    assert_eq!((e.scheme, e.repetitions), (Scheme::Hadamard, 2));
    assert!(AdaptiveTarget::ErrorDb(-35.0).reached(None, Some(-35.0)));
    assert!(!AdaptiveTarget::ErrorDb(-35.0).reached(Some(90.0), Some(-34.9)));
    assert!(!AdaptiveTarget::ErrorDb(-35.0).reached(Some(90.0), None), "unknown is not reached");
    assert!(AdaptiveTarget::SnrDb(30.0).reached(Some(30.0), None));
    assert_eq!(AdaptiveTarget::ErrorDb(-30.0).shortfall_db(None, Some(-27.0)), Some(3.0));
    assert_eq!(AdaptiveTarget::SnrDb(30.0).shortfall_db(Some(36.0), None), Some(-6.0));
    assert_eq!(AdaptiveTarget::ErrorDb(-30.0).shortfall_db(Some(10.0), None), None);
    let q = parse("sequential-adaptive:1x2@-30").unwrap();
    assert_eq!((q.scheme, q.repetitions), (Scheme::Sequential, 2));
    assert_eq!(q.adaptive, Some(Adaptive { target: AdaptiveTarget::ErrorDb(-30.0), max_rounds: DEFAULT_ROUNDS }));
    assert_eq!(parse("adaptive:0.6x2@40").unwrap().adaptive.map(|a| a.max_rounds), Some(DEFAULT_ROUNDS));
    let s = parse("staggered-adaptive:5x2@-30/4").unwrap();
    assert_eq!((s.scheme, s.repetitions), (Scheme::Staggered, 2));
    assert_eq!(s.adaptive, Some(Adaptive { target: AdaptiveTarget::ErrorDb(-30.0), max_rounds: 4 }));
    assert!(parse("staggered-adaptive:5x1@-30").is_err());
}

#[test]
fn bad_names_and_settings_are_refused_with_the_reason() {
    for (name, needle) in [
        ("nope", "unknown protocol"),
        ("hadamard", "needs settings"),
        ("hadamard:0.1x2", "duration"),
        ("hadamard:1x0", "repetitions"),
        ("hadamard:1", "DxR"),
        ("paper:1x1", "no settings"),
        ("adaptive:1x2@x", "SNR"),
        ("adaptive:1x1@30", "at least 2 periods"),
        ("adaptive:1x2@30/0", "rounds"),
        ("adaptive-error:1x1@-30", "at least 2 periods"),
        ("adaptive-error:1x2@", "error"),
        ("adaptive-error:1x2", "DxR@ERROR"),
        ("adaptive-error", "needs settings"),
        ("interleaved:inf", "finite"),
    ] {
        let err = parse(name).unwrap_err().to_string();
        assert!(err.contains(needle), "{name}: {err}");
    }
}

use metaplate_core::audio::*;

#[test]
fn playback_check_names_the_problem() {
    let config = AudioConfig { sample_rate_hz: 48_000.0, channels: 2 };
    assert_eq!(check_playback(&config, &[vec![0.0; 4], vec![0.5; 4]]), Ok(4));
    let err = check_playback(&config, &[vec![0.0; 4]]).unwrap_err();
    assert!(err.to_string().contains("1 signals for 2"), "{err}");
    let err = check_playback(&config, &[vec![0.0; 4], vec![0.0; 3]]).unwrap_err();
    assert!(err.to_string().contains("channel 1 has 3 frames"), "{err}");
    let err = check_playback(&config, &[vec![], vec![]]).unwrap_err();
    assert!(err.to_string().contains("empty"), "{err}");
    let err = check_playback(&config, &[vec![0.0, f64::NAN], vec![0.0; 2]]).unwrap_err();
    assert!(err.to_string().contains("channel 0 frame 1"), "{err}");
}

#[test]
fn only_link_failures_suggest_reopen() {
    assert!(AudioError::Disconnected { detail: "gone".into() }.suggests_reopen());
    assert!(AudioError::Timeout { detail: "write".into() }.suggests_reopen());
    assert!(!AudioError::Config { detail: "44.1 kHz".into() }.suggests_reopen());
}

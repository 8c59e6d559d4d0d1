//! The ALSA backend: typed errors without a sound card, a full playback through ALSA's `null` PCM, and an opt-in
//! test on a real sound card.
//!
//! Real card: `METAPLATE_AUDIO_DEVICE=hw:CARD=24Ao,DEV=0 cargo test -p metaplate-audio --test alsa_device --
//! --ignored` (optionally `METAPLATE_AUDIO_RATE_HZ`, default 48000, and `METAPLATE_AUDIO_CHANNELS`, default 2).
//! It plays 0.5 s of a quiet 440 Hz tone on every channel: turn the amplifier down.
#![cfg(all(feature = "alsa", target_os = "linux"))]
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use metaplate_audio::{AlsaSink, AudioDriver, PcmError, PcmParams, PcmSink};
use metaplate_core::audio::{AudioConfig, AudioError, AudioOut};

#[test]
fn a_pcm_that_does_not_exist_is_a_typed_error() {
    let name = "metaplate_no_such_pcm_xyz";
    let mut sink = AlsaSink::new(name);
    let err = sink.open(PcmParams { sample_rate_hz: 48_000.0, channels: 2 }).unwrap_err();
    // ALSA answers ENOENT for an unknown PCM name, which is what an unplugged card's name also gets.
    assert!(matches!(err, PcmError::Disconnected(_)), "{err:?}");
    assert!(err.to_string().contains(name), "{err}");

    // Through the driver: the same, as the capability's error, and a reopen still finds nothing.
    let mut audio = AudioDriver::new(AlsaSink::new(name));
    let err = audio.configure(&AudioConfig { sample_rate_hz: 48_000.0, channels: 2 }).unwrap_err();
    assert!(matches!(err, AudioError::Disconnected { .. }), "{err:?}");
    assert!(audio.start(&[vec![0.0; 8], vec![0.0; 8]]).is_err());
}

#[test]
fn a_card_that_does_not_exist_is_a_typed_error() {
    let mut sink = AlsaSink::new("hw:CARD=MetaplateNoSuchCard,DEV=0");
    let err = sink.open(PcmParams { sample_rate_hz: 48_000.0, channels: 8 }).unwrap_err();
    assert!(matches!(err, PcmError::Disconnected(_)), "{err:?}");
}

/// ALSA's `null` PCM (defined in alsa-lib's own configuration) accepts any parameters and discards samples: the
/// whole path (hw and sw parameters, writer thread, drain, reuse of the stream) runs without a sound card.
#[test]
fn the_null_pcm_plays_buffers_end_to_end() {
    let mut audio = AudioDriver::new(AlsaSink::new("null"));
    audio.configure(&AudioConfig { sample_rate_hz: 48_000.0, channels: 8 }).unwrap();
    assert_eq!(audio.sink().sample_format(), Some(metaplate_audio::SampleFormat::F32));
    for frames in [10, 24_000] {
        let signals: Vec<Vec<f64>> =
            (0..8).map(|ch| (0..frames).map(|n| ((n + ch) as f64 * 0.01).sin() * 0.5).collect()).collect();
        audio.start(&signals).unwrap();
        let report = audio.finish().unwrap();
        assert_eq!(report.frames_played, frames as u64);
    }
    audio.reopen().unwrap();
    audio.start(&vec![vec![0.25; 100]; 8]).unwrap();
    assert_eq!(audio.finish().unwrap().frames_played, 100);
}

#[test]
#[ignore = "needs a real sound card: METAPLATE_AUDIO_DEVICE=hw:... cargo test -p metaplate-audio --test alsa_device -- --ignored"]
fn a_real_card_plays_at_the_exact_rate() {
    let name = std::env::var("METAPLATE_AUDIO_DEVICE")
        .expect("this test needs METAPLATE_AUDIO_DEVICE=<ALSA PCM name>, e.g. hw:CARD=24Ao,DEV=0");
    let rate_hz: f64 = std::env::var("METAPLATE_AUDIO_RATE_HZ").map_or(48_000.0, |v| v.parse().unwrap());
    let channels: u32 = std::env::var("METAPLATE_AUDIO_CHANNELS").map_or(2, |v| v.parse().unwrap());
    let mut audio = AudioDriver::new(AlsaSink::new(&name));
    eprintln!("identity: {:?}", audio.identity());
    audio.configure(&AudioConfig { sample_rate_hz: rate_hz, channels }).unwrap();
    eprintln!("sample format: {:?}", audio.sink().sample_format());

    let frames = (0.5 * rate_hz) as usize;
    let tone: Vec<f64> =
        (0..frames).map(|n| 0.05 * (2.0 * std::f64::consts::PI * 440.0 * n as f64 / rate_hz).sin()).collect();
    let wall = std::time::Instant::now();
    audio.start(&vec![tone; channels as usize]).unwrap();
    let report = audio.finish().unwrap();
    let elapsed_s = wall.elapsed().as_secs_f64();
    assert_eq!(report.frames_played, frames as u64);
    assert_eq!(report.underruns, 0, "underruns on an idle machine");
    // The playback takes its length: at least 0.5 s less one device buffer (0.2 s, started once full), and not
    // much more than 0.5 s plus the buffer and start-up (1 s of slack for a loaded machine).
    assert!(elapsed_s > 0.5 - 0.2 && elapsed_s < 0.5 + 0.2 + 1.0, "playback took {elapsed_s} s");

    // A rate the card does not run at is refused with both numbers, not resampled.
    let err = audio.configure(&AudioConfig { sample_rate_hz: 12_345.0, channels }).unwrap_err();
    eprintln!("12345 Hz: {err}");
    assert!(matches!(err, AudioError::Config { .. }), "{err:?}");
}

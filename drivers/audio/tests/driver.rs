//! `AudioDriver` over a fake `PcmSink` that records what it receives and opens what it is told to.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap: a panic is the test failing

use metaplate_audio::{AudioDriver, PcmError, PcmParams, PcmSink, PcmStatus};
use metaplate_core::audio::{AudioConfig, AudioError, AudioOut};

/// A sink that records every call and answers as scripted.
#[derive(Default)]
struct FakeSink {
    /// Every `open` request, in order.
    opens: Vec<PcmParams>,
    /// Every submitted buffer, in order.
    submitted: Vec<Vec<f32>>,
    closes: usize,
    /// What `open` returns instead of the request (a device that runs at something else).
    opens_as: Option<PcmParams>,
    /// The error the next `open`, `submit` or `wait` returns.
    fail_open: Option<PcmError>,
    fail_submit: Option<PcmError>,
    fail_wait: Option<PcmError>,
    underruns: u32,
}

impl PcmSink for FakeSink {
    fn describe(&self) -> (String, String, String) {
        ("Fake".into(), "Sink 8".into(), "fake:0".into())
    }

    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        self.opens.push(wanted);
        if let Some(error) = self.fail_open.take() {
            return Err(error);
        }
        Ok(self.opens_as.unwrap_or(wanted))
    }

    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        if let Some(error) = self.fail_submit.take() {
            return Err(error);
        }
        self.submitted.push(interleaved);
        Ok(())
    }

    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        if let Some(error) = self.fail_wait.take() {
            return Err(error);
        }
        let channels = self.opens.last().map_or(1, |p| p.channels) as u64;
        let samples = self.submitted.last().map_or(0, Vec::len) as u64;
        Ok(PcmStatus { frames_played: samples / channels, underruns: self.underruns })
    }

    fn close(&mut self) {
        self.closes += 1;
    }
}

fn config(channels: u32) -> AudioConfig {
    AudioConfig { sample_rate_hz: 48_000.0, channels }
}

fn configured(channels: u32) -> AudioDriver<FakeSink> {
    let mut audio = AudioDriver::new(FakeSink::default());
    audio.configure(&config(channels)).unwrap();
    audio
}

#[test]
fn identity_comes_from_the_sink() {
    let audio = AudioDriver::new(FakeSink::default());
    let id = audio.identity();
    assert_eq!((id.vendor.as_str(), id.model.as_str(), id.serial.as_str()), ("Fake", "Sink 8", "fake:0"));
}

#[test]
fn frames_are_interleaved_channel_by_channel() {
    let mut audio = configured(3);
    // Values exactly representable in f32, so the comparison is exact.
    let signals = vec![vec![0.0, 0.5, -0.5], vec![0.125, 0.25, 0.375], vec![-1.0, 1.0, 0.75]];
    audio.start(&signals).unwrap();
    let report = audio.finish().unwrap();
    assert_eq!(audio.sink().submitted, [vec![0.0, 0.125, -1.0, 0.5, 0.25, 1.0, -0.5, 0.375, 0.75]]);
    assert_eq!(report.frames_played, 3);
    assert_eq!(audio.sink().opens, [PcmParams { sample_rate_hz: 48_000.0, channels: 3 }]);
}

#[test]
fn samples_beyond_full_scale_are_clipped() {
    let mut audio = configured(2);
    audio.start(&[vec![1.5, -7.0, 1.0, -1.0], vec![1e300, -1e300, 0.999, 1.0 + 1e-12]]).unwrap();
    // Exact: clipping yields exactly +/-1; 0.999 -> nearest f32, compared as the same cast.
    assert_eq!(audio.sink().submitted[0], [1.0, 1.0, -1.0, -1.0, 1.0, 0.999_f64 as f32, -1.0, 1.0]);
}

#[test]
fn underruns_reach_the_report() {
    let mut audio = configured(1);
    audio.sink_mut().underruns = 2;
    audio.start(&[vec![0.0; 5]]).unwrap();
    assert_eq!(audio.finish().unwrap().underruns, 2);
}

#[test]
fn a_device_at_another_rate_or_channel_count_is_refused() {
    for opens_as in
        [PcmParams { sample_rate_hz: 44_100.0, channels: 8 }, PcmParams { sample_rate_hz: 48_000.0, channels: 2 }]
    {
        let mut audio = AudioDriver::new(FakeSink { opens_as: Some(opens_as), ..FakeSink::default() });
        let err = audio.configure(&config(8)).unwrap_err();
        assert!(matches!(err, AudioError::Config { .. }), "{err:?}");
        let message = err.to_string();
        assert!(message.contains("asked for 8 channels at 48000 Hz"), "{message}");
        assert!(
            message.contains(&format!("opened {} channels at {} Hz", opens_as.channels, opens_as.sample_rate_hz)),
            "{message}"
        );
        // The mismatched stream is closed, and nothing can be played on it.
        assert_eq!(audio.sink().closes, 1);
        assert!(matches!(audio.start(&vec![vec![0.0; 4]; 8]), Err(AudioError::State { .. })));
    }
}

#[test]
fn a_rate_off_by_a_fraction_of_a_hertz_is_refused() {
    // 48 000.01 Hz is 0.2 ppm off, above the driver's 1e-9 relative tolerance (rounding noise only).
    let opens_as = PcmParams { sample_rate_hz: 48_000.01, channels: 2 };
    let mut audio = AudioDriver::new(FakeSink { opens_as: Some(opens_as), ..FakeSink::default() });
    assert!(matches!(audio.configure(&config(2)), Err(AudioError::Config { .. })));
}

#[test]
fn bad_configurations_never_reach_the_sink() {
    let mut audio = AudioDriver::new(FakeSink::default());
    for bad in [
        AudioConfig { sample_rate_hz: 0.0, channels: 2 },
        AudioConfig { sample_rate_hz: f64::NAN, channels: 2 },
        AudioConfig { sample_rate_hz: f64::INFINITY, channels: 2 },
        AudioConfig { sample_rate_hz: -48_000.0, channels: 2 },
        AudioConfig { sample_rate_hz: 48_000.0, channels: 0 },
    ] {
        assert!(matches!(audio.configure(&bad), Err(AudioError::Config { .. })), "{bad:?}");
    }
    assert!(audio.sink().opens.is_empty());
}

#[test]
fn calls_out_of_order_are_state_errors() {
    let mut audio = AudioDriver::new(FakeSink::default());
    let err = audio.start(&[vec![0.0; 4]]).unwrap_err();
    assert!(matches!(err, AudioError::State { .. }) && err.to_string().contains("before configure"), "{err}");
    let err = audio.finish().unwrap_err();
    assert!(matches!(err, AudioError::State { .. }) && err.to_string().contains("nothing playing"), "{err}");

    audio.configure(&config(1)).unwrap();
    audio.start(&[vec![0.0; 4]]).unwrap();
    let err = audio.start(&[vec![0.0; 4]]).unwrap_err();
    assert!(matches!(err, AudioError::State { .. }) && err.to_string().contains("while a playback"), "{err}");
    let err = audio.configure(&config(1)).unwrap_err();
    assert!(matches!(err, AudioError::State { .. }), "{err}");
    // Only the first start reached the sink.
    assert_eq!(audio.sink().submitted.len(), 1);
    audio.finish().unwrap();
    let err = audio.finish().unwrap_err();
    assert!(matches!(err, AudioError::State { .. }), "{err}");
}

#[test]
fn bad_buffers_are_refused_before_the_sink() {
    let mut audio = configured(2);
    for bad in [vec![vec![0.0; 4]], vec![vec![0.0; 4], vec![0.0; 3]], vec![vec![0.0, f64::NAN], vec![0.0; 2]]] {
        assert!(matches!(audio.start(&bad), Err(AudioError::Config { .. })), "{bad:?}");
    }
    assert!(audio.sink().submitted.is_empty());
    // Still idle: a good buffer plays.
    audio.start(&[vec![0.0; 2], vec![0.0; 2]]).unwrap();
}

#[test]
fn sink_errors_map_to_capability_errors() {
    let cases = [
        (PcmError::Disconnected("unplugged".into()), true),
        (PcmError::Timeout("stalled".into()), true),
        (PcmError::Params("S8 only".into()), false),
        (PcmError::State("twice".into()), false),
        (PcmError::Unavailable("no ALSA".into()), false),
        (PcmError::Other("EPERM".into()), false),
    ];
    for (error, reopen) in cases {
        // On open (configure), on submit (start) and on wait (finish).
        let mut audio = AudioDriver::new(FakeSink { fail_open: Some(error.clone()), ..FakeSink::default() });
        let on_open = audio.configure(&config(1)).unwrap_err();
        let mut audio = configured(1);
        audio.sink_mut().fail_submit = Some(error.clone());
        let on_submit = audio.start(&[vec![0.0; 2]]).unwrap_err();
        audio.sink_mut().fail_wait = Some(error.clone());
        audio.start(&[vec![0.0; 2]]).unwrap();
        let on_wait = audio.finish().unwrap_err();
        for mapped in [on_open, on_submit, on_wait] {
            assert_eq!(mapped.suggests_reopen(), reopen, "{error:?} -> {mapped:?}");
            let expected_kind = match &error {
                PcmError::Disconnected(_) => matches!(mapped, AudioError::Disconnected { .. }),
                PcmError::Timeout(_) => matches!(mapped, AudioError::Timeout { .. }),
                PcmError::Params(_) => matches!(mapped, AudioError::Config { .. }),
                PcmError::State(_) => matches!(mapped, AudioError::State { .. }),
                PcmError::Unavailable(_) => matches!(mapped, AudioError::Unavailable { .. }),
                PcmError::Other(_) => matches!(mapped, AudioError::Device { .. }),
            };
            assert!(expected_kind, "{error:?} -> {mapped:?}");
        }
    }
}

#[test]
fn reopen_reapplies_the_last_configuration() {
    let mut audio = AudioDriver::new(FakeSink::default());
    // Nothing configured: reopen only closes.
    audio.reopen().unwrap();
    assert!(audio.sink().opens.is_empty());

    audio.configure(&config(2)).unwrap();
    audio.configure(&AudioConfig { sample_rate_hz: 96_000.0, channels: 8 }).unwrap();
    audio.start(&vec![vec![0.0; 3]; 8]).unwrap();
    audio.sink_mut().fail_wait = Some(PcmError::Disconnected("unplugged".into()));
    assert!(audio.finish().unwrap_err().suggests_reopen());

    // Still unplugged: the reopen says so.
    audio.sink_mut().fail_open = Some(PcmError::Disconnected("still gone".into()));
    assert!(matches!(audio.reopen(), Err(AudioError::Disconnected { .. })));
    audio.reopen().unwrap();
    let last = PcmParams { sample_rate_hz: 96_000.0, channels: 8 };
    assert_eq!(audio.sink().opens[2..], [last, last]);
    audio.start(&vec![vec![0.0; 3]; 8]).unwrap();
    assert_eq!(audio.finish().unwrap().frames_played, 3);
}

#[test]
fn reopen_while_playing_abandons_the_playback() {
    let mut audio = configured(1);
    audio.start(&[vec![0.0; 3]]).unwrap();
    audio.reopen().unwrap();
    assert!(matches!(audio.finish(), Err(AudioError::State { .. })));
    audio.start(&[vec![0.0; 3]]).unwrap();
}

//! A PCM session recorded through `RecordingSink` and replayed through `ReplaySink`: the same results call for
//! call, other samples are a mismatch naming the first differing sample, and an injected wait fault is the
//! sink's typed error.

// Test helpers, not only #[test] functions, may unwrap: a failure is the test failing.
#![allow(clippy::unwrap_used)]

use std::sync::Arc;

use metaplate_audio::{PcmError, PcmParams, PcmSink, PcmStatus};
use metaplate_cassette::{Body, Cassette, DeviceIdentity, DeviceKind, Header};
use metaplate_core::clock::VirtualClock;
use metaplate_replay::{Deviation, FaultKind, Recorder, RecordingSink, ReplayFaults, ReplaySink};

/// A sink that opens at what is asked (refusing 7 channels), plays at once, and reports the frames.
#[derive(Default)]
struct FakeSink {
    channels: u32,
    pending: Option<usize>,
}

impl PcmSink for FakeSink {
    fn describe(&self) -> (String, String, String) {
        ("MOTU".into(), "24Ao".into(), "hw:1".into())
    }
    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        if wanted.channels == 7 {
            return Err(PcmError::Params("7 channels: no such mode".into()));
        }
        self.channels = wanted.channels;
        Ok(wanted)
    }
    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        if self.pending.is_some() {
            return Err(PcmError::State("still playing".into()));
        }
        self.pending = Some(interleaved.len() / self.channels.max(1) as usize);
        Ok(())
    }
    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        let frames = self.pending.take().ok_or_else(|| PcmError::State("nothing submitted".into()))?;
        Ok(PcmStatus { frames_played: frames as u64, underruns: 0 })
    }
    fn close(&mut self) {}
}

fn buffer(frames: usize, channels: usize, scale: f32) -> Vec<f32> {
    (0..frames * channels).map(|i| scale * ((i % 97) as f32 / 97.0 - 0.5)).collect()
}

fn session(sink: &mut impl PcmSink) -> Vec<String> {
    let p = PcmParams { sample_rate_hz: 48_000.0, channels: 8 };
    vec![
        format!("{:?}", sink.open(PcmParams { channels: 7, ..p })),
        format!("{:?}", sink.open(p)),
        format!("{:?}", sink.submit(buffer(4800, 8, 0.5))),
        format!("{:?}", sink.submit(buffer(10, 8, 0.5))),
        format!("{:?}", sink.wait()),
        format!("{:?}", sink.submit(buffer(2400, 8, 0.25))),
        format!("{:?}", sink.wait()),
        format!("{:?}", sink.wait()),
        {
            sink.close();
            "closed".into()
        },
    ]
}

fn record() -> (Cassette, Vec<String>) {
    let header = Header { device_kind: DeviceKind::Audio, identity: DeviceIdentity::default(), start_unix_ns: 0 };
    let recorder = Recorder::start(Vec::new(), &header, Arc::new(VirtualClock::new())).unwrap();
    let mut sink = RecordingSink::new(FakeSink::default(), recorder.clone());
    let results = session(&mut sink);
    recorder.finish().unwrap();
    let bytes = recorder.with_writer(|w| w.clone()).unwrap();
    (Cassette::from_bytes(&bytes).unwrap(), results)
}

#[test]
fn replay_gives_the_same_results_and_stores_the_buffers() {
    let (cassette, recorded) = record();
    // Errors of every kind are among the results: a refused open, a submit while playing, a wait with nothing.
    assert!(recorded[0].contains("Params") && recorded[3].contains("State") && recorded[7].contains("State"));
    // The submitted buffers are in the cassette, bit for bit.
    let stored: Vec<f32> = cassette
        .records
        .iter()
        .filter_map(|r| match &r.body {
            Body::Stream(b) => match &b.samples {
                metaplate_cassette::Samples::F32(x) => Some(x.clone()),
                metaplate_cassette::Samples::I16(_) => None,
            },
            _ => None,
        })
        .flatten()
        .collect();
    let submitted: Vec<f32> =
        [buffer(4800, 8, 0.5), buffer(10, 8, 0.5), buffer(2400, 8, 0.25)].into_iter().flatten().collect();
    assert_eq!(stored, submitted);
    let mut sink = ReplaySink::new(&cassette, ReplayFaults::none()).unwrap();
    assert_eq!(session(&mut sink), recorded);
    assert!(sink.mismatch().is_none() && sink.is_finished());
    assert_eq!(sink.describe(), (String::new(), String::new(), String::new()), "the header's identity");
}

#[test]
fn other_samples_are_a_mismatch_at_the_first_differing_sample() {
    let (cassette, _) = record();
    let mut sink = ReplaySink::new(&cassette, ReplayFaults::none()).unwrap();
    let p = PcmParams { sample_rate_hz: 48_000.0, channels: 8 };
    assert!(sink.open(PcmParams { channels: 7, ..p }).is_err());
    sink.open(p).unwrap();
    let mut samples = buffer(4800, 8, 0.5);
    samples[1234] += 1e-6;
    assert!(matches!(sink.submit(samples), Err(PcmError::Other(m)) if m.contains("replay mismatch")));
    let m = sink.mismatch().unwrap();
    assert_eq!((m.deviation, m.first_difference), (Deviation::Samples, Some(1234)));
}

#[test]
fn an_injected_wait_fault_is_the_sinks_typed_error() {
    let (cassette, recorded) = record();
    let wait = cassette
        .records
        .iter()
        .position(|r| matches!(&r.body, Body::Event(metaplate_cassette::Event::Note(t)) if t.starts_with("played")))
        .unwrap();
    let mut sink = ReplaySink::new(&cassette, ReplayFaults::none().with(wait, FaultKind::Disconnect)).unwrap();
    let results = session(&mut sink);
    assert!(results[4].contains("Disconnected"), "{results:?}");
    assert_eq!(results[..4], recorded[..4]);
    assert_eq!(results[5..], recorded[5..]);
}

/// A session through the audio driver itself (what a recipe does), recorded.
fn record_driver_session() -> (Cassette, Vec<String>) {
    use metaplate_audio::AudioDriver;
    use metaplate_core::audio::{AudioConfig, AudioOut};
    let header = Header { device_kind: DeviceKind::Audio, identity: DeviceIdentity::default(), start_unix_ns: 0 };
    let recorder = Recorder::start(Vec::new(), &header, Arc::new(VirtualClock::new())).unwrap();
    let mut driver = AudioDriver::new(RecordingSink::new(FakeSink::default(), recorder.clone()));
    let config = AudioConfig { sample_rate_hz: 48_000.0, channels: 3 };
    let tone = |scale: f64| -> Vec<Vec<f64>> {
        (0..3).map(|c| (0..480).map(|i| scale * ((i * (c + 1)) as f64 * 0.01).sin()).collect()).collect()
    };
    let results = vec![
        format!("{:?}", driver.configure(&config)),
        format!("{:?}", driver.start(&tone(0.5))),
        format!("{:?}", driver.finish()),
        format!("{:?}", driver.start(&tone(0.25))),
        format!("{:?}", driver.finish()),
    ];
    recorder.finish().unwrap();
    let bytes = recorder.with_writer(|w| w.clone()).unwrap();
    (Cassette::from_bytes(&bytes).unwrap(), results)
}

#[test]
fn a_driver_session_replays_through_the_driver() {
    let (cassette, recorded) = record_driver_session();
    let report = metaplate_replay::session::replay(&cassette, ReplayFaults::none()).unwrap();
    assert!(report.mismatch.is_none(), "{:?}", report.mismatch);
    assert!(report.finished);
    let calls: Vec<&str> = report.calls.iter().map(|c| c.call.as_str()).collect();
    assert_eq!(calls, ["configure", "start", "finish", "start", "finish"]);
    assert!(recorded.iter().all(|r| r.starts_with("Ok")), "{recorded:?}");
    assert!(report.calls.iter().all(|c| c.result.is_ok()), "{:?}", report.calls);
    assert_eq!(report.calls[2].result.as_deref(), Ok("480 frames, 0 underruns"));
    // A disconnect injected at the first wait's record: the driver's finish reports it, typed.
    let wait_record = wait_record_index(&cassette);
    let faulted =
        metaplate_replay::session::replay(&cassette, ReplayFaults::none().with(wait_record, FaultKind::Disconnect))
            .unwrap();
    let finish = &faulted.calls[2];
    assert_eq!(finish.call, "finish");
    assert!(finish.result.as_ref().unwrap_err().contains("disconnected"), "{finish:?}");
}

/// The record index of the first `played` note (the first wait's result).
fn wait_record_index(cassette: &Cassette) -> usize {
    cassette
        .records
        .iter()
        .position(|r| matches!(&r.body, Body::Event(metaplate_cassette::Event::Note(t)) if t.starts_with("played")))
        .unwrap()
}

//! The PCM playback stream (audio interface): recording and replay.
//!
//! Calls map onto records as follows (endpoints of [`crate::script`]):
//! - `open(wanted)`: on [`EP_CONTROL`] a note `open <rate_hz> <channels>`, then `opened <rate_hz> <channels>` or
//!   the failure;
//! - `submit(samples)`: on [`EP_OUT`] the samples as `f32` stream blocks (the whole buffer, split into blocks of at
//!   most [`MAX_BLOCK_SAMPLES`] samples only when it exceeds a record's payload limit), then a note `submitted` or
//!   the failure. The buffers are stored whole, not as a length and checksum: replay then reports the first
//!   differing sample, and a cassette is a usable record of what was played (a 3 s sweep on 8 channels at
//!   48 kHz is 4.6 MB);
//! - `wait()`: on [`EP_IN`] a note `played <frames> <underruns>` or the failure;
//! - `close()`: on [`EP_CONTROL`] a close event.
//!
//! Rates are written with Rust's shortest round-trip formatting, so they read back exactly.

use std::io::Write;

use metaplate_audio::{PcmError, PcmParams, PcmSink, PcmStatus};
use metaplate_cassette::{Body, Cassette, DeviceKind, Event, MAX_PAYLOAD_LEN, Record, Samples, StreamBlock};

use crate::engine::{ReplayStats, first_difference};
use crate::failure::Failure;
use crate::faults::{FaultKind, ReplayFaults};
use crate::load::{ReplayError, check_kind};
use crate::mismatch::{Deviation, Mismatch};
use crate::recorder::Recorder;
use crate::script::{EP_CONTROL, EP_IN, EP_OUT};

/// The most samples in one stream record: what fits a record's payload after the 19-byte block header.
pub const MAX_BLOCK_SAMPLES: usize = (MAX_PAYLOAD_LEN - 19) / 4;

impl From<&PcmError> for Failure {
    fn from(e: &PcmError) -> Self {
        let other = |kind: &str, detail: &str| Failure::Other { kind: kind.into(), detail: detail.into() };
        match e {
            PcmError::Timeout(d) => Failure::Timeout(d.clone()),
            PcmError::Disconnected(d) => Failure::Disconnected(d.clone()),
            PcmError::Params(d) => other("params", d),
            PcmError::State(d) => other("state", d),
            PcmError::Unavailable(d) => other("unavailable", d),
            PcmError::Other(d) => other("other", d),
        }
    }
}

fn pcm_error(failure: Failure) -> PcmError {
    match failure {
        Failure::Timeout(d) => PcmError::Timeout(d),
        Failure::Disconnected(d) => PcmError::Disconnected(d),
        Failure::Stall => PcmError::Other("stall".into()),
        Failure::Other { kind, detail } => match kind.as_str() {
            "params" => PcmError::Params(detail),
            "state" => PcmError::State(detail),
            "unavailable" => PcmError::Unavailable(detail),
            _ => PcmError::Other(detail),
        },
    }
}

fn note(text: String) -> Body {
    Body::Event(Event::Note(text))
}

fn params_text(word: &str, p: PcmParams) -> String {
    format!("{word} {} {}", p.sample_rate_hz, p.channels)
}

fn parse_params(text: &str, word: &str) -> Option<PcmParams> {
    let mut parts = text.strip_prefix(word)?.split_whitespace();
    let sample_rate_hz = parts.next()?.parse().ok()?;
    let channels = parts.next()?.parse().ok()?;
    parts.next().is_none().then_some(PcmParams { sample_rate_hz, channels })
}

/// A [`PcmSink`] that passes every call to `S` and records it (see the module documentation).
pub struct RecordingSink<S: PcmSink, W: Write + Send> {
    inner: S,
    recorder: Recorder<W>,
    params: Option<PcmParams>,
    frames_submitted: u64,
}

impl<S: PcmSink, W: Write + Send> RecordingSink<S, W> {
    /// Records the session on `inner` into `recorder` (started with an audio header).
    pub fn new(inner: S, recorder: Recorder<W>) -> Self {
        Self { inner, recorder, params: None, frames_submitted: 0 }
    }

    /// The recorder, to finish the cassette once the session is over.
    pub fn recorder(&self) -> &Recorder<W> {
        &self.recorder
    }
}

impl<S: PcmSink, W: Write + Send> PcmSink for RecordingSink<S, W> {
    fn describe(&self) -> (String, String, String) {
        self.inner.describe()
    }

    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        let result = self.inner.open(wanted);
        let mut bodies = vec![note(params_text("open", wanted))];
        match &result {
            Ok(got) => {
                bodies.push(note(params_text("opened", *got)));
                self.params = Some(*got);
                self.frames_submitted = 0;
            }
            Err(e) => bodies.extend(Failure::from(e).to_bodies()),
        }
        self.recorder.record(EP_CONTROL, bodies);
        result
    }

    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        // Blocks need a whole number of frames and a positive rate: a buffer that is neither is recorded as one
        // channel at 1 Hz (the driver will have refused it anyway).
        let (channels, rate) = match self.params {
            Some(p) if p.channels >= 1 && interleaved.len().is_multiple_of(p.channels as usize) => {
                (u16::try_from(p.channels).unwrap_or(1), p.sample_rate_hz)
            }
            _ => (1, 1.0),
        };
        let rate = if rate.is_finite() && rate > 0.0 { rate } else { 1.0 };
        let chunk = (MAX_BLOCK_SAMPLES / usize::from(channels)).max(1) * usize::from(channels);
        let mut bodies = Vec::new();
        let mut first = self.frames_submitted;
        for samples in interleaved.chunks(chunk) {
            bodies.push(Body::Stream(StreamBlock {
                channels,
                sample_rate_hz: rate,
                first_sample_index: first,
                samples: Samples::F32(samples.to_vec()),
            }));
            first += (samples.len() / usize::from(channels)) as u64;
        }
        let result = self.inner.submit(interleaved);
        match &result {
            Ok(()) => {
                bodies.push(note("submitted".into()));
                self.frames_submitted = first;
            }
            Err(e) => bodies.extend(Failure::from(e).to_bodies()),
        }
        self.recorder.record(EP_OUT, bodies);
        result
    }

    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        let result = self.inner.wait();
        let bodies = match &result {
            Ok(s) => vec![note(format!("played {} {}", s.frames_played, s.underruns))],
            Err(e) => Failure::from(e).to_bodies(),
        };
        self.recorder.record(EP_IN, bodies);
        result
    }

    fn close(&mut self) {
        self.inner.close();
        self.recorder.record(EP_CONTROL, [Body::Event(Event::Close)]);
    }
}

/// One recorded call of a PCM sink.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum AudioStep {
    Open { record: usize, wanted: PcmParams, result: Result<PcmParams, Failure> },
    Submit { record: usize, samples: Vec<f32>, result: Result<(), Failure> },
    Wait { record: usize, result: Result<PcmStatus, Failure> },
    Close { record: usize },
}

impl AudioStep {
    fn record(&self) -> usize {
        match self {
            AudioStep::Open { record, .. }
            | AudioStep::Submit { record, .. }
            | AudioStep::Wait { record, .. }
            | AudioStep::Close { record } => *record,
        }
    }
}

fn note_text(record: Option<&Record>) -> Option<&str> {
    match record.map(|r| &r.body) {
        Some(Body::Event(Event::Note(text))) => Some(text),
        _ => None,
    }
}

/// The result recorded at `records[i]` on `endpoint`: `ok(note)` for a success note, else a failure.
fn result_at<T>(records: &[Record], i: usize, ok: impl Fn(&str) -> Option<T>) -> Option<(Result<T, Failure>, usize)> {
    let record = records.get(i)?;
    if let Some(value) = note_text(Some(record)).and_then(&ok) {
        return Some((Ok(value), 1));
    }
    let rest = records.get(i..)?;
    let (failure, n) =
        Failure::from_bodies(rest.iter().take_while(|r| r.endpoint == record.endpoint).map(|r| &r.body))?;
    Some((Err(failure), n))
}

fn parse_played(text: &str) -> Option<PcmStatus> {
    let mut parts = text.strip_prefix("played ")?.split_whitespace();
    let frames_played = parts.next()?.parse().ok()?;
    let underruns = parts.next()?.parse().ok()?;
    Some(PcmStatus { frames_played, underruns })
}

pub(crate) fn audio_steps(records: &[Record]) -> (Vec<AudioStep>, usize) {
    let mut steps = Vec::new();
    let mut ignored = 0;
    let mut i = 0;
    while i < records.len() {
        let record = &records[i];
        let text = note_text(Some(record));
        let parsed = match (&record.body, record.endpoint) {
            (Body::Event(Event::Note(_)), EP_CONTROL) => {
                text.and_then(|t| parse_params(t, "open")).and_then(|wanted| {
                    let (result, n) = result_at(records, i + 1, |t| parse_params(t, "opened"))?;
                    Some((AudioStep::Open { record: i, wanted, result }, 1 + n))
                })
            }
            (Body::Stream(_), EP_OUT) => {
                let mut samples = Vec::new();
                let mut j = i;
                while let Some(Record { body: Body::Stream(block), endpoint: EP_OUT, .. }) = records.get(j) {
                    if let Samples::F32(x) = &block.samples {
                        samples.extend_from_slice(x);
                    }
                    j += 1;
                }
                result_at(records, j, |t| (t == "submitted").then_some(()))
                    .map(|(result, n)| (AudioStep::Submit { record: i, samples, result }, j - i + n))
            }
            (_, EP_IN) => {
                result_at(records, i, parse_played).map(|(result, n)| (AudioStep::Wait { record: i, result }, n))
            }
            (Body::Event(Event::Close), EP_CONTROL) => Some((AudioStep::Close { record: i }, 1)),
            _ => None,
        };
        match parsed {
            Some((step, n)) => {
                steps.push(step);
                i += n;
            }
            None => {
                ignored += 1;
                i += 1;
            }
        }
    }
    (steps, ignored)
}

/// A [`PcmSink`] that plays an audio cassette back to a driver: each call must be the next recorded one, with
/// the same parameters and samples (bit for bit); it returns the recorded result. Faults at a wait's record:
/// `timeout` and `disconnect` return that error instead (the sink has no retry protocol to recover; the driver's
/// error shows). A deviation returns `PcmError::Other` carrying the [`Mismatch`].
pub struct ReplaySink {
    steps: Vec<AudioStep>,
    records: usize,
    cursor: usize,
    faults: ReplayFaults,
    identity: (String, String, String),
    mismatch: Option<Mismatch>,
    stats: ReplayStats,
}

impl std::fmt::Debug for ReplaySink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReplaySink").field("stats", &self.stats).finish_non_exhaustive()
    }
}

impl ReplaySink {
    /// A replay of `cassette` with `faults`; it describes itself with the cassette's vendor, model and serial.
    ///
    /// # Errors
    /// [`ReplayError::WrongDevice`] unless the cassette is an audio session.
    pub fn new(cassette: &Cassette, faults: ReplayFaults) -> Result<Self, ReplayError> {
        check_kind(cassette, DeviceKind::Audio)?;
        let (steps, ignored_records) = audio_steps(&cassette.records);
        let id = &cassette.header.identity;
        let stats = ReplayStats { steps: steps.len(), ignored_records, ..ReplayStats::default() };
        Ok(Self {
            steps,
            records: cassette.records.len(),
            cursor: 0,
            faults,
            identity: (id.vendor.clone(), id.model.clone(), id.serial.clone()),
            mismatch: None,
            stats,
        })
    }

    /// The first deviation of the driver from the recording, if any.
    pub fn mismatch(&self) -> Option<&Mismatch> {
        self.mismatch.as_ref()
    }

    /// What the replay did so far.
    pub fn stats(&self) -> &ReplayStats {
        &self.stats
    }

    /// Whether every recorded call has been played.
    pub fn is_finished(&self) -> bool {
        self.cursor >= self.steps.len()
    }

    fn deviate(&mut self, deviation: Deviation, first_difference: Option<usize>) -> PcmError {
        let record = self.steps.get(self.cursor).map_or(self.records, AudioStep::record);
        let deviation = if self.cursor >= self.steps.len() { Deviation::PastEnd } else { deviation };
        let m = Mismatch { deviation, record, expected: Vec::new(), got: Vec::new(), first_difference };
        let error = PcmError::Other(m.to_string());
        self.mismatch.get_or_insert(m);
        error
    }

    fn blocked(&self) -> Option<PcmError> {
        self.mismatch.as_ref().map(|m| PcmError::Other(m.to_string()))
    }

    fn advance(&mut self) {
        self.cursor += 1;
        self.stats.played += 1;
    }
}

impl PcmSink for ReplaySink {
    fn describe(&self) -> (String, String, String) {
        self.identity.clone()
    }

    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        if let Some(e) = self.blocked() {
            return Err(e);
        }
        match self.steps.get(self.cursor) {
            Some(AudioStep::Open { wanted: w, result, .. }) if *w == wanted => {
                let result = result.clone();
                self.advance();
                result.map_err(pcm_error)
            }
            _ => Err(self.deviate(Deviation::UnexpectedWrite, None)),
        }
    }

    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        if let Some(e) = self.blocked() {
            return Err(e);
        }
        let Some(AudioStep::Submit { samples, result, .. }) = self.steps.get(self.cursor) else {
            return Err(self.deviate(Deviation::UnexpectedWrite, None));
        };
        // Bit for bit: the recorded f32 values are exactly what was submitted.
        let (rec, got): (Vec<u32>, Vec<u32>) =
            (samples.iter().map(|x| x.to_bits()).collect(), interleaved.iter().map(|x| x.to_bits()).collect());
        if let Some(at) = first_difference(&rec, &got) {
            return Err(self.deviate(Deviation::Samples, Some(at)));
        }
        let result = result.clone();
        self.stats.writes_matched += 1;
        self.advance();
        result.map_err(pcm_error)
    }

    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        if let Some(e) = self.blocked() {
            return Err(e);
        }
        let Some(AudioStep::Wait { record, result }) = self.steps.get(self.cursor) else {
            return Err(self.deviate(Deviation::UnexpectedRead, None));
        };
        let (record, result) = (*record, result.clone());
        self.advance();
        let injected = match self.faults.at(record) {
            Some(FaultKind::Disconnect) => Some(PcmError::Disconnected("injected disconnect (replay)".into())),
            Some(FaultKind::Timeout | FaultKind::Stall) => Some(PcmError::Timeout("injected timeout (replay)".into())),
            _ => None,
        };
        if let (Some(error), Some(kind)) = (injected, self.faults.at(record)) {
            self.faults = std::mem::take(&mut self.faults).without(record);
            self.stats.faults_applied.push((record, kind));
            return Err(error);
        }
        result.map_err(pcm_error)
    }

    fn close(&mut self) {
        if let Some(AudioStep::Close { .. }) = self.steps.get(self.cursor) {
            self.advance();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_notes_round_trip_exactly() {
        let p = PcmParams { sample_rate_hz: 48_000.000_000_001, channels: 24 };
        assert_eq!(parse_params(&params_text("opened", p), "opened"), Some(p));
        assert_eq!(parse_params("opened 48000", "opened"), None);
        assert_eq!(parse_played("played 144000 2"), Some(PcmStatus { frames_played: 144_000, underruns: 2 }));
    }
}

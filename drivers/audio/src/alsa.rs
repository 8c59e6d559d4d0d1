//! The ALSA backend: a [`PcmSink`] on a Linux sound card, through libasound (crate `alsa`).
//!
//! The stream is opened by PCM name (`hw:CARD=24Ao,DEV=0` for the interface itself, `default` for whatever the
//! system routes to). It asks for the exact rate with ALSA's resampler off, the channel count, interleaved access,
//! and the first sample format the device offers among `FLOAT_LE`, `S32_LE`, `S24_LE`, `S24_3LE`, `S16_LE`
//! (converting from `f32` for the integer ones); it reports back what the device really opened, which the driver
//! then compares with what it asked. One submitted buffer is written by a writer thread, which recovers from
//! underruns (counting them) and drains the stream at the end.

use std::ffi::CString;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use alsa::pcm::{Access, Format, HwParams, PCM, State};
use alsa::{Direction, ValueOr};

use crate::samples::{SampleFormat, encode};
use crate::sink::{PcmError, PcmParams, PcmSink, PcmStatus};

/// Device buffer asked for, microseconds: long enough to ride over scheduling hiccups of a loaded 2-core machine,
/// short enough that a stop takes effect quickly.
const BUFFER_TIME_US: u32 = 200_000;
/// Period asked for, microseconds (a quarter of the buffer: the writer refills in these steps).
const PERIOD_TIME_US: u32 = 50_000;

/// Longest single wait for room in the device buffer, ms (several buffer lengths).
const WAIT_FOR_ROOM_MS: u32 = 1_000;

/// ALSA's name of a sample format.
fn alsa_format(format: SampleFormat) -> Format {
    match format {
        SampleFormat::F32 => Format::FloatLE,
        SampleFormat::S32 => Format::S32LE,
        SampleFormat::S24 => Format::S24LE,
        SampleFormat::S24Packed => Format::S243LE,
        SampleFormat::S16 => Format::S16LE,
    }
}

/// What the device opened, kept for the writer.
#[derive(Debug, Clone, Copy)]
struct Negotiated {
    format: SampleFormat,
    channels: u32,
    period_frames: usize,
}

/// What the writer thread hands back: the PCM (for the next buffer) and how the playback went.
type WriterOutcome = (PCM, Result<PcmStatus, PcmError>);

/// A playback stream on an ALSA PCM.
pub struct AlsaSink {
    name: String,
    card: (String, String),
    pcm: Option<PCM>,
    negotiated: Option<Negotiated>,
    writer: Option<JoinHandle<WriterOutcome>>,
    stop: Arc<AtomicBool>,
}

impl AlsaSink {
    /// A sink on the PCM called `pcm_name` (`hw:CARD=24Ao,DEV=0`, `default`, ...). Nothing is opened for playback
    /// until [`PcmSink::open`]; the card's name is looked up now, best effort (empty when the PCM cannot be opened,
    /// which `open` will then report).
    pub fn new(pcm_name: &str) -> Self {
        Self {
            name: pcm_name.to_string(),
            card: card_names(pcm_name),
            pcm: None,
            negotiated: None,
            writer: None,
            stop: Arc::new(AtomicBool::new(false)),
        }
    }

    /// The PCM name this sink opens.
    pub fn pcm_name(&self) -> &str {
        &self.name
    }

    /// The sample format the open stream writes, if open.
    pub fn sample_format(&self) -> Option<SampleFormat> {
        self.negotiated.map(|n| n.format)
    }

    /// Joins the writer, if any, putting its PCM back.
    fn join_writer(&mut self) -> Option<Result<PcmStatus, PcmError>> {
        let handle = self.writer.take()?;
        Some(match handle.join() {
            Ok((pcm, result)) => {
                self.pcm = Some(pcm);
                result
            }
            Err(_) => {
                // The PCM went down with the thread: only a reopen helps.
                self.negotiated = None;
                Err(PcmError::Other(format!("{}: the writer thread panicked", self.name)))
            }
        })
    }
}

impl Drop for AlsaSink {
    fn drop(&mut self) {
        self.close();
    }
}

/// A playback or capture PCM of a sound card, as `metaplate devices` lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PcmListing {
    /// The name the hardware file's `audio.device` (playback) or `daq.device` (capture) takes (`hw:CARD=24Ao,DEV=0`).
    pub name: String,
    /// The card's long name.
    pub card: String,
    /// Channels it can open, lowest and highest; `None` when it could not be opened to ask (in use).
    pub channels: Option<(u32, u32)>,
    /// Frame rates it can run at, lowest and highest, Hz; `None` as above.
    pub rates_hz: Option<(u32, u32)>,
    /// Why it could not be asked, empty when it could.
    pub note: String,
}

/// Every playback PCM of every sound card (the hardware devices `hw:CARD=...,DEV=...`, which run at exactly the
/// asked rate), with the channel counts and rates it accepts. A PCM in use by another program is listed with a
/// note instead of its ranges.
///
/// # Errors
/// [`PcmError::Other`] when the cards cannot be enumerated at all.
pub fn playback_pcms() -> Result<Vec<PcmListing>, PcmError> {
    pcms(Direction::Playback)
}

/// Every capture PCM of every sound card, as [`playback_pcms`] lists the playback ones.
///
/// # Errors
/// As [`playback_pcms`].
pub fn capture_pcms() -> Result<Vec<PcmListing>, PcmError> {
    pcms(Direction::Capture)
}

fn pcms(direction: Direction) -> Result<Vec<PcmListing>, PcmError> {
    let mut found = Vec::new();
    for card in alsa::card::Iter::new() {
        let card = card.map_err(|e| PcmError::Other(format!("enumerating sound cards: {e}")))?;
        let index = card.get_index();
        let Ok(ctl) = alsa::Ctl::new(&format!("hw:{index}"), false) else { continue };
        let Ok(info) = ctl.card_info() else { continue };
        let id = info.get_id().unwrap_or_default().to_owned();
        let card_name = card.get_longname().unwrap_or_default();
        for device in alsa::ctl::DeviceIter::new(&ctl) {
            let Ok(device_index) = u32::try_from(device) else { continue };
            // Devices of this direction only: a capture-only device has no playback PCM info, and back.
            if ctl.pcm_info(device_index, 0, direction).is_err() {
                continue;
            }
            let name = format!("hw:CARD={id},DEV={device}");
            let mut listing = PcmListing {
                name: name.clone(),
                card: card_name.clone(),
                channels: None,
                rates_hz: None,
                note: String::new(),
            };
            match pcm_ranges(&name, direction) {
                Ok((channels, rates)) => (listing.channels, listing.rates_hz) = (Some(channels), Some(rates)),
                Err(e) => listing.note = map_error(&name, "asking its ranges", e).to_string(),
            }
            found.push(listing);
        }
    }
    Ok(found)
}

/// The channel and rate ranges of the PCM `name` in `direction`, opened non-blocking and closed again.
#[allow(clippy::type_complexity)] // Two (lowest, highest) pairs: channels and rates.
fn pcm_ranges(name: &str, direction: Direction) -> Result<((u32, u32), (u32, u32)), alsa::Error> {
    let pcm = PCM::new(name, direction, true)?;
    let hw = HwParams::any(&pcm)?;
    Ok(((hw.get_channels_min()?, hw.get_channels_max()?), (hw.get_rate_min()?, hw.get_rate_max()?)))
}

/// (card name, card long name) of a PCM, or empty strings when it cannot be opened.
fn card_names(pcm_name: &str) -> (String, String) {
    let card = CString::new(pcm_name)
        .ok()
        .and_then(|name| PCM::open(&name, Direction::Playback, true).ok())
        .and_then(|pcm| pcm.info().ok().map(|info| info.get_card()));
    match card {
        Some(index) if index >= 0 => {
            let card = alsa::Card::new(index);
            (card.get_name().unwrap_or_default(), card.get_longname().unwrap_or_default())
        }
        _ => (String::new(), String::new()),
    }
}

/// An open PCM with what it really opened at: the sample format, rate and channels, period and buffer (frames).
pub(crate) type Opened = (PCM, SampleFormat, PcmParams, alsa::pcm::Frames, alsa::pcm::Frames);

/// Opens the PCM `name` in `direction` asking for `wanted`: the exact rate with ALSA's resampler off, interleaved
/// access, the channel count (nearest), the first format of [`SampleFormat::PREFERENCE`] it offers, and the buffer
/// and period times above; returns what it really opened (the caller compares it with what it asked).
///
/// # Errors
/// [`PcmError::Params`] for a rate that is not a whole number of frames per second, no channel, or none of the
/// formats; the mapped ALSA error of each step otherwise.
pub(crate) fn open_pcm(name: &str, direction: Direction, wanted: PcmParams) -> Result<Opened, PcmError> {
    let rate_hz = wanted.sample_rate_hz;
    // ALSA rates are whole numbers of frames per second.
    if !(rate_hz.is_finite() && rate_hz >= 1.0 && rate_hz <= f64::from(u32::MAX) && rate_hz.fract() == 0.0) {
        return Err(PcmError::Params(format!("{name}: {rate_hz} Hz is not a whole rate ALSA can ask for")));
    }
    if wanted.channels == 0 {
        return Err(PcmError::Params(format!("{name}: 0 channels")));
    }
    let c_name = CString::new(name).map_err(|_| PcmError::Params(format!("PCM name {name:?} contains a NUL byte")))?;
    let err = |doing: &'static str| move |e| map_error(name, doing, e);
    let doing_open = match direction {
        Direction::Playback => "opening for playback",
        Direction::Capture => "opening for capture",
    };
    let pcm = PCM::open(&c_name, direction, false).map_err(err(doing_open))?;
    let format = {
        let hw = HwParams::any(&pcm).map_err(err("reading its parameters"))?;
        // Refuse ALSA's own resampling: the device runs at the rate we ask, or we see that it does not.
        hw.set_rate_resample(false).map_err(err("turning resampling off"))?;
        hw.set_access(Access::RWInterleaved).map_err(err("asking for interleaved access"))?;
        // Nearest values, not exact ones: the device then opens at what it can, we read it back, and the
        // driver refuses a mismatch with both numbers in its message.
        hw.set_channels_near(wanted.channels).map_err(err("setting the channel count"))?;
        hw.set_rate_near(rate_hz as u32, ValueOr::Nearest).map_err(err("setting the rate"))?;
        let format =
            SampleFormat::PREFERENCE.into_iter().find(|f| hw.test_format(alsa_format(*f)).is_ok()).ok_or_else(
                || PcmError::Params(format!("{name}: offers none of FLOAT_LE, S32_LE, S24_LE, S24_3LE, S16_LE")),
            )?;
        hw.set_format(alsa_format(format)).map_err(err("setting the sample format"))?;
        hw.set_buffer_time_near(BUFFER_TIME_US, ValueOr::Nearest).map_err(err("setting the buffer time"))?;
        hw.set_period_time_near(PERIOD_TIME_US, ValueOr::Nearest).map_err(err("setting the period time"))?;
        pcm.hw_params(&hw).map_err(err("applying the parameters"))?;
        format
    };
    let (opened, period_frames, buffer_frames) = {
        let hw = pcm.hw_params_current().map_err(err("reading back its parameters"))?;
        let rate = hw.get_rate().map_err(err("reading back the rate"))?;
        let channels = hw.get_channels().map_err(err("reading back the channel count"))?;
        let period = hw.get_period_size().map_err(err("reading back the period"))?;
        let buffer = hw.get_buffer_size().map_err(err("reading back the buffer"))?;
        (PcmParams { sample_rate_hz: f64::from(rate), channels }, period, buffer)
    };
    Ok((pcm, format, opened, period_frames, buffer_frames))
}

/// Maps an ALSA error to a [`PcmError`], saying what was being done.
pub(crate) fn map_error(pcm_name: &str, doing: &str, error: alsa::Error) -> PcmError {
    let detail = format!("{pcm_name}: {doing}: {error}");
    match error.errno() {
        // Unplugged USB interfaces answer ENODEV (or ESHUTDOWN); a card that is gone has no PCM of that name.
        libc::ENODEV | libc::ENOENT | libc::ENXIO | libc::ESHUTDOWN => PcmError::Disconnected(detail),
        // The kernel gives up on a stream that stops progressing after about 10 s with EIO.
        libc::EIO | libc::ETIMEDOUT => PcmError::Timeout(detail),
        libc::EBUSY => PcmError::Unavailable(format!("{detail} (in use by another program?)")),
        libc::EINVAL => PcmError::Params(detail),
        libc::EBADFD => PcmError::State(detail),
        _ => PcmError::Other(detail),
    }
}

impl PcmSink for AlsaSink {
    fn describe(&self) -> (String, String, String) {
        (self.card.1.clone(), self.card.0.clone(), self.name.clone())
    }

    fn open(&mut self, wanted: PcmParams) -> Result<PcmParams, PcmError> {
        self.close();
        let (pcm, format, opened, period_frames, buffer_frames) = open_pcm(&self.name, Direction::Playback, wanted)?;
        let err = |doing: &str| {
            let pcm_name = self.name.clone();
            let doing = doing.to_string();
            move |e| map_error(&pcm_name, &doing, e)
        };
        {
            // Start only once the buffer is full (or explicitly, for a short buffer), not after the first period:
            // a stream started early underruns while the writer is still filling it.
            let sw = pcm.sw_params_current().map_err(err("reading the software parameters"))?;
            sw.set_start_threshold(buffer_frames).map_err(err("setting the start threshold"))?;
            pcm.sw_params(&sw).map_err(err("applying the software parameters"))?;
        }
        self.negotiated = Some(Negotiated {
            format,
            channels: opened.channels,
            period_frames: usize::try_from(period_frames).unwrap_or(1).max(1),
        });
        self.pcm = Some(pcm);
        Ok(opened)
    }

    fn submit(&mut self, interleaved: Vec<f32>) -> Result<(), PcmError> {
        if self.writer.is_some() {
            return Err(PcmError::State(format!("{}: submit while a buffer is still playing", self.name)));
        }
        let (Some(negotiated), Some(pcm)) = (self.negotiated, self.pcm.take()) else {
            return Err(PcmError::State(format!("{}: submit before open", self.name)));
        };
        let channels = negotiated.channels as usize;
        if interleaved.is_empty() || !interleaved.len().is_multiple_of(channels) {
            self.pcm = Some(pcm);
            return Err(PcmError::State(format!(
                "{}: {} samples is not a whole, nonzero number of {channels}-channel frames",
                self.name,
                interleaved.len()
            )));
        }
        let job = WriteJob {
            bytes: encode(&interleaved, negotiated.format),
            frame_bytes: channels * negotiated.format.bytes_per_sample(),
            chunk_frames: negotiated.period_frames,
            name: self.name.clone(),
        };
        self.stop.store(false, Ordering::Release);
        let stop = Arc::clone(&self.stop);
        let (started_tx, started_rx) = sync_channel(1);
        let spawned = std::thread::Builder::new()
            .name("alsa-writer".into())
            .spawn(move || job.run(pcm, &stop, &started_tx))
            .map_err(|e| {
                // The PCM moved into the closure that never ran; a reopen makes a new one.
                PcmError::Other(format!("{}: cannot start the writer thread: {e}", self.name))
            });
        match spawned {
            Ok(handle) => self.writer = Some(handle),
            Err(error) => {
                self.negotiated = None;
                return Err(error);
            }
        }
        self.await_start(&started_rx)
    }

    fn wait(&mut self) -> Result<PcmStatus, PcmError> {
        self.join_writer()
            .unwrap_or_else(|| Err(PcmError::State(format!("{}: wait with nothing submitted", self.name))))
    }

    fn close(&mut self) {
        self.stop.store(true, Ordering::Release);
        // The writer sees the flag at its next period and drops the stream; its outcome no longer matters.
        let _ = self.join_writer();
        // Dropping the PCM closes it (snd_pcm_close).
        self.pcm = None;
        self.negotiated = None;
    }
}

impl AlsaSink {
    /// Waits until the writer says playback started (or failed before starting).
    fn await_start(&mut self, started: &Receiver<Result<(), PcmError>>) -> Result<(), PcmError> {
        match started.recv() {
            Ok(Ok(())) => Ok(()),
            // Failed before the stream ran: collect the thread so that the caller can retry or reopen.
            Ok(Err(error)) => {
                let _ = self.join_writer();
                Err(error)
            }
            // The thread ended without a word: its outcome says why.
            Err(_) => match self.join_writer() {
                Some(Err(error)) => Err(error),
                _ => Err(PcmError::Other(format!("{}: the writer ended before playback started", self.name))),
            },
        }
    }
}

/// One buffer to write, as the device's bytes.
struct WriteJob {
    bytes: Vec<u8>,
    frame_bytes: usize,
    chunk_frames: usize,
    name: String,
}

impl WriteJob {
    /// The writer thread's body: plays the buffer, tells `started` when the stream runs (or why it failed),
    /// and hands back the PCM with the outcome.
    fn run(self, pcm: PCM, stop: &AtomicBool, started: &SyncSender<Result<(), PcmError>>) -> WriterOutcome {
        let result = self.play(&pcm, stop, started);
        if let Err(error) = &result {
            // Ignored when the start was already reported (the receiver is gone): `wait` returns the error.
            let _ = started.try_send(Err(error.clone()));
        }
        (pcm, result)
    }

    fn play(
        &self,
        pcm: &PCM,
        stop: &AtomicBool,
        started: &SyncSender<Result<(), PcmError>>,
    ) -> Result<PcmStatus, PcmError> {
        let err = |doing: &'static str| move |e| map_error(&self.name, doing, e);
        if pcm.state() != State::Prepared {
            pcm.prepare().map_err(err("preparing the stream"))?;
        }
        let total_frames = self.bytes.len() / self.frame_bytes;
        let mut written = 0;
        let mut underruns = 0_u32;
        let mut signalled = false;
        let signal = |signalled: &mut bool| {
            if !*signalled {
                *signalled = true;
                let _ = started.try_send(Ok(()));
            }
        };
        {
            let io = pcm.io_bytes();
            while written < total_frames {
                if stop.load(Ordering::Acquire) {
                    pcm.drop().map_err(err("stopping the stream"))?;
                    return Ok(PcmStatus { frames_played: written as u64, underruns });
                }
                let end = (written + self.chunk_frames).min(total_frames);
                match io.writei(&self.bytes[written * self.frame_bytes..end * self.frame_bytes]) {
                    Ok(frames) => written += frames,
                    // EPIPE: underrun; ESTRPIPE: suspended. Recover and carry on where we were.
                    Err(e) if e.errno() == libc::EPIPE || e.errno() == libc::ESTRPIPE => {
                        underruns = underruns.saturating_add(1);
                        pcm.try_recover(e, true).map_err(err("recovering from an underrun"))?;
                    }
                    // Interrupted, or (unexpectedly, the stream blocks) not ready: wait for room, bounded, and retry.
                    Err(e) if e.errno() == libc::EAGAIN || e.errno() == libc::EINTR => {
                        pcm.wait(Some(WAIT_FOR_ROOM_MS)).map_err(err("waiting for room in the buffer"))?;
                    }
                    Err(e) => return Err(map_error(&self.name, "writing samples", e)),
                }
                if pcm.state() == State::Running {
                    signal(&mut signalled);
                }
            }
        }
        // A buffer shorter than the device's never reached the start threshold.
        if pcm.state() == State::Prepared {
            pcm.start().map_err(err("starting the stream"))?;
        }
        signal(&mut signalled);
        match pcm.drain() {
            Ok(()) => {}
            // An underrun while draining: the tail played late or not at all.
            Err(e) if e.errno() == libc::EPIPE => underruns = underruns.saturating_add(1),
            Err(e) => return Err(map_error(&self.name, "draining the stream", e)),
        }
        Ok(PcmStatus { frames_played: total_frames as u64, underruns })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_with_nul_is_a_typed_error() {
        let mut sink = AlsaSink::new("hw:\0");
        let err = sink.open(PcmParams { sample_rate_hz: 48_000.0, channels: 2 }).unwrap_err();
        assert!(matches!(err, PcmError::Params(_)), "{err:?}");
    }

    #[test]
    fn fractional_rates_are_refused_before_touching_alsa() {
        let mut sink = AlsaSink::new("null");
        for rate in [44_100.5, 0.0, -48_000.0, f64::NAN, f64::INFINITY, 1e10] {
            let err = sink.open(PcmParams { sample_rate_hz: rate, channels: 2 }).unwrap_err();
            assert!(matches!(err, PcmError::Params(_)), "{rate}: {err:?}");
        }
    }

    #[test]
    fn misuse_is_a_state_error() {
        let mut sink = AlsaSink::new("null");
        assert!(matches!(sink.submit(vec![0.0; 4]), Err(PcmError::State(_))));
        assert!(matches!(sink.wait(), Err(PcmError::State(_))));
        sink.close();
        sink.close();
    }
}

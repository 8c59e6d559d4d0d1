//! The plain data a cassette holds: a header and records. Everything here is public fields, `Clone` and
//! `PartialEq`, so a replayer (or a fault injector) can walk, copy and modify records freely; the encoder checks
//! them again before writing.

use crate::error::Invalid;
use crate::layout::{MAX_IDENTITY_FIELD_LEN, MAX_NOTE_LEN};

/// The kind of device a session was recorded with (the wire protocol its bytes follow).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceKind {
    /// The scanning laser Doppler vibrometer's controller, on a serial line.
    LdvSerial,
    /// The DAQ, on USB bulk endpoints.
    DaqUsb,
    /// The multichannel audio interface.
    Audio,
    /// A HID device.
    Hid,
}

impl DeviceKind {
    /// Every device kind, in code order.
    pub const ALL: [DeviceKind; 4] = [DeviceKind::LdvSerial, DeviceKind::DaqUsb, DeviceKind::Audio, DeviceKind::Hid];

    /// Its code in the header (1..=4).
    pub fn code(self) -> u8 {
        match self {
            DeviceKind::LdvSerial => 1,
            DeviceKind::DaqUsb => 2,
            DeviceKind::Audio => 3,
            DeviceKind::Hid => 4,
        }
    }

    /// The device kind with this code, or `None` for a code this version does not know.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.code() == code)
    }
}

/// Who the device was. Each field is UTF-8 of at most [`MAX_IDENTITY_FIELD_LEN`] bytes; empty when unknown.
#[derive(Debug, Clone, PartialEq, Eq, Default, Hash)]
pub struct DeviceIdentity {
    /// Manufacturer.
    pub vendor: String,
    /// Model name or number.
    pub model: String,
    /// Serial number.
    pub serial: String,
    /// Firmware version.
    pub firmware: String,
}

impl DeviceIdentity {
    /// The fields with their names, in file order.
    pub(crate) fn fields(&self) -> [(&'static str, &str); 4] {
        [("vendor", &self.vendor), ("model", &self.model), ("serial", &self.serial), ("firmware", &self.firmware)]
    }

    /// Checks every field's length.
    ///
    /// # Errors
    /// [`Invalid::FieldTooLong`] for the first field over [`MAX_IDENTITY_FIELD_LEN`] bytes.
    pub fn check(&self) -> Result<(), Invalid> {
        for (field, text) in self.fields() {
            if text.len() > MAX_IDENTITY_FIELD_LEN {
                return Err(Invalid::FieldTooLong { field, len: text.len(), max: MAX_IDENTITY_FIELD_LEN });
            }
        }
        Ok(())
    }
}

/// A cassette's header: what was recorded, and when.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Header {
    /// The kind of device.
    pub device_kind: DeviceKind,
    /// The device's identity.
    pub identity: DeviceIdentity,
    /// When the recording started, ns since the Unix epoch (informational only: record timestamps are relative to
    /// the session start, and replay never reads a clock).
    pub start_unix_ns: u64,
}

/// One recorded happening in a session.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// When it happened, ns since the session start. Never decreases from one record to the next.
    pub t_ns: u64,
    /// The endpoint or channel id it happened on (a USB endpoint, a serial port index, an audio stream), as the
    /// device's driver numbers them.
    pub endpoint: u16,
    /// What happened.
    pub body: Body,
}

/// What a record holds.
#[derive(Debug, Clone, PartialEq)]
pub enum Body {
    /// Bytes the host sent to the device.
    HostToDevice(Vec<u8>),
    /// Bytes the device sent to the host.
    DeviceToHost(Vec<u8>),
    /// A block of samples of a sample stream.
    Stream(StreamBlock),
    /// A session event.
    Event(Event),
}

impl Body {
    /// Its record-kind code in the file (1..=4).
    pub fn kind_code(&self) -> u8 {
        match self {
            Body::HostToDevice(_) => 1,
            Body::DeviceToHost(_) => 2,
            Body::Stream(_) => 3,
            Body::Event(_) => 4,
        }
    }
}

/// A block of interleaved samples of a sample stream (frame-major: sample `i` of channel `c` is
/// `samples[i * channels + c]`).
#[derive(Debug, Clone, PartialEq)]
pub struct StreamBlock {
    /// Channels per frame, at least 1.
    pub channels: u16,
    /// Sample rate, Hz: finite and positive.
    pub sample_rate_hz: f64,
    /// Index of this block's first frame in the stream (counts frames, not interleaved samples).
    pub first_sample_index: u64,
    /// The samples, a whole number of frames.
    pub samples: Samples,
}

impl StreamBlock {
    /// Checks the block: at least one channel, a finite positive rate, whole frames, finite samples.
    ///
    /// # Errors
    /// [`Invalid::ZeroChannels`], [`Invalid::SampleRate`], [`Invalid::PartialFrame`] or
    /// [`Invalid::NonFiniteSample`].
    pub fn check(&self) -> Result<(), Invalid> {
        if self.channels == 0 {
            return Err(Invalid::ZeroChannels);
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(Invalid::SampleRate { sample_rate_hz: self.sample_rate_hz });
        }
        let channels = usize::from(self.channels);
        if !self.samples.len().is_multiple_of(channels) {
            return Err(Invalid::PartialFrame { samples: self.samples.len(), channels });
        }
        if let Samples::F32(x) = &self.samples
            && let Some(index) = x.iter().position(|v| !v.is_finite())
        {
            return Err(Invalid::NonFiniteSample { index, value: x[index] });
        }
        Ok(())
    }

    /// Number of frames (samples per channel).
    pub fn frames(&self) -> usize {
        // `check` guarantees channels >= 1; max(1) keeps an unchecked block from dividing by zero.
        self.samples.len() / usize::from(self.channels.max(1))
    }
}

/// Samples in their recorded format.
#[derive(Debug, Clone, PartialEq)]
pub enum Samples {
    /// Signed 16-bit integers (a DAQ's raw codes).
    I16(Vec<i16>),
    /// 32-bit floats (an audio stream), finite.
    F32(Vec<f32>),
}

impl Samples {
    /// Number of samples (all channels).
    pub fn len(&self) -> usize {
        match self {
            Samples::I16(x) => x.len(),
            Samples::F32(x) => x.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes per sample in the file (2 or 4).
    pub fn sample_size(&self) -> usize {
        match self {
            Samples::I16(_) => 2,
            Samples::F32(_) => 4,
        }
    }

    /// Its sample-format code in the file (1 = i16, 2 = f32).
    pub fn format_code(&self) -> u8 {
        match self {
            Samples::I16(_) => 1,
            Samples::F32(_) => 2,
        }
    }
}

/// A session event.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// The host opened the device.
    Open,
    /// The host closed the device.
    Close,
    /// A transfer or reply timed out.
    Timeout,
    /// The device disappeared (unplugged, powered off).
    Disconnect,
    /// The device came back.
    Reconnect,
    /// A free-text note (UTF-8, at most [`MAX_NOTE_LEN`] bytes): what the recorder wants a reader to know.
    Note(String),
}

impl Event {
    /// Its event-kind code in the file (1..=6).
    pub fn code(&self) -> u8 {
        match self {
            Event::Open => 1,
            Event::Close => 2,
            Event::Timeout => 3,
            Event::Disconnect => 4,
            Event::Reconnect => 5,
            Event::Note(_) => 6,
        }
    }

    /// Its name, for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Event::Open => "open",
            Event::Close => "close",
            Event::Timeout => "timeout",
            Event::Disconnect => "disconnect",
            Event::Reconnect => "reconnect",
            Event::Note(_) => "note",
        }
    }

    /// The event with this code, with its text; `Ok(None)` for a code this version does not know.
    ///
    /// # Errors
    /// [`Invalid::EventText`] when an event other than a note carries text; [`Invalid::Utf8`] or
    /// [`Invalid::FieldTooLong`] for a bad note.
    pub(crate) fn from_code(code: u8, text: &[u8]) -> Result<Option<Self>, Invalid> {
        let event = match code {
            1 => Event::Open,
            2 => Event::Close,
            3 => Event::Timeout,
            4 => Event::Disconnect,
            5 => Event::Reconnect,
            6 => {
                // Length first, so an over-long note is refused before it is copied.
                if text.len() > MAX_NOTE_LEN {
                    return Err(Invalid::FieldTooLong { field: "note", len: text.len(), max: MAX_NOTE_LEN });
                }
                let note = std::str::from_utf8(text).map_err(|_| Invalid::Utf8 { field: "note" })?;
                return Ok(Some(Event::Note(note.to_owned())));
            }
            _ => return Ok(None),
        };
        if !text.is_empty() {
            return Err(Invalid::EventText { event: event.name(), len: text.len() });
        }
        Ok(Some(event))
    }

    /// Checks a note's length.
    ///
    /// # Errors
    /// [`Invalid::FieldTooLong`] for a note over [`MAX_NOTE_LEN`] bytes.
    pub fn check(&self) -> Result<(), Invalid> {
        match self {
            Event::Note(text) if text.len() > MAX_NOTE_LEN => {
                Err(Invalid::FieldTooLong { field: "note", len: text.len(), max: MAX_NOTE_LEN })
            }
            _ => Ok(()),
        }
    }
}

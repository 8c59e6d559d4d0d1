//! Record payloads: a [`Body`] to bytes and back. The record framing around them lives in `encode` and `decode`.

use crate::error::Invalid;
use crate::layout::{Fields, STREAM_HEAD_LEN};
use crate::model::{Body, Event, Samples, StreamBlock};

/// Why a payload could not be decoded.
#[derive(Debug)]
pub(crate) enum PayloadError {
    /// A kind code this version does not know: (which code, the code).
    Unknown(&'static str, u8),
    /// Sound framing, invalid content.
    Invalid(Invalid),
}

impl From<Invalid> for PayloadError {
    fn from(reason: Invalid) -> Self {
        PayloadError::Invalid(reason)
    }
}

/// The payload length `body` encodes to, bytes (saturating, so an absurd body is refused as oversize).
pub(crate) fn payload_len(body: &Body) -> usize {
    match body {
        Body::HostToDevice(bytes) | Body::DeviceToHost(bytes) => bytes.len(),
        Body::Stream(block) => {
            STREAM_HEAD_LEN.saturating_add(block.samples.len().saturating_mul(block.samples.sample_size()))
        }
        Body::Event(Event::Note(text)) => 1usize.saturating_add(text.len()),
        Body::Event(_) => 1,
    }
}

/// Checks a body's content (not its size).
///
/// # Errors
/// The [`Invalid`] reason of a bad stream block or note.
pub(crate) fn check_body(body: &Body) -> Result<(), Invalid> {
    match body {
        Body::HostToDevice(_) | Body::DeviceToHost(_) => Ok(()),
        Body::Stream(block) => block.check(),
        Body::Event(event) => event.check(),
    }
}

/// Appends `body`'s payload to `out`. The body must have passed [`check_body`].
pub(crate) fn write_payload(body: &Body, out: &mut Vec<u8>) {
    match body {
        Body::HostToDevice(bytes) | Body::DeviceToHost(bytes) => out.extend_from_slice(bytes),
        Body::Stream(block) => {
            out.extend_from_slice(&block.channels.to_le_bytes());
            out.push(block.samples.format_code());
            out.extend_from_slice(&block.sample_rate_hz.to_le_bytes());
            out.extend_from_slice(&block.first_sample_index.to_le_bytes());
            match &block.samples {
                Samples::I16(x) => x.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
                Samples::F32(x) => x.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes())),
            }
        }
        Body::Event(event) => {
            out.push(event.code());
            if let Event::Note(text) = event {
                out.extend_from_slice(text.as_bytes());
            }
        }
    }
}

/// Decodes the payload of a record of kind `kind_code`.
///
/// # Errors
/// [`PayloadError::Unknown`] for an unknown record kind, sample format or event kind; [`PayloadError::Invalid`]
/// for content that breaks the format's rules.
pub(crate) fn read_payload(kind_code: u8, payload: &[u8]) -> Result<Body, PayloadError> {
    match kind_code {
        1 => Ok(Body::HostToDevice(payload.to_vec())),
        2 => Ok(Body::DeviceToHost(payload.to_vec())),
        3 => read_stream(payload).map(Body::Stream),
        4 => read_event(payload).map(Body::Event),
        code => Err(PayloadError::Unknown("record kind", code)),
    }
}

fn read_stream(payload: &[u8]) -> Result<StreamBlock, PayloadError> {
    if payload.len() < STREAM_HEAD_LEN {
        return Err(Invalid::StreamTooShort { len: payload.len(), min: STREAM_HEAD_LEN }.into());
    }
    let mut f = Fields::new(payload, 0);
    let channels = f.u16();
    let format = f.u8();
    let sample_rate_hz = f.f64();
    let first_sample_index = f.u64();
    let data = &payload[f.position()..];
    if channels == 0 {
        return Err(Invalid::ZeroChannels.into());
    }
    let sample_size = match format {
        1 => 2,
        2 => 4,
        code => return Err(PayloadError::Unknown("sample format", code)),
    };
    // Whole frames only; checked on bytes, before the samples are allocated.
    let frame_bytes = usize::from(channels) * sample_size;
    if !data.len().is_multiple_of(frame_bytes) {
        return Err(Invalid::PartialFrame { samples: data.len(), channels: frame_bytes }.into());
    }
    let samples = if format == 1 {
        Samples::I16(data.chunks_exact(2).map(|c| i16::from_le_bytes([c[0], c[1]])).collect())
    } else {
        Samples::F32(data.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
    };
    let block = StreamBlock { channels, sample_rate_hz, first_sample_index, samples };
    block.check()?;
    Ok(block)
}

fn read_event(payload: &[u8]) -> Result<Event, PayloadError> {
    let Some((&code, text)) = payload.split_first() else {
        return Err(Invalid::EmptyEvent.into());
    };
    Event::from_code(code, text)?.ok_or(PayloadError::Unknown("event kind", code))
}

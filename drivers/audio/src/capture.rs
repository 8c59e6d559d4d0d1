//! The audio interface as the DAQ: an ALSA capture PCM read as the [`Daq`] capability.
//!
//! Many labs record the vibrometer's velocity output and the loopback on inputs of the same multichannel interface
//! that plays the drive: one clock, no drift between playback and recording. The stream is opened as playback is
//! ([`crate::alsa`]): the exact rate with ALSA's resampler off (a device that opens at another rate is refused with
//! both numbers), interleaved access, the first sample format it offers among `FLOAT_LE`, `S32_LE`, `S24_LE`,
//! `S24_3LE`, `S16_LE`. A DAQ channel's `input` is the interface's input (channel of the PCM, from 0). An interface's
//! inputs have one range: the voltage at digital full scale, declared in the hardware file (`full_scale_v`, from the
//! interface's manual, e.g. +/-1.74 V for +4 dBu line inputs at 0 dB gain); a channel must ask exactly that range.
//!
//! The channel map: the positions the PCM reports for its channels once open (`snd_pcm_get_chmap`, ALSA's short
//! names: `FL FR`, `AUX0 AUX1 ...`; many interfaces report none) are added to the identity's model once the stream
//! is open; a hardware file that names the map it expects ([`AlsaCaptureDaq::expect_channel_map`]) has any other
//! PCM refused when the stream opens, naming both (another interface behind the name, or a routing changed).

use alsa::Direction;
use alsa::pcm::PCM;
use metaplate_core::daq::{BlockIntegrity, Daq, DaqBlock, DaqConfig, DaqError, DaqIdentity};

use crate::alsa::{map_error, open_pcm};
use crate::samples::{SampleFormat, decode};
use crate::sink::{PcmError, PcmParams};

/// The largest block, frames: a DAQ block is read in one piece (about 20 s at 48 kHz).
const MAX_BLOCK_FRAMES: u32 = 1 << 20;

/// How long one wait for captured frames may take before the read times out, ms (many periods).
const WAIT_MS: u32 = 2_000;

/// What the open stream is.
struct Stream {
    pcm: PCM,
    format: SampleFormat,
    channels: usize,
}

/// An ALSA capture PCM as a DAQ.
pub struct AlsaCaptureDaq {
    name: String,
    full_scale_v: f64,
    expected_channel_map: Option<Vec<String>>,
    identity: DaqIdentity,
    stream: Option<Stream>,
    config: Option<DaqConfig>,
    running: bool,
    next_sample_index: u64,
}

impl AlsaCaptureDaq {
    /// A DAQ on the capture PCM `pcm_name` (`hw:CARD=24Ao,DEV=0`) whose inputs read `full_scale_v` volts at
    /// digital full scale. Nothing is opened until [`Daq::configure`].
    pub fn new(pcm_name: &str, full_scale_v: f64) -> Self {
        let identity = DaqIdentity {
            vendor: "ALSA".into(),
            model: format!("capture PCM {pcm_name}"),
            serial: pcm_name.into(),
            // The driver library; the interface itself reports no firmware through ALSA.
            firmware: "libasound".into(),
        };
        Self {
            name: pcm_name.into(),
            full_scale_v,
            expected_channel_map: None,
            identity,
            stream: None,
            config: None,
            running: false,
            next_sample_index: 0,
        }
    }

    /// Refuses to configure unless the PCM reports exactly this channel map: one ALSA short name per channel the
    /// stream opens with, in channel order (`["FL", "FR"]`; case ignored). The stream asks for as many channels as
    /// the highest input used: a `hw:` PCM opens with its own count, but a `plughw:` one with exactly that many,
    /// so name the map of those. Without it any map, or none, is taken.
    pub fn expect_channel_map(mut self, positions: Vec<String>) -> Self {
        self.expected_channel_map = Some(positions.iter().map(|p| p.trim().to_ascii_uppercase()).collect());
        self
    }

    /// The sample format the open stream reads, if open.
    pub fn sample_format(&self) -> Option<SampleFormat> {
        self.stream.as_ref().map(|s| s.format)
    }

    fn check(&self, config: &DaqConfig) -> Result<(), DaqError> {
        let invalid = |detail: String| Err(DaqError::Config { detail: format!("{}: {detail}", self.name) });
        if !(self.full_scale_v.is_finite() && self.full_scale_v > 0.0) {
            return invalid(format!("full scale {} V is not a finite voltage above 0", self.full_scale_v));
        }
        if config.channels.is_empty() {
            return invalid("no channel".into());
        }
        for (i, channel) in config.channels.iter().enumerate() {
            if config.channels[..i].iter().any(|c| c.input == channel.input) {
                return invalid(format!("input {} is listed twice", channel.input));
            }
            // One range per interface: within a part in a million of the declared full scale (NaN is not).
            let matches = (channel.range_v / self.full_scale_v - 1.0).abs() < 1e-6;
            if !matches {
                return invalid(format!(
                    "input {} asks +/-{} V; the interface's inputs read +/-{} V at full scale (its `full_scale_v`)",
                    channel.input, channel.range_v, self.full_scale_v
                ));
            }
        }
        if !(1..=MAX_BLOCK_FRAMES).contains(&config.block_len_samples) {
            return invalid(format!("block of {} samples is not 1 to {MAX_BLOCK_FRAMES}", config.block_len_samples));
        }
        Ok(())
    }

    fn open(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        self.stream = None;
        let highest = config.channels.iter().map(|c| u32::from(c.input)).max().unwrap_or(0);
        let wanted = PcmParams { sample_rate_hz: config.sample_rate_hz, channels: highest + 1 };
        let (pcm, format, opened, _, _) = open_pcm(&self.name, Direction::Capture, wanted).map_err(daq_error)?;
        if opened.sample_rate_hz != wanted.sample_rate_hz {
            return Err(DaqError::Config {
                detail: format!(
                    "{}: opened at {} Hz, asked {} Hz (the interface runs at another rate: set it to the asked one)",
                    self.name, opened.sample_rate_hz, wanted.sample_rate_hz
                ),
            });
        }
        if opened.channels <= highest {
            return Err(DaqError::Config {
                detail: format!("{}: has {} inputs, input {highest} asked", self.name, opened.channels),
            });
        }
        let reported = channel_map(&pcm);
        if let Some(expected) = &self.expected_channel_map {
            let name = &self.name;
            let expected_text = expected.join(" ");
            match &reported {
                None => {
                    return Err(DaqError::Config {
                        detail: format!(
                            "{name}: reports no channel map; the hardware file expects `{expected_text}` \
                             (`daq.channel_map`)"
                        ),
                    });
                }
                Some(map) if map != expected => {
                    return Err(DaqError::Config {
                        detail: format!(
                            "{name}: its channel map is `{}`; the hardware file expects `{expected_text}` \
                             (`daq.channel_map`): another interface behind this name, or its routing changed",
                            map.join(" ")
                        ),
                    });
                }
                Some(_) => {}
            }
        }
        self.identity.model = match &reported {
            Some(map) => format!("capture PCM {} (channel map {})", self.name, map.join(" ")),
            None => format!("capture PCM {}", self.name),
        };
        self.stream = Some(Stream { pcm, format, channels: opened.channels as usize });
        Ok(())
    }

    fn read_frames(&self, frames: usize) -> Result<Vec<u8>, DaqError> {
        let name = &self.name;
        let Some(stream) = self.stream.as_ref() else {
            return Err(DaqError::Protocol { detail: format!("{name}: read before configure") });
        };
        let frame_bytes = stream.channels * stream.format.bytes_per_sample();
        let mut bytes = vec![0_u8; frames * frame_bytes];
        let mut filled = 0;
        let io = stream.pcm.io_bytes();
        while filled < frames {
            let ready =
                stream.pcm.wait(Some(WAIT_MS)).map_err(|e| daq_error(map_error(name, "waiting for samples", e)))?;
            if !ready {
                return Err(DaqError::Timeout { what: format!("{name}: captured samples"), attempts: 1 });
            }
            match io.readi(&mut bytes[filled * frame_bytes..]) {
                Ok(n) => filled += n,
                // EPIPE: the device's buffer overflowed before we read; the samples are gone.
                Err(e) if e.errno() == libc::EPIPE => {
                    return Err(DaqError::Overrun {
                        detail: format!(
                            "{name}: the capture buffer overflowed ({} samples read so far)",
                            self.next_sample_index
                        ),
                    });
                }
                Err(e) => return Err(daq_error(map_error(name, "reading samples", e))),
            }
        }
        Ok(bytes)
    }
}

impl Daq for AlsaCaptureDaq {
    fn identity(&self) -> &DaqIdentity {
        &self.identity
    }

    fn configure(&mut self, config: &DaqConfig) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: format!("{}: configure while running", self.name) });
        }
        self.check(config)?;
        self.open(config)?;
        self.config = Some(config.clone());
        Ok(())
    }

    fn start(&mut self) -> Result<(), DaqError> {
        if self.running {
            return Err(DaqError::Protocol { detail: format!("{}: start while running", self.name) });
        }
        let name = self.name.clone();
        let Some(stream) = self.stream.as_ref() else {
            return Err(DaqError::Protocol { detail: format!("{name}: start before configure") });
        };
        stream.pcm.prepare().map_err(|e| daq_error(map_error(&name, "preparing the stream", e)))?;
        stream.pcm.start().map_err(|e| daq_error(map_error(&name, "starting the capture", e)))?;
        self.running = true;
        self.next_sample_index = 0;
        Ok(())
    }

    fn read_block(&mut self) -> Result<DaqBlock, DaqError> {
        let (true, Some(frames)) = (self.running, self.config.as_ref().map(|c| c.block_len_samples as usize)) else {
            return Err(DaqError::Protocol { detail: format!("{}: read while not running", self.name) });
        };
        // An overrun or a fault ends the acquisition, as the capability says.
        let bytes = match self.read_frames(frames) {
            Ok(bytes) => bytes,
            Err(e) => {
                self.running = false;
                return Err(e);
            }
        };
        let (Some(stream), Some(config)) = (self.stream.as_ref(), self.config.as_ref()) else {
            return Err(DaqError::Protocol { detail: format!("{}: the stream went away", self.name) });
        };
        let values = decode(&bytes, stream.format);
        let mut clipped = false;
        let volts: Vec<Vec<f64>> = config
            .channels
            .iter()
            .map(|c| {
                values
                    .iter()
                    .skip(usize::from(c.input))
                    .step_by(stream.channels)
                    .map(|&x| {
                        clipped |= x.abs() >= 1.0;
                        x * self.full_scale_v
                    })
                    .collect()
            })
            .collect();
        let block = DaqBlock {
            first_sample_index: self.next_sample_index,
            volts,
            integrity: BlockIntegrity { clipped, ..BlockIntegrity::default() },
        };
        self.next_sample_index += frames as u64;
        Ok(block)
    }

    fn stop(&mut self) -> Result<(), DaqError> {
        if let (true, Some(stream)) = (self.running, self.stream.as_ref()) {
            stream.pcm.drop().map_err(|e| daq_error(map_error(&self.name, "stopping the capture", e)))?;
        }
        self.running = false;
        Ok(())
    }

    fn reopen(&mut self) -> Result<(), DaqError> {
        self.running = false;
        self.stream = None;
        match self.config.clone() {
            Some(config) => self.open(&config),
            None => Ok(()),
        }
    }
}

/// The channel positions `pcm` reports once open, ALSA's short names in channel order; `None` when it reports none
/// (many interfaces and plugins) or the map cannot be printed.
fn channel_map(pcm: &PCM) -> Option<Vec<String>> {
    use std::fmt::Write as _;
    let map = pcm.get_chmap().ok()?;
    // Through `write!`, not `to_string`: the crate's `Display` fails (rather than prints) a map ALSA cannot print.
    let mut text = String::new();
    write!(text, "{map}").ok()?;
    let positions: Vec<String> = text.split_whitespace().map(str::to_ascii_uppercase).collect();
    (!positions.is_empty()).then_some(positions)
}

/// A PCM error as the DAQ capability's.
fn daq_error(error: PcmError) -> DaqError {
    match error {
        PcmError::Params(detail) => DaqError::Config { detail },
        PcmError::Timeout(what) => DaqError::Timeout { what, attempts: 1 },
        PcmError::Disconnected(detail) => DaqError::Disconnected { detail },
        PcmError::State(detail) => DaqError::Protocol { detail },
        PcmError::Unavailable(detail) => DaqError::Unavailable { detail },
        PcmError::Other(detail) => DaqError::Device { code: 0, detail },
    }
}

//! The hardware file: parsed and checked without opening anything (the format is in the crate documentation).

use std::path::{Path, PathBuf};

use metaplate_core::rig::Wiring;
use metaplate_core::vibrometer::VibrometerIdentity;
use metaplate_daq::{DriverSettings, UsbSelector};
use metaplate_ldv::{AnalogVibrometer, BAUD_RATE, DecoderChoice, FocusSpan, MAX_DECODERS, PolytecConfig, PortSelector};
use metaplate_u6_protocol::config::MAX_STREAM_RESOLUTION_INDEX;
use serde::Deserialize;
use serde::de::DeserializeOwned;

use crate::aim::AimSection;
use crate::backends::{self, Capability};
use crate::nidaqmx::NidaqmxDaq;

/// Why a hardware file cannot be used as it is, or its rig cannot be opened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HardwareError {
    /// The file cannot be read or parsed, or a value in it is missing, unknown or out of range.
    #[error("hardware file {}: {key}: {reason}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// The key in error (`daq.backend`, `wiring`), or `(file)` for the file as a whole.
        key: String,
        /// What is wrong (with the TOML parser's line and column when it has them).
        reason: String,
    },
    /// The file names a backend this build of metaplate does not have (a cargo feature off, or an operating system
    /// without it).
    #[error("hardware file {}: {key} = \"{backend}\": {reason}", path.display())]
    NotInThisBuild {
        /// The file.
        path: PathBuf,
        /// The key naming the backend (`audio.backend`).
        key: String,
        /// The backend named.
        backend: &'static str,
        /// Why it is missing and how to get it.
        reason: String,
    },
    /// An instrument could not be opened.
    #[error("cannot open the {device} `{name}` ({backend}): {detail}")]
    Device {
        /// Which instrument (`LDV`, `DAQ`, `audio interface`, `keypad`, `aimer`).
        device: &'static str,
        /// Its backend.
        backend: &'static str,
        /// How the file names it (port, USB ids, device name).
        name: String,
        /// The driver's error.
        detail: String,
    },
    /// One or more instruments could not be opened: each one's error, in the order LDV, DAQ, audio interface,
    /// keypad, aim (for a check every one is tried; otherwise opening stops at the first, [`crate::OpenPurpose`]).
    #[error("{}", failures.iter().map(ToString::to_string).collect::<Vec<_>>().join("; "))]
    Devices {
        /// Each instrument's error ([`HardwareError::Device`], or [`HardwareError::File`] for a file it names).
        failures: Vec<HardwareError>,
    },
    /// The scene the file names as its `plate` cannot be read, or is invalid.
    #[error(transparent)]
    Scene(#[from] metaplate_core::scene::SceneError),
    /// The wiring does not fit the plate.
    #[error("hardware file {}: {reason}", path.display())]
    Plate {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
}

impl HardwareError {
    /// Each instrument of a [`HardwareError::Devices`] that could not be opened: its hardware file section (`ldv`,
    /// `daq`, `audio`, `keypad`, `aim`) and the error's message. Empty for any other error (of the file, its plate,
    /// the build): nothing was opened.
    pub fn failed_instruments(&self) -> Vec<(&'static str, String)> {
        let HardwareError::Devices { failures } = self else { return Vec::new() };
        let section = |failure: &HardwareError| match failure {
            HardwareError::Device { device, .. } => {
                Capability::ALL.into_iter().find(|c| c.noun() == *device).map(Capability::section)
            }
            HardwareError::File { key, .. } => {
                let prefix = key.split('.').next().unwrap_or_default();
                Capability::ALL.into_iter().map(Capability::section).find(|s| *s == prefix)
            }
            _ => None,
        };
        failures.iter().map(|failure| (section(failure).unwrap_or("rig"), failure.to_string())).collect()
    }
}

/// `[ldv]`: the vibrometer.
#[derive(Debug, Clone, PartialEq)]
pub enum LdvSection {
    /// `backend = "polytec"`: a Polytec controller (OFV-5000, VibroFlex) on an RS-232 port.
    Polytec(PolytecLdv),
    /// `backend = "analog"`: a vibrometer without a remote interface; its range is declared here.
    Analog(AnalogLdv),
}

/// `[ldv]` with `backend = "polytec"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolytecLdv {
    /// Serial port path (`/dev/serial/by-id/...`, `COM3`).
    pub port: PathBuf,
    /// Baud rate; must be the one the driver opens at ([`BAUD_RATE`]); optional.
    #[serde(default = "default_baud")]
    pub baud: u32,
    /// The velocity decoder: its name (`"VD-09"`) or index (`1` for `VeloDec,1`); without it the driver takes the
    /// first velocity decoder the unit reports.
    pub decoder: Option<toml::Value>,
    /// The decoder's low-pass filter as the unit spells it (`"20kHz"`), if any.
    pub low_pass: Option<String>,
    /// Autofocus at open and after a reconnect: `"Full"`, `"Medium"` or `"Small"`; optional.
    pub autofocus: Option<String>,
}

fn default_baud() -> u32 {
    BAUD_RATE
}

impl PolytecLdv {
    /// The port selector of this section.
    pub fn selector(&self) -> PortSelector {
        PortSelector::Path(self.port.clone())
    }

    /// The driver's configuration of this section.
    ///
    /// # Errors
    /// A sentence naming the key (`decoder`, `autofocus`) and what is wrong with it.
    pub fn config(&self) -> Result<PolytecConfig, String> {
        let decoder = match &self.decoder {
            None => DecoderChoice::First,
            Some(toml::Value::String(name)) if !name.trim().is_empty() => DecoderChoice::Name(name.trim().to_owned()),
            Some(toml::Value::Integer(i)) => u8::try_from(*i)
                .ok()
                .filter(|i| *i < MAX_DECODERS)
                .map(DecoderChoice::Index)
                .ok_or_else(|| format!("decoder = {i}: an index is 0 to {}", MAX_DECODERS - 1))?,
            Some(other) => return Err(format!("decoder = {other}: a name (\"VD-09\") or an index (1)")),
        };
        let autofocus = match self.autofocus.as_deref() {
            None => None,
            Some("Full") => Some(FocusSpan::Full),
            Some("Medium") => Some(FocusSpan::Medium),
            Some("Small") => Some(FocusSpan::Small),
            Some(other) => return Err(format!("autofocus = {other:?}: \"Full\", \"Medium\" or \"Small\"")),
        };
        Ok(PolytecConfig { decoder, low_pass: self.low_pass.clone(), autofocus })
    }
}

/// `[ldv]` with `backend = "analog"`: what the dataset records of a vibrometer that cannot be asked.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnalogLdv {
    /// The velocity range set at the instrument, as written on it (`"25mm/s/V"`).
    pub range: String,
    /// Its output's swing at full scale, +/- V; optional, 10 V.
    pub output_full_scale_v: Option<f64>,
    /// Manufacturer, for the dataset.
    pub vendor: String,
    /// Model, for the dataset.
    pub model: String,
    /// Serial number, for the dataset; optional.
    pub serial: Option<String>,
}

impl AnalogLdv {
    /// The identity the dataset records.
    pub fn identity(&self) -> VibrometerIdentity {
        VibrometerIdentity {
            vendor: self.vendor.clone(),
            model: self.model.clone(),
            serial: self.serial.clone().unwrap_or_else(|| "not given".into()),
            firmware: "analog output only".into(),
        }
    }
}

/// `[daq]`: the DAQ.
#[derive(Debug, Clone, PartialEq)]
pub enum DaqSection {
    /// `backend = "labjack-u6"`: a LabJack U6 over USB.
    LabjackU6(LabjackU6Daq),
    /// `backend = "nidaqmx"`: an NI DAQ through NI-DAQmx.
    Nidaqmx(NidaqmxDaq),
    /// `backend = "alsa"`: the audio interface's own inputs, through ALSA.
    Alsa(AlsaDaq),
}

/// `[daq]` with `backend = "alsa"`: the inputs of a sound card (often the interface that plays the drive: one
/// clock for both).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlsaDaq {
    /// ALSA capture PCM name (`arecord -L`; `metaplate devices` lists the cards' capture PCMs).
    pub device: String,
    /// The inputs' voltage at digital full scale, V (from the interface's manual at the gain in use; for example
    /// 1.74 for +4 dBu line inputs at 0 dB): `wiring.daq_range_v` must be this.
    pub full_scale_v: f64,
    /// The channel map the PCM must report, one ALSA short name per channel the stream opens with (`["FL", "FR"]`,
    /// `["AUX0", "AUX1"]`; a `hw:` PCM opens all its channels, a `plughw:` one as many as the highest input used):
    /// any other, or none, is refused when a run opens the stream, the error naming what it reports. Default: any
    /// map, or none.
    pub channel_map: Option<Vec<String>>,
}

/// `[daq]` with `backend = "labjack-u6"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabjackU6Daq {
    /// The U6's serial number, decimal (`"360012345"`: on its label; `metaplate devices` lists it): required, a
    /// lab may have two.
    pub serial: String,
    /// StreamConfig's ResolutionIndex, 0-8 (default 0, the U6's usual stream setting).
    #[serde(default)]
    pub resolution_index: u8,
    /// StreamConfig's SettlingFactor in 10 us steps (default 0: the U6 chooses).
    #[serde(default)]
    pub settling_factor: u8,
}

impl LabjackU6Daq {
    /// The USB selector of this section: the U6 with this serial number.
    pub fn selector(&self) -> UsbSelector {
        UsbSelector::u6(Some(self.serial.clone()))
    }

    /// The driver settings of this section (the defaults, with its resolution index and settling).
    pub fn settings(&self) -> DriverSettings {
        DriverSettings {
            resolution_index: self.resolution_index,
            settling_factor: self.settling_factor,
            ..DriverSettings::default()
        }
    }
}

/// `[audio]`: the multichannel audio interface.
#[derive(Debug, Clone, PartialEq)]
pub enum AudioSection {
    /// `backend = "alsa"`.
    Alsa(AlsaAudio),
}

/// `[audio]` with `backend = "alsa"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlsaAudio {
    /// ALSA PCM name (`aplay -L`).
    pub device: String,
    /// Frame rate, Hz (opened exactly, never resampled).
    pub sample_rate_hz: f64,
    /// Output channels to open.
    pub channels: u32,
}

impl AudioSection {
    /// Frame rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        match self {
            AudioSection::Alsa(alsa) => alsa.sample_rate_hz,
        }
    }

    /// Output channels.
    pub fn channels(&self) -> u32 {
        match self {
            AudioSection::Alsa(alsa) => alsa.channels,
        }
    }
}

/// `[keypad]` (optional): the response keypad.
#[derive(Debug, Clone, PartialEq)]
pub enum KeypadSection {
    /// `backend = "hidraw"`: a USB HID keyboard through hidapi.
    Hidraw(HidrawKeypad),
}

/// `[keypad]` with `backend = "hidraw"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HidrawKeypad {
    /// `VID:PID` or `VID:PID:SERIAL`, ids in hex.
    pub usb: String,
    /// Report ID in front of the boot reports, for a composite device that uses report IDs (omit otherwise).
    #[serde(default)]
    pub report_id: Option<u8>,
}

/// `[wiring]`: [`Wiring`] without what `[audio]` already says.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WiringSection {
    /// Audio channel of each actuator.
    pub actuator_channels: Vec<u32>,
    /// Audio channel looped back into the DAQ.
    pub loopback_channel: u32,
    /// DAQ input of the velocity.
    pub velocity_input: u8,
    /// DAQ input of the loopback.
    pub loopback_input: u8,
    /// DAQ input range, +/- V.
    pub daq_range_v: f64,
    /// DAQ sample rate, Hz.
    pub daq_sample_rate_hz: f64,
    /// V at the DAQ per full-scale audio sample.
    pub loopback_volts_per_full_scale: f64,
}

/// USB ids as a hardware file writes them: `VID:PID` or `VID:PID:SERIAL`, ids in hex.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UsbIds {
    /// Vendor id.
    pub vendor_id: u16,
    /// Product id.
    pub product_id: u16,
    /// Serial number, if given (never empty).
    pub serial: Option<String>,
}

impl UsbIds {
    /// Parses `VID:PID[:SERIAL]`.
    ///
    /// # Errors
    /// A sentence saying what is malformed.
    pub fn parse(spec: &str) -> Result<Self, String> {
        let mut parts = spec.splitn(3, ':');
        let (Some(vid), Some(pid)) = (parts.next(), parts.next()) else {
            return Err(format!("`{spec}` is not VID:PID or VID:PID:SERIAL"));
        };
        let hex = |s: &str| u16::from_str_radix(s, 16).map_err(|_| format!("`{s}` in `{spec}` is not a hex USB id"));
        let serial = match parts.next() {
            Some("") => return Err(format!("`{spec}` has an empty serial number")),
            other => other.map(str::to_string),
        };
        Ok(Self { vendor_id: hex(vid)?, product_id: hex(pid)?, serial })
    }
}

/// A hardware file, parsed and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct HardwareFile {
    /// Where it was read from (named in errors).
    pub path: PathBuf,
    /// Scene describing the plate's geometry (built-in name or scene file).
    pub plate: String,
    /// The vibrometer's controller.
    pub ldv: LdvSection,
    /// The DAQ.
    pub daq: DaqSection,
    /// The audio interface.
    pub audio: AudioSection,
    /// The response keypad, if one is used.
    pub keypad: Option<KeypadSection>,
    /// What aims the beam, if anything does (`[aim]`).
    pub aim: Option<AimSection>,
    /// The cabling.
    pub wiring: WiringSection,
}

/// The file as TOML, before each instrument's section is read by its backend.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    plate: String,
    ldv: toml::Table,
    daq: toml::Table,
    audio: toml::Table,
    keypad: Option<toml::Table>,
    aim: Option<toml::Table>,
    wiring: WiringSection,
}

impl HardwareFile {
    /// Reads and checks the hardware file at `path` (see [`HardwareFile::parse`]).
    ///
    /// # Errors
    /// [`HardwareError::File`] saying what is wrong and where.
    pub fn load(path: &Path) -> Result<Self, HardwareError> {
        let text = std::fs::read_to_string(path).map_err(|e| HardwareError::File {
            path: path.to_path_buf(),
            key: "(file)".into(),
            reason: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// Parses and checks `text`, read from `path` (named in errors): TOML syntax, known keys, a known backend per
    /// instrument with its keys, the baud rate, the USB ids and the wiring. Opens no device, and accepts backends
    /// this build lacks ([`crate::open_rig`] refuses them).
    ///
    /// # Errors
    /// [`HardwareError::File`] saying what is wrong and where.
    pub fn parse(text: &str, path: &Path) -> Result<Self, HardwareError> {
        let bad = |key: &str, reason: String| HardwareError::File { path: path.to_path_buf(), key: key.into(), reason };
        let raw: RawFile = toml::from_str(text).map_err(|e| bad("(file)", e.to_string().trim_end().to_string()))?;
        let ldv = match section(path, Capability::Vibrometer, raw.ldv)? {
            ("polytec", rest) => LdvSection::Polytec(keys(path, "ldv", rest)?),
            ("analog", rest) => LdvSection::Analog(keys(path, "ldv", rest)?),
            (other, _) => return Err(unknown_backend(path, Capability::Vibrometer, other)),
        };
        let daq = match section(path, Capability::Daq, raw.daq)? {
            ("labjack-u6", rest) => DaqSection::LabjackU6(keys(path, "daq", rest)?),
            ("nidaqmx", rest) => DaqSection::Nidaqmx(keys(path, "daq", rest)?),
            ("alsa", rest) => DaqSection::Alsa(keys(path, "daq", rest)?),
            (other, _) => return Err(unknown_backend(path, Capability::Daq, other)),
        };
        let audio = match section(path, Capability::Audio, raw.audio)? {
            ("alsa", rest) => AudioSection::Alsa(keys(path, "audio", rest)?),
            (other, _) => return Err(unknown_backend(path, Capability::Audio, other)),
        };
        let keypad = match raw.keypad.map(|table| section(path, Capability::Keypad, table)).transpose()? {
            None => None,
            Some(("hidraw", rest)) => Some(KeypadSection::Hidraw(keys(path, "keypad", rest)?)),
            Some((other, _)) => return Err(unknown_backend(path, Capability::Keypad, other)),
        };
        let aim = match raw.aim.map(|table| section(path, Capability::Aim, table)).transpose()? {
            None => None,
            Some(("galvo", rest)) => {
                Some(crate::aim::parse_galvo(path, rest).map_err(|(key, reason)| bad(&key, reason))?)
            }
            Some(("zaber", rest)) => {
                Some(AimSection::Zaber(crate::zaber::parse_zaber(rest).map_err(|(key, reason)| bad(&key, reason))?))
            }
            Some((other, _)) => return Err(unknown_backend(path, Capability::Aim, other)),
        };
        let file =
            Self { path: path.to_path_buf(), plate: raw.plate, ldv, daq, audio, keypad, aim, wiring: raw.wiring };
        match &file.ldv {
            LdvSection::Polytec(polytec) => {
                if polytec.baud != BAUD_RATE {
                    let detail = format!("{}: the driver opens the controller at {BAUD_RATE} baud 8N1", polytec.baud);
                    return Err(bad("ldv.baud", detail));
                }
                polytec.config().map_err(|reason| bad("ldv", reason))?;
            }
            LdvSection::Analog(analog) => {
                AnalogVibrometer::new(analog.identity(), &analog.range, analog.output_full_scale_v)
                    .map_err(|e| bad("ldv.range", e.to_string()))?;
            }
        }
        match &file.daq {
            DaqSection::LabjackU6(u6) => {
                if u6.serial.parse::<u32>().is_err() {
                    let detail = format!("{:?} is not a U6 serial number (decimal digits, as on its label)", u6.serial);
                    return Err(bad("daq.serial", detail));
                }
                if u6.resolution_index > MAX_STREAM_RESOLUTION_INDEX {
                    let detail = format!("{}: the U6 streams at resolution index 0-8", u6.resolution_index);
                    return Err(bad("daq.resolution_index", detail));
                }
            }
            DaqSection::Nidaqmx(ni) => {
                ni.settings(path).map_err(|(key, reason)| bad(&key, reason))?;
            }
            DaqSection::Alsa(alsa) => {
                if let Some(map) = &alsa.channel_map {
                    let bad_position = map.iter().find(|p| p.trim().is_empty() || !p.trim().is_ascii());
                    if map.is_empty() || bad_position.is_some() {
                        let detail = format!("{map:?} is not a list of ALSA channel positions (`[\"FL\", \"FR\"]`)");
                        return Err(bad("daq.channel_map", detail));
                    }
                }
                let full_scale_v = alsa.full_scale_v;
                if !(full_scale_v.is_finite() && full_scale_v > 0.0) {
                    return Err(bad("daq.full_scale_v", format!("{full_scale_v} V is not a voltage above 0")));
                }
                // The interface's inputs have one range: the recipes ask for the wiring's.
                if file.wiring.daq_range_v != full_scale_v {
                    let detail = format!(
                        "{} V, but the interface's inputs read +/-{full_scale_v} V at full scale (`daq.full_scale_v`)",
                        file.wiring.daq_range_v
                    );
                    return Err(bad("wiring.daq_range_v", detail));
                }
            }
        }
        if let Some(KeypadSection::Hidraw(keypad)) = &file.keypad {
            UsbIds::parse(&keypad.usb).map_err(|reason| bad("keypad.usb", reason))?;
        }
        file.wiring().validate().map_err(|reason| bad("wiring", reason))?;
        Ok(file)
    }

    /// The wiring this file describes.
    pub fn wiring(&self) -> Wiring {
        let w = &self.wiring;
        Wiring {
            actuator_channels: w.actuator_channels.clone(),
            loopback_channel: w.loopback_channel,
            audio_channels: self.audio.channels(),
            audio_sample_rate_hz: self.audio.sample_rate_hz(),
            velocity_input: w.velocity_input,
            loopback_input: w.loopback_input,
            daq_range_v: w.daq_range_v,
            daq_sample_rate_hz: w.daq_sample_rate_hz,
            loopback_volts_per_full_scale: w.loopback_volts_per_full_scale,
        }
    }

    /// The backend named for each instrument, in the order `ldv`, `daq`, `audio`, `keypad` and `aim` (if any).
    pub fn backends(&self) -> Vec<(Capability, &'static str)> {
        let mut named = vec![
            (
                Capability::Vibrometer,
                match self.ldv {
                    LdvSection::Polytec(_) => "polytec",
                    LdvSection::Analog(_) => "analog",
                },
            ),
            (
                Capability::Daq,
                match self.daq {
                    DaqSection::LabjackU6(_) => "labjack-u6",
                    DaqSection::Nidaqmx(_) => "nidaqmx",
                    DaqSection::Alsa(_) => "alsa",
                },
            ),
            (
                Capability::Audio,
                match self.audio {
                    AudioSection::Alsa(_) => "alsa",
                },
            ),
        ];
        if let Some(KeypadSection::Hidraw(_)) = self.keypad {
            named.push((Capability::Keypad, "hidraw"));
        }
        if let Some(aim) = &self.aim {
            named.push((Capability::Aim, aim.backend()));
        }
        named
    }
}

/// Splits an instrument's section into its `backend` and the rest of its keys.
fn section(
    path: &Path,
    capability: Capability,
    mut table: toml::Table,
) -> Result<(&'static str, toml::Table), HardwareError> {
    let key = format!("{}.backend", capability.section());
    let bad = |reason: String| HardwareError::File { path: path.to_path_buf(), key: key.clone(), reason };
    let names = || backends::names(capability).join(", ");
    let backend = match table.remove("backend") {
        None => return Err(bad(format!("missing: name one of {}", names()))),
        Some(toml::Value::String(name)) => name,
        Some(other) => return Err(bad(format!("{other} is not a backend name: one of {}", names()))),
    };
    match backends::names(capability).into_iter().find(|known| *known == backend) {
        Some(known) => Ok((known, table)),
        None => Err(unknown_backend(path, capability, &backend)),
    }
}

fn unknown_backend(path: &Path, capability: Capability, name: &str) -> HardwareError {
    HardwareError::File {
        path: path.to_path_buf(),
        key: format!("{}.backend", capability.section()),
        reason: format!(
            "\"{name}\" is not a {} backend: one of {}",
            capability.noun(),
            backends::names(capability).join(", ")
        ),
    }
}

/// Reads a section's keys (all but `backend`) as `T`, refusing unknown ones.
fn keys<T: DeserializeOwned>(path: &Path, section: &str, table: toml::Table) -> Result<T, HardwareError> {
    toml::Value::Table(table).try_into().map_err(|e: toml::de::Error| HardwareError::File {
        path: path.to_path_buf(),
        key: section.into(),
        reason: e.message().trim_end().to_string(),
    })
}

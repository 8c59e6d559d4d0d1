//! Building the [`Rig`] a recipe runs on: the mock lab of a scene (`--scene`), or the real instruments named by a
//! hardware file (`--hardware FILE`).
//!
//! # The hardware file (TOML)
//! ```toml
//! # The plate under test: a scene (built-in name or scene file) whose outline, supports, measurement grid and
//! # actuator positions describe the real plate; its simulation settings are ignored.
//! plate = "metamaterial"
//!
//! [ldv]                      # the scanning vibrometer's controller, on RS-232
//! port = "/dev/serial/by-id/usb-FTDI_FT232R_USB_UART_A10K1234-if00-port0"
//! baud = 115200              # optional; the controller speaks 115200 8N1 only, anything else is refused
//!
//! [daq]                      # the DAQ speaking metaplate's USB bulk protocol
//! usb = "1209:0001:SN0001"   # VID:PID:SERIAL, ids in hex as lsusb prints them
//! interface = 0              # optional (default 0): interface carrying the bulk endpoints
//! endpoint_out = 0x01        # optional (default 0x01)
//! endpoint_in = 0x81         # optional (default 0x81)
//!
//! [audio]                    # the multichannel audio interface, through ALSA
//! device = "hw:CARD=24Ao,DEV=0"
//! sample_rate_hz = 48000
//! channels = 10
//!
//! [wiring]                   # how it is cabled (checked by metaplate_core::rig::Wiring::validate)
//! actuator_channels = [0, 1, 2, 3, 4, 5, 6, 7]   # audio channel of each actuator, in the plate's actuator order
//! loopback_channel = 8       # audio channel cabled back into the DAQ
//! velocity_input = 0         # DAQ input of the LDV's velocity output
//! loopback_input = 1         # DAQ input of the loopback
//! daq_range_v = 10.0         # DAQ input range, +/- V
//! daq_sample_rate_hz = 24000
//! loopback_volts_per_full_scale = 1.0   # V at the DAQ for a full-scale audio sample
//! ```
//! `cli/hardware.example.toml` is this example as a file. Unknown keys are refused (a typo must not fall
//! back to a default), and every device is opened before the run starts, so an absent one is reported at once,
//! by name.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use metaplate_audio::{AlsaSink, AudioDriver};
use metaplate_core::audio::{AudioConfig, AudioOut};
use metaplate_core::clock::RealClock;
use metaplate_core::rig::{Rig, Wiring};
use metaplate_core::scene::Scene;
use metaplate_daq::{DaqDriver, DriverSettings, UsbSelector, UsbTransport};
use metaplate_lab::{LabOptions, MockLab};
use metaplate_ldv::{LdvDriver, PortSelector, RetryPolicy, SerialPortLine};
use metaplate_store::SceneId;
use serde::Deserialize;

/// Why a rig could not be built.
#[derive(Debug)]
pub enum RigError {
    /// The hardware file cannot be read or parsed, or a value in it is out of range.
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong (with the TOML parser's line and column when it has them).
        reason: String,
    },
    /// An instrument could not be opened.
    Device {
        /// Which instrument (`LDV`, `DAQ`, `audio interface`).
        device: &'static str,
        /// How the file names it (port, USB ids, ALSA name).
        name: String,
        /// The driver's error.
        detail: String,
    },
    /// The mock lab of a scene could not be built.
    Lab(String),
}

impl fmt::Display for RigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RigError::File { path, reason } => write!(f, "hardware file {}: {reason}", path.display()),
            RigError::Device { device, name, detail } => write!(f, "cannot open the {device} `{name}`: {detail}"),
            RigError::Lab(detail) => write!(f, "cannot build the mock lab: {detail}"),
        }
    }
}

impl std::error::Error for RigError {}

/// The plate a run measures: its geometry (grid, mask, actuator positions) and its identity in the dataset.
#[derive(Debug, Clone)]
pub struct Plate {
    /// The scene describing it (simulated or real plate).
    pub scene: Scene,
    /// Its identity in the manifest.
    pub id: SceneId,
}

impl Plate {
    /// The plate of the scene `name_or_path` (a built-in name or a scene file).
    ///
    /// # Errors
    /// The scene's error (not found, invalid, with the key path).
    pub fn resolve(name_or_path: &str) -> anyhow::Result<Self> {
        let scene = Scene::resolve(name_or_path)?;
        scene.validate()?;
        let id = SceneId { name: scene.name.clone(), hash: format!("fnv1a64:{:016x}", scene.content_hash()) };
        Ok(Self { scene, id })
    }

    /// Each actuator's magnet position, m, in actuator order.
    pub fn actuator_sites_m(&self) -> Vec<(f64, f64)> {
        self.scene.actuators.iter().map(|a| (a.x_m, a.y_m)).collect()
    }

    /// Flat "point" indices of the actuators' driving points in the mock lab (`grid.len() + k`).
    pub fn driving_points(&self) -> Vec<usize> {
        let n = self.scene.grid.len();
        (0..self.scene.actuators.len()).map(|k| n + k).collect()
    }
}

/// The mock lab of `plate`'s scene, preparing only `points` (Green's functions are computed, or read from
/// `cache_dir`, for those alone), with its rig. Keep the lab alive while the rig is used.
///
/// # Errors
/// [`RigError::Lab`] with the lab's reason.
pub fn mock_rig(
    plate: &Plate,
    points: Vec<usize>,
    seed: Option<u64>,
    cache_dir: Option<PathBuf>,
) -> Result<(MockLab, Rig), RigError> {
    let options = LabOptions { seed, cache_dir, points: Some(points), ..LabOptions::default() };
    let lab = MockLab::new(&plate.scene, &options).map_err(|e| RigError::Lab(e.to_string()))?;
    let rig = lab.rig().map_err(|e| RigError::Lab(e.to_string()))?;
    Ok((lab, rig))
}

/// A hardware file, as parsed (see the module documentation).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HardwareFile {
    /// Scene describing the plate's geometry.
    pub plate: String,
    /// The vibrometer's controller.
    pub ldv: LdvSection,
    /// The DAQ.
    pub daq: DaqSection,
    /// The audio interface.
    pub audio: AudioSection,
    /// The cabling.
    pub wiring: WiringSection,
}

/// `[ldv]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LdvSection {
    /// Serial port path.
    pub port: PathBuf,
    /// Baud rate; must be the controller's ([`metaplate_ldv::BAUD_RATE`]).
    #[serde(default = "default_baud")]
    pub baud: u32,
}

fn default_baud() -> u32 {
    metaplate_ldv::BAUD_RATE
}

/// `[daq]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DaqSection {
    /// `VID:PID:SERIAL` (hex ids).
    pub usb: String,
    /// Interface with the bulk endpoints.
    #[serde(default)]
    pub interface: u8,
    /// Bulk OUT endpoint address.
    #[serde(default = "default_endpoint_out")]
    pub endpoint_out: u8,
    /// Bulk IN endpoint address.
    #[serde(default = "default_endpoint_in")]
    pub endpoint_in: u8,
}

fn default_endpoint_out() -> u8 {
    0x01
}

fn default_endpoint_in() -> u8 {
    0x81
}

/// `[audio]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AudioSection {
    /// ALSA PCM name.
    pub device: String,
    /// Frame rate, Hz.
    pub sample_rate_hz: f64,
    /// Output channels to open.
    pub channels: u32,
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

impl HardwareFile {
    /// Reads and checks the hardware file at `path`: TOML syntax, known keys, the baud rate, the USB selector and
    /// the wiring. Opens no device.
    ///
    /// # Errors
    /// [`RigError::File`] saying what is wrong and where.
    pub fn load(path: &Path) -> Result<Self, RigError> {
        let bad = |reason: String| RigError::File { path: path.to_path_buf(), reason };
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
        let file: HardwareFile = toml::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if file.ldv.baud != metaplate_ldv::BAUD_RATE {
            return Err(bad(format!(
                "ldv.baud = {}: the controller speaks {} baud 8N1 only",
                file.ldv.baud,
                metaplate_ldv::BAUD_RATE
            )));
        }
        file.usb_selector().map_err(|e| bad(format!("daq.usb: {e}")))?;
        file.wiring().validate().map_err(|e| bad(format!("wiring: {e}")))?;
        Ok(file)
    }

    /// The wiring this file describes.
    pub fn wiring(&self) -> Wiring {
        let w = &self.wiring;
        Wiring {
            actuator_channels: w.actuator_channels.clone(),
            loopback_channel: w.loopback_channel,
            audio_channels: self.audio.channels,
            audio_sample_rate_hz: self.audio.sample_rate_hz,
            velocity_input: w.velocity_input,
            loopback_input: w.loopback_input,
            daq_range_v: w.daq_range_v,
            daq_sample_rate_hz: w.daq_sample_rate_hz,
            loopback_volts_per_full_scale: w.loopback_volts_per_full_scale,
        }
    }

    /// The DAQ's USB selector from `daq.usb` (`VID:PID:SERIAL`).
    ///
    /// # Errors
    /// A sentence saying what is malformed.
    pub fn usb_selector(&self) -> Result<UsbSelector, String> {
        let spec = &self.daq.usb;
        let parts: Vec<&str> = spec.split(':').collect();
        let [vid, pid, serial] = parts.as_slice() else {
            return Err(format!("`{spec}` is not VID:PID:SERIAL"));
        };
        let hex = |s: &str| u16::from_str_radix(s, 16).map_err(|_| format!("`{s}` in `{spec}` is not a hex USB id"));
        if serial.is_empty() {
            return Err(format!("`{spec}` has an empty serial number"));
        }
        Ok(UsbSelector {
            vendor_id: hex(vid)?,
            product_id: hex(pid)?,
            serial: Some((*serial).to_string()),
            interface: self.daq.interface,
            endpoint_out: self.daq.endpoint_out,
            endpoint_in: self.daq.endpoint_in,
        })
    }
}

/// The plate and rig described by the hardware file at `path`: opens the LDV controller, the DAQ and the audio
/// interface (configured once, so that a missing card is found now rather than at the first point), on the real
/// clock.
///
/// # Errors
/// [`RigError::File`] for the file; [`RigError::Device`] naming the first instrument that cannot be opened; the
/// plate scene's error.
pub fn hardware_rig(path: &Path) -> anyhow::Result<(Plate, Rig)> {
    let file = HardwareFile::load(path)?;
    let plate = Plate::resolve(&file.plate)?;
    let wiring = file.wiring();
    if wiring.actuator_channels.len() != plate.scene.actuators.len() {
        return Err(RigError::File {
            path: path.to_path_buf(),
            reason: format!(
                "wiring.actuator_channels lists {} actuators, the plate `{}` has {}",
                wiring.actuator_channels.len(),
                file.plate,
                plate.scene.actuators.len()
            ),
        }
        .into());
    }
    let clock: Arc<dyn metaplate_core::clock::Clock> = Arc::new(RealClock::new());
    let port = file.ldv.port.display().to_string();
    let ldv_error = |detail: String| RigError::Device { device: "LDV", name: port.clone(), detail };
    let line = SerialPortLine::open(PortSelector::Path(file.ldv.port.clone())).map_err(|e| ldv_error(e.to_string()))?;
    let vibrometer =
        LdvDriver::new(line, Arc::clone(&clock), RetryPolicy::default()).map_err(|e| ldv_error(e.to_string()))?;
    let daq_error = |detail: String| RigError::Device { device: "DAQ", name: file.daq.usb.clone(), detail };
    let selector = file.usb_selector().map_err(&daq_error)?;
    let transport = UsbTransport::open(selector).map_err(|e| daq_error(e.to_string()))?;
    let daq = DaqDriver::open(transport, DriverSettings::default()).map_err(|e| daq_error(e.to_string()))?;
    let mut audio = AudioDriver::new(AlsaSink::new(&file.audio.device));
    audio
        .configure(&AudioConfig { sample_rate_hz: file.audio.sample_rate_hz, channels: file.audio.channels })
        .map_err(|e| RigError::Device {
            device: "audio interface",
            name: file.audio.device.clone(),
            detail: e.to_string(),
        })?;
    let rig = Rig { vibrometer: Box::new(vibrometer), daq: Box::new(daq), audio: Box::new(audio), clock, wiring };
    Ok((plate, rig))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    const EXAMPLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/hardware.example.toml");

    #[test]
    fn the_example_file_parses_to_a_valid_wiring() {
        let file = HardwareFile::load(Path::new(EXAMPLE)).unwrap();
        assert_eq!(file.plate, "metamaterial");
        assert_eq!(file.ldv.baud, 115_200);
        let usb = file.usb_selector().unwrap();
        assert_eq!((usb.vendor_id, usb.product_id, usb.serial.as_deref()), (0x1209, 0x0001, Some("SN0001")));
        assert_eq!((usb.interface, usb.endpoint_out, usb.endpoint_in), (0, 0x01, 0x81));
        let wiring = file.wiring();
        assert_eq!(wiring.actuator_channels, (0..8).collect::<Vec<u32>>());
        assert_eq!((wiring.loopback_channel, wiring.audio_channels), (8, 10));
    }

    /// Writes the example with `edit` applied, in a temporary directory.
    fn edited(edit: impl Fn(String) -> String) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hardware.toml");
        std::fs::write(&path, edit(std::fs::read_to_string(EXAMPLE).unwrap())).unwrap();
        (dir, path)
    }

    #[test]
    fn a_missing_serial_port_is_named_in_the_error() {
        let missing = "/dev/metaplate-no-such-port";
        let (_dir, path) = edited(|text| {
            let start = text.find("port = ").unwrap();
            let end = start + text[start..].find('\n').unwrap();
            format!("{}port = \"{missing}\"{}", &text[..start], &text[end..])
        });
        let error = hardware_rig(&path).err().unwrap();
        let rig_error = error.downcast_ref::<RigError>().unwrap();
        assert!(matches!(rig_error, RigError::Device { device: "LDV", .. }), "{rig_error:?}");
        let message = error.to_string();
        assert!(message.contains("LDV") && message.contains(missing), "{message}");
    }

    #[test]
    fn bad_files_say_what_is_wrong() {
        let cases: [(&str, &str, &str); 4] = [
            ("baud = 115200", "baud = 9600", "ldv.baud = 9600"),
            ("usb = \"1209:0001:SN0001\"", "usb = \"12g9:0001:SN0001\"", "not a hex USB id"),
            ("loopback_channel = 8", "loopback_channel = 3", "actuator 3's audio channel 3 is used twice"),
            ("loopback_channel = 8", "loopback_channel = 8\nloopbak = 1", "loopbak"),
        ];
        for (from, to, expected) in cases {
            let (_dir, path) = edited(|text| {
                assert!(text.contains(from), "{from}");
                text.replacen(from, to, 1)
            });
            let message = HardwareFile::load(&path).unwrap_err().to_string();
            assert!(message.contains(expected), "{to}: {message}");
        }
    }
}

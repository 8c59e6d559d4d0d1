//! `[aim]` with `backend = "zaber"`: Zaber XY stages on a serial port (`metaplate-aim`'s feature `zaber`).
//!
//! ```toml
//! [aim]
//! backend = "zaber"
//! port = "/dev/serial/by-id/usb-Zaber_..."
//! baud = 115200            # optional: Zaber's default for the ASCII protocol
//! moves = "head"           # "head" or "plate" (the plate moving inverts every direction)
//! reply_timeout_s = 0.5    # optional
//! move_timeout_s = 120.0   # optional: the longest a move or homing may take
//!
//! [aim.x]                  # the axis along the plate's x; [aim.y] the same for y
//! device = 1               # device address on the chain
//! axis = 1                 # optional: 1 (an integrated stage)
//! microstep_um = 0.047625  # the product's "Microstep Size (Default Resolution)"
//! origin_mm = 50.0         # stage position, mm from home, that puts the beam on the plate's origin
//! travel_min_mm = 5.0      # optional: narrower than the device's own limits
//! travel_max_mm = 95.0     # optional
//! ```
//! The keys are checked in every build; their ranges in a build with the backend (the binary's default).

use std::path::PathBuf;

use metaplate_core::aim::Aim;
use serde::Deserialize;

/// `[aim]` with `backend = "zaber"`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZaberAim {
    /// Serial port path of the chain (`/dev/serial/by-id/...`).
    pub port: PathBuf,
    /// Baud rate; optional, 115200.
    #[serde(default = "default_baud")]
    pub baud: u32,
    /// What the stages carry: `"head"` or `"plate"`.
    pub moves: String,
    /// How long a reply may take, s; optional, 0.5.
    #[serde(default = "default_reply_timeout_s")]
    pub reply_timeout_s: f64,
    /// How long a move or homing may take, s; optional, 120.
    #[serde(default = "default_move_timeout_s")]
    pub move_timeout_s: f64,
    /// The axis along the plate's x.
    pub x: ZaberAimAxis,
    /// The axis along the plate's y.
    pub y: ZaberAimAxis,
}

/// `[aim.x]` or `[aim.y]` of a `zaber` aimer.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZaberAimAxis {
    /// Device address on the chain (1 to 99).
    pub device: u8,
    /// Axis number on the device; optional, 1.
    #[serde(default = "default_axis")]
    pub axis: u8,
    /// The product's "Microstep Size (Default Resolution)", µm.
    pub microstep_um: f64,
    /// Stage position, mm from home, that puts the beam on the plate's origin.
    pub origin_mm: f64,
    /// Narrower travel than the device's limits, mm from home; optional.
    pub travel_min_mm: Option<f64>,
    /// As `travel_min_mm`, the upper end; optional.
    pub travel_max_mm: Option<f64>,
}

fn default_baud() -> u32 {
    115_200
}

fn default_reply_timeout_s() -> f64 {
    0.5
}

fn default_move_timeout_s() -> f64 {
    120.0
}

fn default_axis() -> u8 {
    1
}

/// Parses `[aim]`'s keys after its `backend` (`zaber`).
///
/// # Errors
/// The key in error (`aim`, `aim.moves`, `aim.x.device`...) and what is wrong with it.
pub(crate) fn parse_zaber(table: toml::Table) -> Result<ZaberAim, (String, String)> {
    let zaber: ZaberAim = toml::Value::Table(table)
        .try_into()
        .map_err(|e: toml::de::Error| ("aim".to_owned(), e.message().trim_end().to_owned()))?;
    if !matches!(zaber.moves.as_str(), "head" | "plate") {
        return Err(("aim.moves".into(), format!("{:?}: \"head\" or \"plate\"", zaber.moves)));
    }
    #[cfg(feature = "zaber")]
    zaber.config()?;
    Ok(zaber)
}

#[cfg(feature = "zaber")]
impl ZaberAim {
    /// The driver's configuration of this section, checked.
    ///
    /// # Errors
    /// The key in error (under `aim.`) and what is wrong with it.
    pub fn config(&self) -> Result<metaplate_aim::zaber::ZaberConfig, (String, String)> {
        use metaplate_aim::zaber::{MovingPart, StageAxisConfig, ZaberConfig, ZaberError};
        let axis = |a: &ZaberAimAxis| StageAxisConfig {
            device: a.device,
            axis: a.axis,
            microstep_um: a.microstep_um,
            origin_mm: a.origin_mm,
            travel_min_mm: a.travel_min_mm,
            travel_max_mm: a.travel_max_mm,
        };
        let moving = if self.moves == "plate" { MovingPart::Plate } else { MovingPart::Head };
        let config = ZaberConfig {
            port: metaplate_ldv::PortSelector::Path(self.port.clone()),
            baud_rate: self.baud,
            moving,
            x: axis(&self.x),
            y: axis(&self.y),
            reply_timeout_s: self.reply_timeout_s,
            move_timeout_s: self.move_timeout_s,
        };
        match config.validate() {
            Ok(()) => Ok(config),
            Err(ZaberError::Config { key, reason }) => Err((format!("aim.{key}"), reason)),
            Err(other) => Err(("aim".into(), other.to_string())),
        }
    }
}

/// Why the stages did not open.
#[derive(Debug)]
#[allow(dead_code)] // Which variants occur depends on the feature `zaber`.
pub(crate) enum OpenFailure {
    /// A value out of range: the key (under `aim.`) and why.
    Key(String, String),
    /// The driver's error.
    Device(String),
    /// This build lacks the backend (the feature `zaber`).
    NotBuilt,
}

impl ZaberAim {
    /// Opens the stages, homing an axis without its reference (see `metaplate_aim::zaber`).
    ///
    /// # Errors
    /// [`OpenFailure`].
    pub(crate) fn open(&self) -> Result<Box<dyn Aim + Send>, OpenFailure> {
        #[cfg(feature = "zaber")]
        {
            let config = self.config().map_err(|(key, reason)| OpenFailure::Key(key, reason))?;
            let stages = metaplate_aim::zaber::open_serial(config).map_err(|e| OpenFailure::Device(e.to_string()))?;
            Ok(Box::new(stages))
        }
        #[cfg(not(feature = "zaber"))]
        Err(OpenFailure::NotBuilt)
    }
}

/// Serial ports where a Zaber chain answers (`/get deviceid` to every device): each port's path, and its devices
/// in a sentence.
///
/// # Errors
/// The system's reason when the ports cannot be listed.
#[cfg(feature = "zaber")]
pub(crate) fn chains_on_serial_ports() -> Result<Vec<(String, String)>, String> {
    let ports = metaplate_ldv::available_ports().map_err(|e| e.to_string())?;
    Ok(ports
        .into_iter()
        .filter_map(|port| {
            let selector = metaplate_ldv::PortSelector::Path(port.path.clone());
            let mut line = metaplate_ldv::SerialPortLine::open_at(selector, default_baud()).ok()?;
            let devices = metaplate_aim::zaber::list_chain(&mut line, 0.3).ok().filter(|d| !d.is_empty())?;
            let names: Vec<String> =
                devices.iter().map(|d| format!("device {} (id {})", d.address, d.device_id)).collect();
            Some((port.path.display().to_string(), format!("Zaber chain: {}", names.join(", "))))
        })
        .collect())
}

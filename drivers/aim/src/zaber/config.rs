//! What the hardware file says about a pair of Zaber stages: the port, which device and axis moves along the
//! plate's x and y, the product's step size, where the plate's origin lies in stage coordinates, and whether the
//! stages carry the head or the plate.

use metaplate_ldv::PortSelector;

use crate::zaber::error::ZaberError;

/// Zaber's default rate for the ASCII protocol, baud (*Manual, Quick Start*: 115200 8N1 for firmware 6.06 and
/// later).
pub const DEFAULT_BAUD_RATE: u32 = 115_200;

/// The resolution (microsteps per full step) at which Zaber's product pages give "Microstep Size (Default
/// Resolution)".
pub const DEFAULT_RESOLUTION: u32 = 64;

/// What the stages move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MovingPart {
    /// The stages carry the vibrometer head: the beam moves with them.
    Head,
    /// The stages carry the plate under a fixed beam: moving the plate by +d puts the beam at -d on the plate,
    /// so every direction is inverted.
    Plate,
}

/// One stage axis: which device and axis on the chain, and how its microsteps map to the plate frame.
#[derive(Debug, Clone, PartialEq)]
pub struct StageAxisConfig {
    /// Device address on the chain (1 to 99).
    pub device: u8,
    /// Axis number on that device (1 for an integrated stage).
    pub axis: u8,
    /// The product's "Microstep Size (Default Resolution)", µm (0.047625 for Zaber's X-LSM stages): with the
    /// resolution the device reports, what one microstep is.
    pub microstep_um: f64,
    /// The stage position, mm from its home, at which the beam is on the plate's origin.
    pub origin_mm: f64,
    /// A narrower travel than the device's own limits, mm from home (for example to keep clear of a clamp);
    /// `None` uses `limit.min`.
    pub travel_min_mm: Option<f64>,
    /// As `travel_min_mm`, the upper end; `None` uses `limit.max`.
    pub travel_max_mm: Option<f64>,
}

/// A pair of Zaber stages on one serial port.
#[derive(Debug, Clone, PartialEq)]
pub struct ZaberConfig {
    /// The serial port of the chain.
    pub port: PortSelector,
    /// Its rate, baud ([`DEFAULT_BAUD_RATE`] unless the devices' `comm.rs232.baud` was changed).
    pub baud_rate: u32,
    /// What the stages move.
    pub moving: MovingPart,
    /// The axis along the plate's x.
    pub x: StageAxisConfig,
    /// The axis along the plate's y.
    pub y: StageAxisConfig,
    /// How long a reply may take, s.
    pub reply_timeout_s: f64,
    /// How long a move or a homing may take, s.
    pub move_timeout_s: f64,
}

impl ZaberConfig {
    /// A configuration with the defaults: 115200 baud, 0.5 s per reply, 120 s per move.
    pub fn new(port: PortSelector, moving: MovingPart, x: StageAxisConfig, y: StageAxisConfig) -> Self {
        Self { port, baud_rate: DEFAULT_BAUD_RATE, moving, x, y, reply_timeout_s: 0.5, move_timeout_s: 120.0 }
    }

    /// Checks every value's range.
    ///
    /// # Errors
    /// [`ZaberError::Config`] naming the first bad value.
    pub fn validate(&self) -> Result<(), ZaberError> {
        let bad = |key: &str, reason: String| Err(ZaberError::Config { key: key.to_owned(), reason });
        if self.baud_rate == 0 {
            return bad("baud", "must be positive".into());
        }
        for (key, value) in [("reply_timeout_s", self.reply_timeout_s), ("move_timeout_s", self.move_timeout_s)] {
            if !(value.is_finite() && value > 0.0) {
                return bad(key, format!("{value}: must be positive"));
            }
        }
        for (name, axis) in [("x", &self.x), ("y", &self.y)] {
            if !(1..=metaplate_zaber_protocol::MAX_DEVICE).contains(&axis.device) {
                return bad(&format!("{name}.device"), format!("{}: must be 1 to 99", axis.device));
            }
            if !(1..=metaplate_zaber_protocol::MAX_AXIS).contains(&axis.axis) {
                return bad(&format!("{name}.axis"), format!("{}: must be 1 to 9", axis.axis));
            }
            if !(axis.microstep_um.is_finite() && axis.microstep_um > 0.0) {
                return bad(&format!("{name}.microstep_um"), format!("{}: must be positive", axis.microstep_um));
            }
            if !axis.origin_mm.is_finite() {
                return bad(&format!("{name}.origin_mm"), format!("{}: must be finite", axis.origin_mm));
            }
            for (end, value) in [("travel_min_mm", axis.travel_min_mm), ("travel_max_mm", axis.travel_max_mm)] {
                if value.is_some_and(|v| !v.is_finite()) {
                    return bad(&format!("{name}.{end}"), "must be finite".into());
                }
            }
            if let (Some(min), Some(max)) = (axis.travel_min_mm, axis.travel_max_mm)
                && min >= max
            {
                return bad(&format!("{name}.travel_min_mm"), format!("{min} is not below travel_max_mm {max}"));
            }
        }
        if (self.x.device, self.x.axis) == (self.y.device, self.y.axis) {
            return bad("y", format!("the same axis as x (device {} axis {})", self.x.device, self.x.axis));
        }
        Ok(())
    }
}

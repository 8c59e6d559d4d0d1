//! Zaber motorised XY stages under the vibrometer head or under the plate, over Zaber's ASCII protocol
//! (`metaplate-zaber-protocol`) on a serial port: [`ZaberStages`], configured by [`ZaberConfig`].
//!
//! Two axes (each a device address and an axis number on the chain; two integrated stages, or two axes of one
//! controller) move along the plate's x and y. Positions convert through the product's microstep size at the
//! default resolution (its product page's "Microstep Size (Default Resolution)", [`StageAxisConfig::microstep_um`])
//! and the `resolution` the device reports; the plate's origin is a stage position in mm
//! ([`StageAxisConfig::origin_mm`]); when the stages carry the plate ([`MovingPart::Plate`]) every direction is
//! inverted. Faults and warnings the stages raise are [`ZaberError::Flags`], each flag by its manual name, and
//! become [`metaplate_core::aim::AimError::Device`]; a silent or lost line becomes `Disconnected`. [`list_chain`]
//! asks what answers on a port.

mod chain;
mod config;
mod error;
mod link;
mod stages;

pub use chain::{ChainDevice, list_chain};
pub use config::{DEFAULT_BAUD_RATE, DEFAULT_RESOLUTION, MovingPart, StageAxisConfig, ZaberConfig};
pub use error::ZaberError;
pub use stages::ZaberStages;

/// Opens the stages on the serial port `config` names, at its rate, timed by the wall clock.
///
/// # Errors
/// As [`ZaberStages::open`]; [`ZaberError::Line`] when the port cannot be opened.
pub fn open_serial(config: ZaberConfig) -> Result<ZaberStages<metaplate_ldv::SerialPortLine>, ZaberError> {
    let line =
        metaplate_ldv::SerialPortLine::open_at(config.port.clone(), config.baud_rate).map_err(ZaberError::Line)?;
    ZaberStages::open(config, line, std::sync::Arc::new(metaplate_core::clock::RealClock::new()))
}

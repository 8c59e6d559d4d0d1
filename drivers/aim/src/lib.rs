//! Aiming a single-point vibrometer's beam on the plate: backends of [`metaplate_core::aim::Aim`].
//!
//! - [`galvo`]: galvanometer mirrors driven by two analog outputs ([`metaplate_core::aim::MirrorOutputs`]): the
//!   plate-to-volts map fitted from taught points ([`galvo::GalvoFit`]), its file ([`galvo::file`]), the aimer
//!   ([`galvo::GalvoAimer`]) and the keyboard teaching that makes the fit ([`galvo::teach`]).
//! - `zaber` (feature `zaber`): Zaber XY stages under the head or the plate, over Zaber's ASCII protocol.

pub mod galvo;
#[cfg(feature = "zaber")]
pub mod zaber;

pub use galvo::GalvoError;

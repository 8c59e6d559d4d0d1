//! HID response keypad driver for perceptual experiments.
//!
//! The keypad is any USB HID device that enumerates as a keyboard and sends boot keyboard reports (a response pad
//! or a plain keyboard): there is no protocol of ours here, only the HID standard.
//! - [`report`]: sans-IO codec of boot keyboard reports: diffing successive reports into key-down/key-up changes.
//! - [`transport`]: [`HidInput`], the narrow transport (read one report with a timeout, reopen).
//! - [`hidapi`]: the real transport on the `hidapi` crate (pure-Rust hidraw backend on Linux: no libudev).
//! - [`driver`]: [`Keypad`], timestamped [`KeyEvent`]s on a [`metaplate_core::clock::Clock`].

pub mod driver;
pub mod hidapi;
pub mod report;
pub mod transport;

pub use self::hidapi::{HidapiInput, HidapiSelector};
pub use driver::{KeyEvent, Keypad, KeypadError, ReportPrefix};
pub use report::{BootDecoder, Key, KeyAction, KeyChange, ReportError};
pub use transport::{HidInput, TransportError};

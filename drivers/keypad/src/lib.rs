//! HID response keypad driver for perceptual experiments.
//!
//! The keypad is any USB HID device that enumerates as a keyboard and sends boot keyboard reports (a response pad
//! or a plain keyboard): there is no protocol of ours here, only the HID standard. [`Keypad`] turns its reports
//! into key events stamped on a [`Clock`](metaplate_core::clock::Clock), over any [`HidInput`], the narrow
//! transport trait this crate defines.
//!
//! - [`report`]: the sans-IO codec of boot keyboard reports (`metaplate-keypad-protocol`, re-exported).
//! - [`transport`]: [`HidInput`], the narrow transport (read one report with a timeout, reopen).
//! - `hidapi` (feature `hidraw`, Linux only): the real transport on the `hidapi` crate (pure-Rust hidraw backend:
//!   no libudev).
//! - [`driver`]: [`Keypad`], timestamped [`KeyEvent`]s on a [`metaplate_core::clock::Clock`].
//! - [`scripted`]: [`ScriptedHid`], a fake device that plays a script of reports on a virtual clock: the device of
//!   this driver's tests, of the pre-flight's keypad check (`metaplate-recipes`) and of the experiment console's
//!   tests (`metaplate-experiment`), and of rehearsals.
//!
//! The feature `hidraw` is on by default for this crate's own tests; the workspace depends on the crate without it,
//! and the binary turns it on (through `metaplate-drivers`' `hardware` feature). Elsewhere than Linux it is
//! compiled out.

pub mod driver;
#[cfg(all(feature = "hidraw", target_os = "linux"))]
pub mod hidapi;
pub mod scripted;
pub mod transport;

pub use metaplate_keypad_protocol as report;

#[cfg(all(feature = "hidraw", target_os = "linux"))]
pub use self::hidapi::{HidListing, HidapiInput, HidapiSelector, keypads};
pub use driver::{KeyEvent, Keypad, KeypadError, ReportPrefix};
pub use metaplate_keypad_protocol::{BootDecoder, Key, KeyAction, KeyChange, ReportError};
pub use scripted::{ScriptStep, ScriptedHid};
pub use transport::{HidInput, TransportError};

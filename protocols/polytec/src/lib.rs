//! Sans-IO codec of the RS-232 command syntax of Polytec vibrometer controllers (OFV-5000, OFV-5000 Xtra,
//! VibroFlex): requests, reply lines, velocity ranges. No I/O, no clocks: bytes in, typed values out, and back.
//!
//! # Sources
//!
//! Polytec documents the syntax in "RS-232 Interface Commands: OFV-5000 User Manual". That manual is not public;
//! what this crate implements is what public code and manuals show of it, each rule with where it comes from:
//!
//! - PLACE (github.com/PALab/place), `place/plugins/polytec/polytec.py` (the plugin labs run) and its predecessor
//!   `place/automate/polytec/vibrometer.py` (history before commit 42a86fb, which lists the `Get`, `Set` and
//!   `GetDevInfo` attributes of `Controller`, `Interface`, `SensorHead`, `VeloDec` and `DisplDec`) — cited below
//!   as *PLACE*;
//! - the OFV-3001 controller's user manual, appendix E.2 (RS-232 and IEEE-488), for the terminator and for
//!   invalid settings being ignored — cited as *OFV-3001 E.2*.
//!
//! # Lines
//!
//! Every line, both ways, ends with LF (0x0A) (*OFV-3001 E.2.4*: "All transmissions from and to the controller
//! are terminated with the ASCII character LF"; *PLACE* writes `...\n` and reads with `readline`). The decoders
//! here also drop a CR before the LF, skip empty lines, take UTF-8 text without control characters (a
//! displacement decoder's ranges are spelt in `µm`), and report a line longer than [`MAX_LINE_CONTENT`] once.
//!
//! # Requests
//!
//! `Verb,Device,Index,Attribute[,Value]` ([`Request`]). The verb is `Get` (current value, one reply line), `Set`
//! (no reply; PLACE writes it and reads nothing, and verifies by a `Get`) or `GetDevInfo` (what the unit has:
//! the installed item's name, or the list of values an attribute may take, or `Not Available`). The device is
//! one of [`Device`], the index picks one of several (a unit's decoders are numbered from 0, and which model sits
//! at which index differs from unit to unit: *PLACE*'s note "DD-300 is 'DisplDec,0' ... VD-09 is 'VeloDec,1'").
//!
//! | request | reply | source |
//! |---|---|---|
//! | `GetDevInfo,Controller,0,Name` | `OFV-5000 Vibrometer Controller` | *PLACE* `_get_controller_name` (and the OFV-5000 Xtra's `OFV-5000Xtra Vibrometer Controller`) |
//! | `Get,Controller,0,Version` | the controller's version | *PLACE* (old) `getVersion` |
//! | `Set,Controller,0,Remote,<state>` / `Get,...,Remote` | — / the state | *PLACE* (old) `setRemote` |
//! | `Set,Interface,0,Echo,Off` / `Get,...,Echo` | — / `Off` | *PLACE* (old) `setEcho`, "turning echo 'On' can cause problems" |
//! | `Get,SensorHead,0,Name`, `Get,SensorHead,0,Version` | the head's name, version | *PLACE* (old) `PolytecSensorHead` |
//! | `GetDevInfo,SensorHead,0,AutoFocus` | the autofocus states, or `Not Available` | *PLACE* (old) `getDevAutoFocus` |
//! | `Set,SensorHead,0,AutoFocusSpan,Full` | — (`Full`, `Medium`, `Small`) | *PLACE* `_autofocus_vibrometer` |
//! | `Set,SensorHead,0,AutoFocus,Search` | — | *PLACE* `_autofocus_vibrometer` |
//! | `Get,SensorHead,0,AutoFocusResult` | `Found` once focused | *PLACE* `_autofocus_vibrometer` |
//! | `GetDevInfo,VeloDec,<i>,Name` | the decoder's name (`VD-09`) or `not Installed` | *PLACE* (old) `get_dev_name` |
//! | `GetDevInfo,VeloDec,<i>,Range` | every range of the decoder, or `Not Available` | *PLACE* (old) `get_dev_range` |
//! | `Set,VeloDec,<i>,Range,5mm/s/V` | — | *PLACE* `_set_range` |
//! | `Get,VeloDec,<i>,Range` | `5mm/s/V` | *PLACE* `_get_range` |
//! | `Get,VeloDec,<i>,MaxFreq`, `...,SignalDelay` | `20kHz`, `8.16us` | *PLACE* `_get_maximum_frequency`, `_get_delay` |
//! | `Get,SignalLevel,0,Value` | an integer | *PLACE* `_get_signal_level` |
//!
//! A `GetDevInfo` list is comma-separated ([`split_list`]): *PLACE* reads `GetDevInfo,SensorHead,0,Focus` as a
//! Python literal pair `min,max`. Not in the public sources, and used here on that pattern (to be checked
//! against the manual on a unit): the velocity decoder's `TrackingFilter` and `LowPass` attributes, and
//! `GetDevInfo,SignalLevel,0,Value` giving the level's `min,max`. An invalid setting is ignored (*OFV-3001
//! E.2.4*), so a host reads back what it set.
//!
//! # Replies
//!
//! One line per `Get` or `GetDevInfo` ([`ReplyDecoder`], [`Reply::classify`]); with the interface's echo on,
//! the request comes back first ([`Reply::Echo`], *OFV-3001 E.2.4*'s "Answer with ECHOON" column). Velocity
//! ranges parse into [`VelocityRange`] (m/s per V).

mod error;
mod framer;
mod range;
mod reply;
mod request;

pub use error::PolytecProtocolError;
pub use framer::MAX_LINE_CONTENT;
pub use range::VelocityRange;
pub use reply::{NOT_AVAILABLE, Reply, ReplyDecoder, parse_count, split_list};
pub use request::{Device, Request, RequestDecoder, Verb};

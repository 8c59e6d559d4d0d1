//! Sans-IO codec of Zaber's ASCII protocol, the text protocol of Zaber's motorised stages and controllers
//! (firmware 6.06 and later; 7 is current): commands ([`Command`]), replies, info and alert messages
//! ([`Message`]), warning flags ([`WarningFlag`]), checksums ([`lrc`]) and line splitting ([`LineSplitter`]).
//! Both sides use it: the stage driver (`metaplate-aim`, feature `zaber`) encodes commands and decodes messages;
//! the mock chain (`metaplate-mock-zaber`) the reverse. No I/O, no clocks.
//!
//! # Sources
//!
//! Zaber's "ASCII Protocol Manual" (firmware 7; the firmware 6 edition for `WH`), cited as *Manual* with the
//! section: Message Format (commands, replies, info, alerts, checksums, terminators), Warning Flags, Reply Flags
//! and rejection reasons, and the command reference (`home`, `move`, `get`, `warnings`). The crate `zproto`
//! (github.com/stphnt/zproto) implements the same protocol; it is not used here because it requires `serialport`
//! with libudev, which this workspace builds without.
//!
//! # Example
//!
//! ```
//! use metaplate_zaber_protocol::{Command, Message, ReplyFlag, WarningFlag};
//! assert_eq!(Command::new(1, 1, "move abs 1000").encode(false), b"/1 1 move abs 1000\n");
//! let Ok(Message::Reply(reply)) = Message::parse("@01 1 OK BUSY WR 0") else { panic!() };
//! assert_eq!((reply.flag, reply.warning), (ReplyFlag::Ok, WarningFlag::NO_REFERENCE));
//! ```

mod command;
mod error;
mod line;
mod response;
mod warning;

pub use command::{Command, MAX_AXIS, MAX_DEVICE, MAX_ID};
pub use error::ZaberProtocolError;
pub use line::{LineSplitter, MAX_LINE, lrc};
pub use response::{Message, Reply, ReplyFlag, Status};
pub use warning::{WarningFlag, format_warning_list, parse_warning_list};

/// Rejection reasons a device puts in an `RJ` reply's data (*Manual, Reply Flags*).
pub mod reason {
    /// The command is not one the device knows.
    pub const BAD_COMMAND: &str = "BADCOMMAND";
    /// A parameter is malformed or out of range (a move beyond the travel limits).
    pub const BAD_DATA: &str = "BADDATA";
    /// The axis number does not exist on the device.
    pub const BAD_AXIS: &str = "BADAXIS";
    /// The command must be sent to axis 0.
    pub const DEVICE_ONLY: &str = "DEVICEONLY";
}

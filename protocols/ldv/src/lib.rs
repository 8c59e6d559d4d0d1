//! Sans-IO codec for the scanning laser Doppler vibrometer's controller (Ometron 8330 class) on RS-232.
//!
//! This crate is both the specification of the protocol and its only implementation. The host side (the driver)
//! encodes [`Command`]s with [`encode_command`] and decodes [`Reply`]s with a [`ReplyDecoder`]; the device side (the
//! mock controller) decodes [`Command`]s with a [`CommandDecoder`] and encodes [`Reply`]s with [`encode_reply`]. No
//! I/O, no clocks, no threads: bytes in, typed messages out, and back. The protocol is modelled on how controllers of
//! this class behave; where the real instrument differs, the driver adapts, not this specification.
//!
//! # 1. Physical layer
//!
//! RS-232, 115200 baud, 8 data bits, no parity, 1 stop bit (8N1), no flow control (neither RTS/CTS nor XON/XOFF).
//! One byte takes 87 us on the wire; a maximal line (128 bytes) takes 11.1 ms.
//!
//! # 2. Lines
//!
//! | rule | value |
//! |---|---|
//! | character set | printable ASCII, 0x20 to 0x7E; any other byte inside a line makes it fail with `ERR 2` |
//! | command terminator | the host sends CR (0x0D); the controller accepts CR, LF or CR LF |
//! | reply terminator | the controller sends CR LF; the host decoder accepts CR, LF or CR LF |
//! | maximum line length | [`MAX_LINE_LEN`] = 128 bytes with CR LF, so [`MAX_LINE_CONTENT`] = 126 bytes before the terminator |
//! | overlong line | reported (`ERR 4`) as soon as byte 127 arrives; the rest is dropped up to the next terminator |
//! | blank lines | lines that are empty or only spaces are ignored and get no reply (so CR LF is one line) |
//! | words | separated by one or more spaces; leading and trailing spaces ignored |
//! | keywords and choice words | any letter case (`pos?` is `POS?`); encoders write upper case, one space between words |
//!
//! Numbers are plain decimals, `[+|-]digits[.digits]`, at most 16 characters, with no more decimals than the
//! quantity's resolution: no exponents, no `nan` or `inf`, no hex, no bare `.5` or `5.`. So every number on the
//! wire is finite and exactly representable, and nothing is rounded on either side. Encoders write positions and
//! angles with exactly three decimals and integers without sign or leading zeros.
//!
//! # 3. Commands (host to controller)
//!
//! Queries are the keyword followed by `?`. Every non-blank line gets exactly one reply line: the reply listed, or
//! `ERR <code> <text>`.
//!
//! | command | arguments: unit, range | reply | errors | meaning |
//! |---|---|---|---|---|
//! | `*IDN?` | | `IDN <vendor>,<model>,<serial>,<firmware>` | | identity ([`Command::Identify`]) |
//! | `*RST` | | `OK` | 7, 8 | power-on defaults; clears errors; keeps the laser state ([`Command::Reset`]) |
//! | `*CLS` | | `OK` | | clears a latched hardware fault ([`Command::ClearErrors`]) |
//! | `POS <x> <y>` | mm, -500.000 to 500.000, 0.001 steps | `OK` once settled | 2, 3, 5, 7, 8 | beam to a point of the calibrated plate frame ([`Command::MoveTo`]) |
//! | `POS?` | | `POS <x> <y>` (mm) | 5 | beam position in the plate frame ([`Command::QueryPosition`]) |
//! | `ANG <x> <y>` | degrees, -25.000 to 25.000, 0.001 steps | `OK` once settled | 2, 3, 7, 8 | mirrors to raw angles; needs no calibration ([`Command::MoveToAngles`]) |
//! | `ANG?` | | `ANG <x> <y>` (degrees) | | mirror angles ([`Command::QueryAngles`]) |
//! | `SIG?` | | `SIG <level>`, integer %, 0 to 100 | 6, 8 | signal level ([`Command::QuerySignal`]) |
//! | `VRANGE <r>` | mm/s per V, one of 1, 5, 25, 125, 1000 | `OK` | 2, 3, 7 | velocity range ([`Command::SetVelocityRange`]) |
//! | `VRANGE?` | | `VRANGE <r>` | | ([`Command::QueryVelocityRange`]) |
//! | `TRACK <f>` | `OFF`, `SLOW`, `MEDIUM`, `FAST` | `OK` | 2, 7 | tracking filter ([`Command::SetTrackingFilter`]) |
//! | `TRACK?` | | `TRACK <f>` | | ([`Command::QueryTrackingFilter`]) |
//! | `LASER <s>` | `ON`, `OFF` | `OK` (for `ON`: once stable) | 2, 7, 8 | laser on or off ([`Command::SetLaser`]) |
//! | `LASER?` | | `LASER <s>` | | ([`Command::QueryLaser`]) |
//! | `CAL?` | | `CAL YES` or `CAL NO` | | whether a plate calibration is in force ([`Command::QueryCalibration`]) |
//! | `SYNC <t>` | integer, 0 to 4294967295 | `SYNC <t>`, always | 2, 3 (malformed token only) | echo, to resynchronise ([`Command::Sync`]) |
//!
//! Any command may also fail with `ERR 1` (unknown keyword), `ERR 2` (wrong argument count, malformed argument,
//! bad character) or `ERR 4` (line too long). A position or angle outside the range is `ERR 3`; so is a calibrated
//! point that maps to mirror angles beyond 25 degrees. The plate frame (origin, axes) is the one taught to the
//! controller at calibration; calibration itself is done at the instrument, not over this protocol.
//!
//! Power-on and `*RST` defaults: velocity range 25 mm/s/V, tracking filter off, mirrors at 0, 0 degrees, no latched
//! fault. The laser is off at power-on and left as it is by `*RST`. The analog velocity output swings plus or minus
//! 10 V: velocity (m/s) = voltage (V) x range (mm/s/V) x 1e-3 ([`VelocityRange::m_per_s_per_v`]).
//!
//! # 4. Replies (controller to host)
//!
//! Every reply starts with a keyword, so a reply decodes without knowing the command it answers (unlike SCPI's bare
//! `*IDN?` answer). [`Command::is_answered_by`] tells whether a reply is a proper answer to a command.
//!
//! | reply | content |
//! |---|---|
//! | `OK` | a setting or move was carried out |
//! | `ERR <code> <text>` | the command failed; code from the table below; text: 0 to 100 printable characters, for people |
//! | `IDN <vendor>,<model>,<serial>,<firmware>` | four fields of 1 to 24 printable characters without commas, e.g. `IDN Ometron,8330,SN04512,2.14` |
//! | `POS <x> <y>` | mm, three decimals |
//! | `ANG <x> <y>` | degrees, three decimals |
//! | `SIG <level>` | integer %, 0 to 100 |
//! | `VRANGE <r>` | mm/s per V |
//! | `TRACK <f>` | `OFF`, `SLOW`, `MEDIUM` or `FAST` |
//! | `LASER <s>` | `ON` or `OFF` |
//! | `CAL <c>` | `YES` or `NO` |
//! | `SYNC <t>` | the token of the `SYNC` command |
//!
//! # 5. Error codes
//!
//! | code | [`ErrorCode`] | when |
//! |---|---|---|
//! | 1 | `UnknownCommand` | the first word is not a command keyword |
//! | 2 | `BadArgument` | wrong argument count; a number that breaks the grammar (NaN, inf, exponent, too many digits or decimals); an unknown choice word; a byte outside printable ASCII |
//! | 3 | `OutOfRange` | a well-formed value outside its range (including a velocity range not on the list) |
//! | 4 | `LineTooLong` | more than 126 bytes before the terminator |
//! | 5 | `NotCalibrated` | `POS` or `POS?` without a valid plate calibration |
//! | 6 | `LaserOff` | `SIG?` with the laser off |
//! | 7 | `Busy` | a move or setting while the controller is under front-panel control or running its self-test; queries, `*IDN?` and `SYNC` are still answered; retry after 100 ms |
//! | 8 | `HardwareFault` | a latched mirror-drive or laser fault; beam and laser commands fail until `*CLS` or `*RST` clears it (it returns if the cause persists) |
//!
//! A device decodes a bad line into an [`LdvProtocolError`]; [`LdvProtocolError::error_code`] is the code it
//! replies with, and [`Reply::from_error`] builds that reply.
//!
//! # 6. Conversation and timing
//!
//! The controller handles lines strictly in order and answers each non-blank line exactly once, in order. The host
//! sends one command and waits for its reply before the next (the controller's input FIFO holds 256 bytes; lines
//! sent ahead are not lost but their replies queue up behind a slow move).
//!
//! | step | time (after the command's terminator arrives) |
//! |---|---|
//! | queries, settings, `SYNC`, `*CLS` | reply within 10 ms |
//! | `POS`, `ANG` | reply when the mirrors have settled: 2 ms + 0.5 ms per degree of the larger axis step, so about 2.2 ms for a 5 mm grid step at 1 m stand-off and at most 27 ms for a full-field step |
//! | after a move | the signal level and the velocity output need the tracking filter's lock time before they are valid: none (`OFF`), 5 ms (`FAST`), 20 ms (`MEDIUM`), 50 ms (`SLOW`) |
//! | `SIG?` | the level is averaged over 20 ms; reply within 30 ms |
//! | `VRANGE` | reply after the decoder has switched, within 20 ms |
//! | `LASER ON` | reply once the laser is stable: typically 1 s, at most 2 s; `LASER OFF` within 10 ms |
//! | `*RST` | mirror self-test; reply within 2 s |
//!
//! Recommended host timeouts ([`Command::timeout_s`]): 250 ms, and 3 s for `*RST` and `LASER ON`. After a timeout
//! the host must assume a stale reply may still arrive. It resynchronises: it sends `SYNC <t>` with a token it has
//! not used before, and discards every reply (and every decode error) until `SYNC <t>` comes back; if that takes
//! longer than a timeout, it repeats with a new token, and after three failures reports the controller lost.
//!
//! # 7. Example exchange
//!
//! Host lines end in CR, controller lines in CR LF (shown as `\r` and `\r\n`):
//!
//! | host sends | controller replies |
//! |---|---|
//! | `*IDN?\r` | `IDN Ometron,8330,SN04512,2.14\r\n` |
//! | `CAL?\r` | `CAL YES\r\n` |
//! | `LASER ON\r` | `OK\r\n` |
//! | `VRANGE 5\r` | `OK\r\n` |
//! | `POS 12.000 -35.500\r` | `OK\r\n` |
//! | `SIG?\r` | `SIG 87\r\n` |
//! | `ANG 30 0\r` (typed by hand) | `ERR 3 mirror angle (deg) = 30.000 is outside -25.000..=25.000 deg\r\n` |
//! | `SYNC 17\r` | `SYNC 17\r\n` |
//!
//! ```
//! use metaplate_ldv_protocol::{
//!     Command, CommandDecoder, PlatePoint, Reply, ReplyDecoder, SignalLevel, encode_command, encode_reply,
//! };
//!
//! // Host side: encode a move, then decode the controller's bytes, split anywhere.
//! let point = PlatePoint::from_m(0.012, -0.0355)?;
//! assert_eq!(encode_command(&Command::MoveTo(point)), b"POS 12.000 -35.500\r");
//! let mut replies = ReplyDecoder::new();
//! replies.push(b"OK\r\nSIG ");
//! replies.push(b"87\r\n");
//! let got: Vec<_> = replies.drain().collect::<Result<_, _>>()?;
//! assert_eq!(got, [Reply::Ok, Reply::Signal(SignalLevel::from_percent(87)?)]);
//!
//! // Device side: a bad line becomes the ERR reply to send.
//! let mut commands = CommandDecoder::new();
//! commands.push(b"ANG 30 0\r");
//! let error = commands.poll().ok_or("no line")?.unwrap_err();
//! assert_eq!(
//!     encode_reply(&Reply::from_error(&error)),
//!     b"ERR 3 mirror angle (deg) = 30.000 is outside -25.000..=25.000 deg\r\n"
//! );
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # 8. Codec properties and tests
//!
//! Like every codec in `protocols/`, this one is sans-IO (bytes in, typed messages out, and back), incremental (input
//! split at any byte decodes the same) and bounded: a line longer than [`MAX_LINE_LEN`] is one typed error, and
//! decoding resumes after its terminator. The crate's tests check round trips of every message at arbitrary split
//! points (proptest), the example exchange of section 7 and the resynchronisation of section 6 byte for byte, and every
//! class of malformed input. Two fuzz targets in `fuzz/`, `ldv_reply_decoder` and `ldv_command_decoder`, feed the
//! decoders hostile bytes; run one with `cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run <target> -- -max_total_time=300`
//! (`RUSTC_BOOTSTRAP` lets cargo-fuzz use its sanitizer flags on a stable toolchain).

mod command;
mod decoder;
mod error;
mod framer;
mod number;
mod position;
mod reply;
mod settings;
mod syntax;
mod text;

pub use command::{
    COMMAND_TERMINATOR, Command, REPLY_TIMEOUT_S, SLOW_REPLY_TIMEOUT_S, encode_command, encode_command_into,
};
pub use decoder::{CommandDecoder, LineDecoder, LineMessage, ReplyDecoder};
pub use error::{ErrorCode, LdvProtocolError};
pub use framer::{MAX_LINE_CONTENT, MAX_LINE_LEN};
pub use number::MAX_NUMBER_LEN;
pub use position::{MirrorAngle, MirrorAngles, PlateCoord, PlatePoint};
pub use reply::{Identity, REPLY_TERMINATOR, Reply, encode_reply, encode_reply_into};
pub use settings::{CalibrationState, LaserState, SignalLevel, SyncToken, TrackingFilter, VelocityRange};
pub use text::{ErrorText, IdentityField, MAX_ERROR_TEXT_LEN, MAX_IDENTITY_FIELD_LEN};

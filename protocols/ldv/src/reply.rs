//! Controller-to-host replies: the typed form, its encoding (device side) and its parsing (host side).

use std::fmt;

use crate::error::{ErrorCode, LdvProtocolError};
use crate::position::{MirrorAngles, PlatePoint};
use crate::settings::{CalibrationState, LaserState, SignalLevel, SyncToken, TrackingFilter, VelocityRange};
use crate::syntax::{Tokens, kw};
use crate::text::{ErrorText, IdentityField};

/// Terminator of an encoded reply line: CR LF.
pub const REPLY_TERMINATOR: &[u8] = b"\r\n";

/// The controller's identity, the answer to `*IDN?`: `IDN <vendor>,<model>,<serial>,<firmware>`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Identity {
    /// Manufacturer, for example `Ometron`.
    pub vendor: IdentityField,
    /// Model, for example `8330`.
    pub model: IdentityField,
    /// Serial number.
    pub serial: IdentityField,
    /// Firmware version.
    pub firmware: IdentityField,
}

/// One reply line from the controller. Every command gets exactly one.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Reply {
    /// `OK`: a setting or move was carried out (a move: the mirrors have settled).
    Ok,
    /// `ERR <code> <text>`: the command failed; the code says why, the text is for people.
    Error {
        /// The error code (see the crate documentation's table).
        code: ErrorCode,
        /// Human-readable detail, possibly empty.
        text: ErrorText,
    },
    /// `IDN <vendor>,<model>,<serial>,<firmware>`.
    Identity(Identity),
    /// `POS <x_mm> <y_mm>`: the beam's position in the plate frame.
    Position(PlatePoint),
    /// `ANG <x_deg> <y_deg>`: the mirrors' angles.
    Angles(MirrorAngles),
    /// `SIG <percent>`: the signal level.
    Signal(SignalLevel),
    /// `VRANGE <mm/s/V>`: the velocity range.
    VelocityRange(VelocityRange),
    /// `TRACK <OFF|SLOW|MEDIUM|FAST>`: the tracking filter.
    TrackingFilter(TrackingFilter),
    /// `LASER <ON|OFF>`: the laser state.
    Laser(LaserState),
    /// `CAL <YES|NO>`: whether a plate calibration is in force.
    Calibration(CalibrationState),
    /// `SYNC <token>`: the echo of a `SYNC` command.
    Sync(SyncToken),
}

impl Reply {
    /// The `ERR` reply a controller sends for a command line that failed to decode: the error's code, and its
    /// message as text (made printable and cut to length by [`ErrorText::lossy`]).
    pub fn from_error(error: &LdvProtocolError) -> Self {
        Reply::Error { code: error.error_code(), text: ErrorText::lossy(&error.to_string()) }
    }

    /// Parses one reply line's content (without its terminator): the host side's decoding of one line.
    ///
    /// # Errors
    /// [`LdvProtocolError::UnknownKeyword`] for an unknown first word; [`LdvProtocolError::ArgumentCount`],
    /// [`LdvProtocolError::MalformedNumber`], [`LdvProtocolError::InvalidChoice`],
    /// [`LdvProtocolError::OutOfRange`], [`LdvProtocolError::InvalidText`] or
    /// [`LdvProtocolError::UnknownErrorCode`] for a malformed value.
    pub fn parse_line(line: &str) -> Result<Self, LdvProtocolError> {
        let mut tokens = Tokens::new(line);
        let keyword = tokens.next_word().unwrap_or("");
        let reply = match keyword.to_ascii_uppercase().as_str() {
            kw::OK => tokens.args::<0>(kw::OK).map(|_| Reply::Ok)?,
            kw::ERR => parse_error(tokens)?,
            kw::IDN => Reply::Identity(parse_identity(tokens.rest())?),
            kw::POS => {
                let [x, y] = tokens.args(kw::POS)?;
                Reply::Position(PlatePoint { x: x.parse()?, y: y.parse()? })
            }
            kw::ANG => {
                let [x, y] = tokens.args(kw::ANG)?;
                Reply::Angles(MirrorAngles { x: x.parse()?, y: y.parse()? })
            }
            kw::SIG => tokens.args(kw::SIG).and_then(|[v]| v.parse().map(Reply::Signal))?,
            kw::VRANGE => tokens.args(kw::VRANGE).and_then(|[v]| v.parse().map(Reply::VelocityRange))?,
            kw::TRACK => tokens.args(kw::TRACK).and_then(|[v]| v.parse().map(Reply::TrackingFilter))?,
            kw::LASER => tokens.args(kw::LASER).and_then(|[v]| v.parse().map(Reply::Laser))?,
            kw::CAL => tokens.args(kw::CAL).and_then(|[v]| v.parse().map(Reply::Calibration))?,
            kw::SYNC => tokens.args(kw::SYNC).and_then(|[v]| v.parse().map(Reply::Sync))?,
            _ => return Err(LdvProtocolError::UnknownKeyword { keyword: keyword.to_owned() }),
        };
        Ok(reply)
    }
}

/// `ERR <code> [text]`: the code is a decimal integer that must be in the table; the text is the rest of the line.
fn parse_error(mut tokens: Tokens<'_>) -> Result<Reply, LdvProtocolError> {
    let code_text =
        tokens.next_word().ok_or(LdvProtocolError::ArgumentCount { keyword: kw::ERR, expected: 1, found: 0 })?;
    let number = crate::number::parse_scaled(code_text, 0, "error code")?;
    let code = ErrorCode::from_number(number).ok_or(LdvProtocolError::UnknownErrorCode { code: number })?;
    Ok(Reply::Error { code, text: ErrorText::new(tokens.rest())? })
}

/// `<vendor>,<model>,<serial>,<firmware>`; spaces around a field are dropped.
fn parse_identity(text: &str) -> Result<Identity, LdvProtocolError> {
    let fields: Vec<&str> = text.split(',').map(|field| field.trim_matches(' ')).collect();
    let [vendor, model, serial, firmware] = fields[..] else {
        return Err(LdvProtocolError::ArgumentCount { keyword: kw::IDN, expected: 4, found: fields.len() });
    };
    Ok(Identity {
        vendor: IdentityField::new(vendor)?,
        model: IdentityField::new(model)?,
        serial: IdentityField::new(serial)?,
        firmware: IdentityField::new(firmware)?,
    })
}

impl fmt::Display for Reply {
    /// The wire form of the line, without its terminator (for example `SIG 87`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reply::Ok => f.write_str(kw::OK),
            Reply::Error { code, text } if text.as_str().is_empty() => write!(f, "{} {}", kw::ERR, code.number()),
            Reply::Error { code, text } => write!(f, "{} {} {text}", kw::ERR, code.number()),
            Reply::Identity(id) => {
                write!(f, "{} {},{},{},{}", kw::IDN, id.vendor, id.model, id.serial, id.firmware)
            }
            Reply::Position(p) => write!(f, "{} {} {}", kw::POS, p.x, p.y),
            Reply::Angles(a) => write!(f, "{} {} {}", kw::ANG, a.x, a.y),
            Reply::Signal(s) => write!(f, "{} {s}", kw::SIG),
            Reply::VelocityRange(r) => write!(f, "{} {r}", kw::VRANGE),
            Reply::TrackingFilter(t) => write!(f, "{} {t}", kw::TRACK),
            Reply::Laser(l) => write!(f, "{} {l}", kw::LASER),
            Reply::Calibration(c) => write!(f, "{} {c}", kw::CAL),
            Reply::Sync(t) => write!(f, "{} {t}", kw::SYNC),
        }
    }
}

/// Appends the encoded reply line, terminator included, to `out`. The line always fits [`crate::MAX_LINE_LEN`]
/// (the longest replies, an identity of four 24-byte fields and an `ERR` with a 100-byte text, take 105 and 108
/// bytes).
pub fn encode_reply_into(reply: &Reply, out: &mut Vec<u8>) {
    out.extend_from_slice(reply.to_string().as_bytes());
    out.extend_from_slice(REPLY_TERMINATOR);
}

/// The encoded reply line, terminator included (for example `b"SIG 87\r\n"`).
pub fn encode_reply(reply: &Reply) -> Vec<u8> {
    let mut out = Vec::new();
    encode_reply_into(reply, &mut out);
    out
}

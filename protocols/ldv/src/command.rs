//! Host-to-controller commands: the typed form, its encoding (host side) and its parsing (device side).

use std::fmt;

use crate::error::LdvProtocolError;
use crate::position::{MirrorAngles, PlatePoint};
use crate::reply::Reply;
use crate::settings::{LaserState, SyncToken, TrackingFilter, VelocityRange};
use crate::syntax::{Tokens, kw};

/// Terminator of an encoded command line: CR.
pub const COMMAND_TERMINATOR: &[u8] = b"\r";

/// One command from the host. See the command table in the crate documentation for the wire forms and replies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// `*IDN?`: vendor, model, serial number, firmware.
    Identify,
    /// `*RST`: power-on defaults (velocity range 25 mm/s/V, tracking off, mirrors at 0, 0), errors cleared; the
    /// laser state is kept.
    Reset,
    /// `*CLS`: clears a latched hardware fault (it returns if its cause persists).
    ClearErrors,
    /// `POS <x_mm> <y_mm>`: moves the beam to a point of the calibrated plate frame; replies once settled.
    MoveTo(PlatePoint),
    /// `ANG <x_deg> <y_deg>`: moves the mirrors to raw angles (no calibration needed); replies once settled.
    MoveToAngles(MirrorAngles),
    /// `POS?`: the beam's position in the plate frame.
    QueryPosition,
    /// `ANG?`: the mirrors' angles.
    QueryAngles,
    /// `SIG?`: the signal level.
    QuerySignal,
    /// `VRANGE <mm/s/V>`: sets the velocity range.
    SetVelocityRange(VelocityRange),
    /// `VRANGE?`: the velocity range.
    QueryVelocityRange,
    /// `TRACK <OFF|SLOW|MEDIUM|FAST>`: sets the tracking filter.
    SetTrackingFilter(TrackingFilter),
    /// `TRACK?`: the tracking filter.
    QueryTrackingFilter,
    /// `LASER <ON|OFF>`: switches the laser; `ON` replies once the laser is stable.
    SetLaser(LaserState),
    /// `LASER?`: the laser state.
    QueryLaser,
    /// `CAL?`: whether a plate calibration is in force.
    QueryCalibration,
    /// `SYNC <token>`: echoed as `SYNC <token>`, always; lets a driver drain stale replies after a timeout.
    Sync(SyncToken),
}

/// Recommended reply timeout for most commands, s (crate documentation, section 6).
pub const REPLY_TIMEOUT_S: f64 = 0.25;

/// Recommended reply timeout for `*RST` and `LASER ON`, which take up to 2 s, s.
pub const SLOW_REPLY_TIMEOUT_S: f64 = 3.0;

impl Command {
    /// How long a host should wait for this command's reply before resynchronising, s: [`SLOW_REPLY_TIMEOUT_S`]
    /// for `*RST` and `LASER ON`, [`REPLY_TIMEOUT_S`] for everything else. These cover the specified worst cases
    /// (section 6 of the crate documentation) with a margin for the line time and the host's scheduling.
    pub fn timeout_s(&self) -> f64 {
        match self {
            Command::Reset | Command::SetLaser(LaserState::On) => SLOW_REPLY_TIMEOUT_S,
            _ => REPLY_TIMEOUT_S,
        }
    }

    /// Parses one command line's content (without its terminator): the device side's decoding of one line.
    ///
    /// # Errors
    /// [`LdvProtocolError::UnknownKeyword`] for an unknown first word (an empty line included);
    /// [`LdvProtocolError::ArgumentCount`], [`LdvProtocolError::MalformedNumber`],
    /// [`LdvProtocolError::InvalidChoice`] or [`LdvProtocolError::OutOfRange`] for a bad argument. Their
    /// [`LdvProtocolError::error_code`] is the `ERR` code to reply with.
    pub fn parse_line(line: &str) -> Result<Self, LdvProtocolError> {
        let mut tokens = Tokens::new(line);
        let keyword = tokens.next_word().unwrap_or("");
        let command = match keyword.to_ascii_uppercase().as_str() {
            kw::IDN_QUERY => tokens.args::<0>(kw::IDN_QUERY).map(|_| Command::Identify)?,
            kw::RESET => tokens.args::<0>(kw::RESET).map(|_| Command::Reset)?,
            kw::CLEAR => tokens.args::<0>(kw::CLEAR).map(|_| Command::ClearErrors)?,
            kw::POS => {
                let [x, y] = tokens.args(kw::POS)?;
                Command::MoveTo(PlatePoint { x: x.parse()?, y: y.parse()? })
            }
            kw::ANG => {
                let [x, y] = tokens.args(kw::ANG)?;
                Command::MoveToAngles(MirrorAngles { x: x.parse()?, y: y.parse()? })
            }
            kw::POS_QUERY => tokens.args::<0>(kw::POS_QUERY).map(|_| Command::QueryPosition)?,
            kw::ANG_QUERY => tokens.args::<0>(kw::ANG_QUERY).map(|_| Command::QueryAngles)?,
            kw::SIG_QUERY => tokens.args::<0>(kw::SIG_QUERY).map(|_| Command::QuerySignal)?,
            kw::VRANGE => {
                let [range] = tokens.args(kw::VRANGE)?;
                Command::SetVelocityRange(range.parse()?)
            }
            kw::VRANGE_QUERY => tokens.args::<0>(kw::VRANGE_QUERY).map(|_| Command::QueryVelocityRange)?,
            kw::TRACK => {
                let [filter] = tokens.args(kw::TRACK)?;
                Command::SetTrackingFilter(filter.parse()?)
            }
            kw::TRACK_QUERY => tokens.args::<0>(kw::TRACK_QUERY).map(|_| Command::QueryTrackingFilter)?,
            kw::LASER => {
                let [state] = tokens.args(kw::LASER)?;
                Command::SetLaser(state.parse()?)
            }
            kw::LASER_QUERY => tokens.args::<0>(kw::LASER_QUERY).map(|_| Command::QueryLaser)?,
            kw::CAL_QUERY => tokens.args::<0>(kw::CAL_QUERY).map(|_| Command::QueryCalibration)?,
            kw::SYNC => {
                let [token] = tokens.args(kw::SYNC)?;
                Command::Sync(token.parse()?)
            }
            _ => return Err(LdvProtocolError::UnknownKeyword { keyword: keyword.to_owned() }),
        };
        Ok(command)
    }

    /// Whether `reply` is a proper answer to this command: `OK` (or `ERR`) to a setting or move, the matching value
    /// reply (or `ERR`) to a query, and to `SYNC` only `SYNC` with the same token. A driver that receives a reply
    /// for which this is false is reading a stale reply, and should resynchronise with `SYNC`.
    pub fn is_answered_by(&self, reply: &Reply) -> bool {
        match (self, reply) {
            (Command::Sync(sent), Reply::Sync(echoed)) => sent == echoed,
            (Command::Sync(_), _) => false,
            (_, Reply::Error { .. }) => true,
            (
                Command::Reset
                | Command::ClearErrors
                | Command::MoveTo(_)
                | Command::MoveToAngles(_)
                | Command::SetVelocityRange(_)
                | Command::SetTrackingFilter(_)
                | Command::SetLaser(_),
                Reply::Ok,
            ) => true,
            (Command::Identify, Reply::Identity(_))
            | (Command::QueryPosition, Reply::Position(_))
            | (Command::QueryAngles, Reply::Angles(_))
            | (Command::QuerySignal, Reply::Signal(_))
            | (Command::QueryVelocityRange, Reply::VelocityRange(_))
            | (Command::QueryTrackingFilter, Reply::TrackingFilter(_))
            | (Command::QueryLaser, Reply::Laser(_))
            | (Command::QueryCalibration, Reply::Calibration(_)) => true,
            _ => false,
        }
    }
}

impl fmt::Display for Command {
    /// The wire form of the line, without its terminator (for example `POS 12.000 -3.500`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Command::Identify => f.write_str(kw::IDN_QUERY),
            Command::Reset => f.write_str(kw::RESET),
            Command::ClearErrors => f.write_str(kw::CLEAR),
            Command::MoveTo(p) => write!(f, "{} {} {}", kw::POS, p.x, p.y),
            Command::MoveToAngles(a) => write!(f, "{} {} {}", kw::ANG, a.x, a.y),
            Command::QueryPosition => f.write_str(kw::POS_QUERY),
            Command::QueryAngles => f.write_str(kw::ANG_QUERY),
            Command::QuerySignal => f.write_str(kw::SIG_QUERY),
            Command::SetVelocityRange(r) => write!(f, "{} {r}", kw::VRANGE),
            Command::QueryVelocityRange => f.write_str(kw::VRANGE_QUERY),
            Command::SetTrackingFilter(t) => write!(f, "{} {t}", kw::TRACK),
            Command::QueryTrackingFilter => f.write_str(kw::TRACK_QUERY),
            Command::SetLaser(l) => write!(f, "{} {l}", kw::LASER),
            Command::QueryLaser => f.write_str(kw::LASER_QUERY),
            Command::QueryCalibration => f.write_str(kw::CAL_QUERY),
            Command::Sync(t) => write!(f, "{} {t}", kw::SYNC),
        }
    }
}

/// Appends the encoded command line, terminator included, to `out`. The line always fits
/// [`crate::MAX_LINE_LEN`] (the longest command, `POS -500.000 -500.000`, takes 22 bytes).
pub fn encode_command_into(command: &Command, out: &mut Vec<u8>) {
    out.extend_from_slice(command.to_string().as_bytes());
    out.extend_from_slice(COMMAND_TERMINATOR);
}

/// The encoded command line, terminator included (for example `b"SIG?\r"`).
pub fn encode_command(command: &Command) -> Vec<u8> {
    let mut out = Vec::new();
    encode_command_into(command, &mut out);
    out
}

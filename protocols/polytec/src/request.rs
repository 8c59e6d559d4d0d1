//! Requests (host to controller): `Verb,Device,Index,Attribute[,Value]`, one line each, ended by LF.

use std::fmt;

use crate::error::PolytecProtocolError;
use crate::framer::{LineFramer, MAX_LINE_CONTENT};

/// What a request does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Verb {
    /// `Get`: the attribute's current value; one reply line.
    Get,
    /// `Set`: changes the attribute; no reply (the manual's examples read nothing back; an invalid value is
    /// ignored, so the host reads the attribute back with `Get`).
    Set,
    /// `GetDevInfo`: what the unit has: the installed item's name, or the values the attribute may take (a
    /// decoder's ranges), or `Not Available`; one reply line.
    GetDevInfo,
}

impl Verb {
    /// The verb's wire spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Verb::Get => "Get",
            Verb::Set => "Set",
            Verb::GetDevInfo => "GetDevInfo",
        }
    }

    /// Whether the controller answers the request with a line.
    pub fn expects_reply(self) -> bool {
        !matches!(self, Verb::Set)
    }
}

/// The unit a request addresses; with the index, one of possibly several of its kind (a controller may carry two
/// velocity decoders, `VeloDec,0` and `VeloDec,1`; which model sits at which index differs from unit to unit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Device {
    /// `Controller`: name, version, remote state, power-up settings.
    Controller,
    /// `Interface`: the RS-232 interface itself (name, baud rate, echo).
    Interface,
    /// `SensorHead`: name, version, focus and autofocus.
    SensorHead,
    /// `VeloDec`: a velocity decoder (range, maximum frequency, signal delay, filters).
    VeloDec,
    /// `DisplDec`: a displacement decoder.
    DisplDec,
    /// `SignalLevel`: the returned light's level.
    SignalLevel,
}

impl Device {
    /// Every device, for decoding.
    pub const ALL: [Device; 6] = [
        Device::Controller,
        Device::Interface,
        Device::SensorHead,
        Device::VeloDec,
        Device::DisplDec,
        Device::SignalLevel,
    ];

    /// The device's wire spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Device::Controller => "Controller",
            Device::Interface => "Interface",
            Device::SensorHead => "SensorHead",
            Device::VeloDec => "VeloDec",
            Device::DisplDec => "DisplDec",
            Device::SignalLevel => "SignalLevel",
        }
    }
}

/// One request line.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Request {
    verb: Verb,
    device: Device,
    index: u8,
    attribute: String,
    value: Option<String>,
}

impl Request {
    /// `Get,<device>,<index>,<attribute>`.
    ///
    /// # Errors
    /// [`PolytecProtocolError::BadField`] when `attribute` is not a word of letters and digits.
    pub fn get(device: Device, index: u8, attribute: &str) -> Result<Self, PolytecProtocolError> {
        Self::new(Verb::Get, device, index, attribute, None)
    }

    /// `GetDevInfo,<device>,<index>,<attribute>`.
    ///
    /// # Errors
    /// As [`Request::get`].
    pub fn dev_info(device: Device, index: u8, attribute: &str) -> Result<Self, PolytecProtocolError> {
        Self::new(Verb::GetDevInfo, device, index, attribute, None)
    }

    /// `Set,<device>,<index>,<attribute>,<value>`.
    ///
    /// # Errors
    /// As [`Request::get`]; [`PolytecProtocolError::BadField`] when `value` is empty or holds a control character.
    pub fn set(device: Device, index: u8, attribute: &str, value: &str) -> Result<Self, PolytecProtocolError> {
        Self::new(Verb::Set, device, index, attribute, Some(value))
    }

    fn new(
        verb: Verb,
        device: Device,
        index: u8,
        attribute: &str,
        value: Option<&str>,
    ) -> Result<Self, PolytecProtocolError> {
        check_attribute(attribute)?;
        if let Some(v) = value {
            check_value(v)?;
        }
        let request = Self { verb, device, index, attribute: attribute.to_owned(), value: value.map(str::to_owned) };
        if request.to_string().len() > MAX_LINE_CONTENT {
            return Err(PolytecProtocolError::BadField {
                field: attribute.to_owned(),
                detail: format!("the line would exceed {MAX_LINE_CONTENT} bytes"),
            });
        }
        Ok(request)
    }

    /// The verb.
    pub fn verb(&self) -> Verb {
        self.verb
    }

    /// The device addressed.
    pub fn device(&self) -> Device {
        self.device
    }

    /// The device's index.
    pub fn index(&self) -> u8 {
        self.index
    }

    /// The attribute (`Range`, `Name`, `Value`, ...).
    pub fn attribute(&self) -> &str {
        &self.attribute
    }

    /// The value of a `Set` (`5mm/s/V`); everything after the attribute's comma, so it may hold commas itself
    /// (`AutoFocusArea,100,2000`).
    pub fn value(&self) -> Option<&str> {
        self.value.as_deref()
    }

    /// The request on the wire: its text and LF.
    pub fn encode(&self) -> Vec<u8> {
        let mut bytes = self.to_string().into_bytes();
        bytes.push(b'\n');
        bytes
    }

    /// Decodes one line's content (no terminator).
    ///
    /// # Errors
    /// [`PolytecProtocolError::MalformedRequest`] naming what is wrong.
    pub fn parse(line: &str) -> Result<Self, PolytecProtocolError> {
        let bad = |detail: &str| PolytecProtocolError::MalformedRequest {
            line: line.chars().take(MAX_LINE_CONTENT).collect(),
            detail: detail.to_owned(),
        };
        let mut fields = line.splitn(5, ',');
        let verb = match fields.next().map(str::trim) {
            Some("Get") => Verb::Get,
            Some("Set") => Verb::Set,
            Some("GetDevInfo") => Verb::GetDevInfo,
            _ => return Err(bad("the verb is not Get, Set or GetDevInfo")),
        };
        let device_name = fields.next().map(str::trim).ok_or_else(|| bad("no device"))?;
        let device =
            Device::ALL.into_iter().find(|d| d.as_str() == device_name).ok_or_else(|| bad("unknown device"))?;
        let index = fields
            .next()
            .map(str::trim)
            .and_then(|i| if i.len() <= 3 && i.bytes().all(|b| b.is_ascii_digit()) { i.parse().ok() } else { None })
            .ok_or_else(|| bad("the index is not an integer 0 to 255"))?;
        let attribute = fields.next().map(str::trim).ok_or_else(|| bad("no attribute"))?;
        let value = fields.next().map(str::trim);
        match (verb, value) {
            (Verb::Set, None) => return Err(bad("Set without a value")),
            (Verb::Get | Verb::GetDevInfo, Some(_)) => return Err(bad("a query takes no value")),
            _ => {}
        }
        Self::new(verb, device, index, attribute, value).map_err(|e| bad(&e.to_string()))
    }
}

impl fmt::Display for Request {
    /// The wire text without its terminator.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{},{},{}", self.verb.as_str(), self.device.as_str(), self.index, self.attribute)?;
        if let Some(value) = &self.value {
            write!(f, ",{value}")?;
        }
        Ok(())
    }
}

fn check_attribute(attribute: &str) -> Result<(), PolytecProtocolError> {
    if attribute.is_empty() || attribute.len() > 64 || !attribute.bytes().all(|b| b.is_ascii_alphanumeric()) {
        return Err(PolytecProtocolError::BadField {
            field: attribute.chars().take(64).collect(),
            detail: "an attribute is 1 to 64 letters and digits".into(),
        });
    }
    Ok(())
}

fn check_value(value: &str) -> Result<(), PolytecProtocolError> {
    if value.trim().is_empty() || value.chars().any(char::is_control) {
        return Err(PolytecProtocolError::BadField {
            field: value.chars().take(64).collect(),
            detail: "a value is non-empty text without control characters".into(),
        });
    }
    Ok(())
}

/// The device side's decoder: bytes from the host in, requests out (the mock controller, and the fuzz target).
#[derive(Debug, Default)]
pub struct RequestDecoder {
    framer: LineFramer,
}

impl RequestDecoder {
    /// An empty decoder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.framer.push(bytes);
    }

    /// The next complete request, or why its line did not decode; `None` when more bytes are needed.
    pub fn poll(&mut self) -> Option<Result<Request, PolytecProtocolError>> {
        self.framer.next_line().map(|line| line.and_then(|l| Request::parse(&l)))
    }

    /// Bytes held, for bounding memory.
    pub fn buffered_len(&self) -> usize {
        self.framer.buffered_len()
    }

    /// Drops everything held (a reopened link).
    pub fn clear(&mut self) {
        self.framer.clear();
    }
}

//! `PolytecDriver`: the [`Vibrometer`] capability over a Polytec controller's RS-232 interface.

use metaplate_core::vibrometer::{Tracking, VelocityScale, Vibrometer, VibrometerError, VibrometerIdentity};
use metaplate_polytec_protocol::{Device, Request, VelocityRange, parse_count, split_list};

use crate::config::{DecoderChoice, FocusSpan, MAX_DECODERS, OUTPUT_FULL_SCALE_V, PolytecConfig};
use crate::line::SerialLine;
use crate::link::{Answer, Link};
use crate::policy::RetryPolicy;

/// The velocity decoder in use, as the unit reported it when the driver connected.
#[derive(Debug, Clone, PartialEq)]
pub struct DecoderInfo {
    /// Its index (`VeloDec,<index>`).
    pub index: u8,
    /// Its name (`VD-09`).
    pub name: String,
    /// Its ranges, most sensitive first.
    pub ranges: Vec<VelocityRange>,
}

/// The settings made through the driver, re-applied after a reconnect (the controller may have been power-cycled).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AppliedSettings {
    /// The last velocity range set, if any.
    pub range: Option<VelocityRange>,
    /// The last tracking filter set, if any (its wire spelling).
    pub tracking: Option<String>,
}

/// Polls of `AutoFocusResult` before an autofocus is reported as failed (PLACE waits up to 30 polls).
const AUTOFOCUS_POLLS: u32 = 30;

/// A Polytec controller (OFV-5000, OFV-5000 Xtra, VibroFlex) on any [`SerialLine`].
///
/// Connecting (at the first call, and after a reconnect): echo off (`Set,Interface,0,Echo,Off`), remote on
/// (`Set,Controller,0,Remote,On`, read back), the velocity decoder found by query (`GetDevInfo,VeloDec,<i>,Name`
/// for i = 0, 1, ... as [`PolytecConfig::decoder`] says) with its ranges (`GetDevInfo,VeloDec,<i>,Range`), the
/// signal level's bounds (`GetDevInfo,SignalLevel,0,Value`), then the file's low-pass filter and autofocus, then
/// the range and tracking filter set through this handle. Every `Set` is read back with its `Get` (the
/// controller ignores an invalid setting) and sent again when it did not take.
pub struct PolytecDriver<T: SerialLine> {
    link: Link<T>,
    config: PolytecConfig,
    decoder: Option<DecoderInfo>,
    signal_max: u32,
    settings: AppliedSettings,
}

impl<T: SerialLine> std::fmt::Debug for PolytecDriver<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PolytecDriver")
            .field("config", &self.config)
            .field("decoder", &self.decoder)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

fn request(r: Result<Request, metaplate_polytec_protocol::PolytecProtocolError>) -> Result<Request, VibrometerError> {
    r.map_err(|e| VibrometerError::InvalidArgument { detail: e.to_string() })
}

fn text(answer: &Answer) -> Result<String, String> {
    match answer {
        Answer::Text(t) => Ok(t.clone()),
        Answer::NotAvailable => Err("the unit says Not Available".into()),
    }
}

impl<T: SerialLine> PolytecDriver<T> {
    /// A driver on an open `line`; it sends nothing until its first call.
    ///
    /// # Errors
    /// [`VibrometerError::InvalidArgument`] when `policy` is out of range ([`RetryPolicy::validate`]).
    pub fn new(line: T, policy: RetryPolicy, config: PolytecConfig) -> Result<Self, VibrometerError> {
        policy.validate()?;
        Ok(Self {
            link: Link::new(line, policy),
            config,
            decoder: None,
            signal_max: 0,
            settings: AppliedSettings::default(),
        })
    }

    /// The transport (for example to inspect a mock).
    pub fn line(&self) -> &T {
        self.link.line()
    }

    /// The settings that [`Vibrometer::reconnect`] re-applies.
    pub fn settings(&self) -> &AppliedSettings {
        &self.settings
    }

    /// The velocity decoder in use, connecting first if needed.
    ///
    /// # Errors
    /// As connecting: `Device` when the decoder asked for is not installed; `Timeout`, `Disconnected`.
    pub fn decoder(&mut self) -> Result<DecoderInfo, VibrometerError> {
        self.connected().cloned()
    }

    fn connected(&mut self) -> Result<&DecoderInfo, VibrometerError> {
        if self.decoder.is_none() {
            self.connect()?;
        }
        self.decoder.as_ref().ok_or_else(|| VibrometerError::Protocol { detail: "no decoder after connecting".into() })
    }

    fn connect(&mut self) -> Result<(), VibrometerError> {
        self.link.send(&request(Request::set(Device::Interface, 0, "Echo", "Off"))?)?;
        self.set_verified(Device::Controller, 0, "Remote", "On")?;
        let decoder = self.find_decoder()?;
        self.signal_max = self.link.query(&request(Request::dev_info(Device::SignalLevel, 0, "Value"))?, |a| {
            let t = text(a)?;
            match split_list(&t).as_slice() {
                [_, max] => parse_count(max)
                    .map_err(|e| e.to_string())
                    .and_then(|m| if m > 0 { Ok(m) } else { Err("a maximum level of 0".into()) }),
                _ => Err("not a min,max pair".into()),
            }
        })?;
        let index = decoder.index;
        self.decoder = Some(decoder);
        if let Some(low_pass) = self.config.low_pass.clone() {
            self.set_option(index, "LowPass", &low_pass)?;
        }
        if let Some(span) = self.config.autofocus {
            self.autofocus(span)?;
        }
        let saved = self.settings.clone();
        if let Some(range) = saved.range {
            self.set_verified(Device::VeloDec, index, "Range", range.text())?;
        }
        if let Some(tracking) = saved.tracking {
            self.set_option(index, "TrackingFilter", &tracking)?;
        }
        Ok(())
    }

    /// The velocity decoder as the configuration chooses it, with its ranges.
    fn find_decoder(&mut self) -> Result<DecoderInfo, VibrometerError> {
        let mut installed = Vec::new();
        for index in 0..MAX_DECODERS {
            let name = self.link.query(&request(Request::dev_info(Device::VeloDec, index, "Name"))?, |a| {
                Ok(match a {
                    Answer::Text(t) => Some(t.clone()),
                    Answer::NotAvailable => None,
                })
            })?;
            // Decoders are numbered from 0 without gaps: the first missing index ends the list.
            let Some(name) = name else { break };
            let wanted = match &self.config.decoder {
                DecoderChoice::First => true,
                DecoderChoice::Index(i) => *i == index,
                DecoderChoice::Name(n) => n.eq_ignore_ascii_case(&name),
            };
            if wanted {
                let ranges = self.decoder_ranges(index)?;
                return Ok(DecoderInfo { index, name, ranges });
            }
            installed.push(format!("VeloDec,{index} = {name}"));
        }
        Err(VibrometerError::Device {
            code: 0,
            message: format!(
                "no velocity decoder {:?} on this unit (installed: {})",
                self.config.decoder,
                if installed.is_empty() { "none".to_owned() } else { installed.join(", ") }
            ),
        })
    }

    fn decoder_ranges(&mut self, index: u8) -> Result<Vec<VelocityRange>, VibrometerError> {
        let mut ranges = self.link.query(&request(Request::dev_info(Device::VeloDec, index, "Range"))?, |a| {
            let t = text(a)?;
            let ranges: Result<Vec<_>, _> = split_list(&t).into_iter().map(VelocityRange::parse).collect();
            match ranges {
                Ok(r) if !r.is_empty() => Ok(r),
                Ok(_) => Err("an empty list".into()),
                Err(e) => Err(e.to_string()),
            }
        })?;
        ranges.sort_by(|a, b| a.m_s_per_v().total_cmp(&b.m_s_per_v()));
        Ok(ranges)
    }

    /// `Set` then `Get` until the unit reads back `value` (compared without letter case and spaces).
    fn set_verified(&mut self, device: Device, index: u8, attribute: &str, value: &str) -> Result<(), VibrometerError> {
        let set = request(Request::set(device, index, attribute, value))?;
        let get = request(Request::get(device, index, attribute))?;
        let same = |a: &str| a.replace(' ', "").eq_ignore_ascii_case(&value.replace(' ', ""));
        let mut kept = String::new();
        for _ in 0..2 {
            self.link.send(&set)?;
            kept = self.link.query(&get, text)?;
            if same(&kept) {
                return Ok(());
            }
        }
        Err(VibrometerError::Device { code: 0, message: format!("{set} did not take: the unit reads back {kept:?}") })
    }

    /// A setting the unit may lack: checked against its `GetDevInfo` list first.
    fn set_option(&mut self, index: u8, attribute: &str, value: &str) -> Result<(), VibrometerError> {
        let info = request(Request::dev_info(Device::VeloDec, index, attribute))?;
        let options = self.link.query(&info, |a| {
            Ok(match a {
                Answer::Text(t) => Some(split_list(t).into_iter().map(str::to_owned).collect::<Vec<_>>()),
                Answer::NotAvailable => None,
            })
        })?;
        match options {
            None => Err(VibrometerError::Device { code: 0, message: format!("this decoder has no {attribute}") }),
            Some(o) if !o.iter().any(|v| v.eq_ignore_ascii_case(value)) => Err(VibrometerError::Device {
                code: 0,
                message: format!("{attribute} {value:?} is not on this decoder (it has {})", o.join(", ")),
            }),
            Some(_) => self.set_verified(Device::VeloDec, index, attribute, value),
        }
    }

    /// Runs the sensor head's autofocus over `span` (PLACE's `_autofocus_vibrometer`): span, `Search`, then polls
    /// `AutoFocusResult` until `Found`.
    ///
    /// # Errors
    /// `Device` when the head has no autofocus or does not find focus within 30 polls; `Timeout`, `Disconnected`.
    pub fn autofocus(&mut self, span: FocusSpan) -> Result<(), VibrometerError> {
        let info = request(Request::dev_info(Device::SensorHead, 0, "AutoFocus"))?;
        let has = self.link.query(&info, |a| Ok(matches!(a, Answer::Text(_))))?;
        if !has {
            return Err(VibrometerError::Device { code: 0, message: "this sensor head has no autofocus".into() });
        }
        self.link.send(&request(Request::set(Device::SensorHead, 0, "AutoFocusSpan", span.as_str()))?)?;
        self.link.send(&request(Request::set(Device::SensorHead, 0, "AutoFocus", "Search"))?)?;
        let result = request(Request::get(Device::SensorHead, 0, "AutoFocusResult"))?;
        let mut last = String::new();
        for _ in 0..AUTOFOCUS_POLLS {
            last = self.link.query(&result, text)?;
            if last.eq_ignore_ascii_case("Found") {
                return Ok(());
            }
        }
        Err(VibrometerError::Device { code: 0, message: format!("autofocus did not find focus (last: {last:?})") })
    }

    /// Sends one request as it is, with the retries: a `Set` gets no answer (`None`); a query's answer is its text,
    /// or `Not Available` spelt so. For tools that replay a recorded session request by request.
    ///
    /// # Errors
    /// `Timeout` when every attempt missed; `Disconnected` when the line is gone.
    pub fn exchange(&mut self, request: &Request) -> Result<Option<String>, VibrometerError> {
        if request.verb().expects_reply() {
            let answer = self.link.query(request, |a| {
                Ok(match a {
                    Answer::Text(t) => t.clone(),
                    Answer::NotAvailable => metaplate_polytec_protocol::NOT_AVAILABLE.to_owned(),
                })
            })?;
            Ok(Some(answer))
        } else {
            self.link.send(request).map(|()| None)
        }
    }

    fn get_text(&mut self, device: Device, attribute: &str) -> Result<String, VibrometerError> {
        let r = request(Request::get(device, 0, attribute))?;
        self.link.query(&r, |a| {
            Ok(match a {
                Answer::Text(t) => t.clone(),
                Answer::NotAvailable => "not available".to_owned(),
            })
        })
    }
}

/// Whether a Polytec controller answers on `line`: sends `GetDevInfo,Controller,0,Name` once and returns the
/// name it answers within `timeout_s` seconds (clamped to 0.001 to 60 s). For listing what is on a system's ports.
///
/// # Errors
/// `Timeout` when nothing usable answers; `Disconnected` when the line is gone.
pub fn probe_polytec<T: SerialLine>(line: T, timeout_s: f64) -> Result<String, VibrometerError> {
    let reply_timeout_s = if timeout_s.is_nan() { 0.001 } else { timeout_s.clamp(0.001, 60.0) };
    let mut link = Link::new(line, RetryPolicy { attempts: 1, reply_timeout_s, timeout_scale: 1.0 });
    link.query(&request(Request::dev_info(Device::Controller, 0, "Name"))?, text)
}

/// The most sensitive range whose full scale reaches `max_velocity_m_s`, among `ranges` (sorted, most sensitive
/// first); a low-pass variant (`50mm/s/V LP`) only where the decoder has no plain range of that scale.
fn range_for(ranges: &[VelocityRange], max_velocity_m_s: f64) -> Result<&VelocityRange, VibrometerError> {
    let found = (max_velocity_m_s.is_finite() && max_velocity_m_s > 0.0)
        .then(|| {
            let covers = |r: &&VelocityRange| r.m_s_per_v() * OUTPUT_FULL_SCALE_V >= max_velocity_m_s;
            let plain = ranges.iter().filter(|r| !r.low_pass()).find(covers);
            plain.or_else(|| ranges.iter().find(covers))
        })
        .flatten();
    found.ok_or_else(|| VibrometerError::InvalidArgument {
        detail: format!(
            "max_velocity_m_s = {max_velocity_m_s} is outside (0, {}] m/s, the decoder's largest full scale",
            ranges.last().map_or(0.0, |r| r.m_s_per_v() * OUTPUT_FULL_SCALE_V)
        ),
    })
}

fn tracking_value(tracking: Tracking) -> &'static str {
    match tracking {
        Tracking::Off => "Off",
        Tracking::Slow => "Slow",
        Tracking::Medium => "Medium",
        Tracking::Fast => "Fast",
    }
}

impl<T: SerialLine> Vibrometer for PolytecDriver<T> {
    /// `Polytec`; the model is the controller's name (`GetDevInfo,Controller,0,Name`), its sensor head
    /// (`Get,SensorHead,0,Name`) and the decoder; the firmware the controller's and the head's versions. The
    /// RS-232 commands in the public sources give no serial number: the identity says so.
    fn identify(&mut self) -> Result<VibrometerIdentity, VibrometerError> {
        let decoder = self.connected()?.clone();
        let name = self.link.query(&request(Request::dev_info(Device::Controller, 0, "Name"))?, text)?;
        let controller_version = self.get_text(Device::Controller, "Version")?;
        let head = self.get_text(Device::SensorHead, "Name")?;
        let head_version = self.get_text(Device::SensorHead, "Version")?;
        Ok(VibrometerIdentity {
            vendor: "Polytec".into(),
            model: format!("{name}; sensor head {head}; VeloDec,{} {}", decoder.index, decoder.name),
            serial: "not reported over RS-232".into(),
            firmware: format!("controller {controller_version}; sensor head {head_version}"),
        })
    }

    /// `Get,SignalLevel,0,Value` over the maximum `GetDevInfo,SignalLevel,0,Value` gave, clamped to 0..1.
    fn signal_level(&mut self) -> Result<f64, VibrometerError> {
        self.connected()?;
        let max = f64::from(self.signal_max.max(1));
        let r = request(Request::get(Device::SignalLevel, 0, "Value"))?;
        let level = self.link.query(&r, |a| parse_count(&text(a)?).map_err(|e| e.to_string()))?;
        Ok((f64::from(level) / max).clamp(0.0, 1.0))
    }

    fn set_velocity_range(&mut self, max_velocity_m_s: f64) -> Result<VelocityScale, VibrometerError> {
        let decoder = self.connected()?.clone();
        let range = range_for(&decoder.ranges, max_velocity_m_s)?.clone();
        self.set_verified(Device::VeloDec, decoder.index, "Range", range.text())?;
        let scale =
            VelocityScale { m_s_per_v: range.m_s_per_v(), full_scale_m_s: range.m_s_per_v() * OUTPUT_FULL_SCALE_V };
        self.settings.range = Some(range);
        Ok(scale)
    }

    fn set_tracking(&mut self, tracking: Tracking) -> Result<(), VibrometerError> {
        let index = self.connected()?.index;
        let value = tracking_value(tracking);
        self.set_option(index, "TrackingFilter", value)?;
        self.settings.tracking = Some(value.to_owned());
        Ok(())
    }

    /// Reopens the line and connects again: echo off, remote on, the decoder found again, then the file's
    /// filters and focus and the range and tracking filter set through this handle.
    fn reconnect(&mut self) -> Result<(), VibrometerError> {
        self.link.reopen()?;
        self.decoder = None;
        self.connect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_range_is_the_most_sensitive_that_covers() {
        let ranges: Vec<VelocityRange> = ["1mm/s/V", "5mm/s/V", "25mm/s/V", "125mm/s/V", "1m/s/V"]
            .iter()
            .map(|r| VelocityRange::parse(r).unwrap())
            .collect();
        // Exactly a full scale (10 V x range) picks that range; just above picks the next.
        for (v, want) in
            [(1e-9, "1mm/s/V"), (0.01, "1mm/s/V"), (0.010_001, "5mm/s/V"), (1.25, "125mm/s/V"), (10.0, "1m/s/V")]
        {
            assert_eq!(range_for(&ranges, v).unwrap().text(), want, "{v} m/s");
        }
        for bad in [0.0, -1.0, 10.000_001, f64::NAN] {
            assert!(matches!(range_for(&ranges, bad), Err(VibrometerError::InvalidArgument { .. })), "{bad}");
        }
    }
}

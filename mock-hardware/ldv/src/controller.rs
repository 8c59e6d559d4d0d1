//! The controller's state machine: one request in, at most one reply line out, in Polytec's syntax.

use metaplate_core::scene::LdvSpec;
use metaplate_polytec_protocol::{Device, NOT_AVAILABLE, Request, VelocityRange, Verb};

use crate::speckle::{DROPOUT_LEVEL_PERCENT, SpeckleModel};
use crate::unit::UnitSpec;

/// The state of one velocity decoder.
#[derive(Debug, Clone, PartialEq, Eq)]
struct DecoderState {
    range: usize,
    tracking: Option<usize>,
    low_pass: Option<usize>,
}

/// Where the controller holds the beam, m: whole micrometres (an exact aim reads back up to half of this off).
pub const BEAM_RESOLUTION_M: f64 = 1e-6;

/// The mock controller: its unit, each decoder's range and filters, remote and echo, the autofocus, and the
/// signal level from the scene's speckle model at the beam's spot (set by whoever aims the beam: in the mock lab,
/// the lab itself).
#[derive(Debug, Clone)]
pub struct MockController {
    unit: UnitSpec,
    speckle: SpeckleModel,
    decoders: Vec<DecoderState>,
    remote: String,
    echo: bool,
    focus_span: String,
    focus_polls_left: Option<u32>,
    beam_um: Option<(i32, i32)>,
    dropout_queries_left: u32,
}

/// `AutoFocusResult` polls answered `Searching` before `Found` (a search takes a moment on a real head).
const FOCUS_POLLS: u32 = 2;

impl MockController {
    /// `unit` at power-on, with the speckle of `spec` under `seed`.
    pub fn new(unit: UnitSpec, spec: &LdvSpec, seed: u64) -> Self {
        let mut me = Self {
            speckle: SpeckleModel::new(spec, seed),
            decoders: Vec::new(),
            remote: String::new(),
            echo: false,
            focus_span: String::new(),
            focus_polls_left: None,
            beam_um: None,
            dropout_queries_left: 0,
            unit,
        };
        me.power_cycle();
        me
    }

    /// Power cycle: decoders at their default ranges with filters off, remote `Local`, echo as at power-up; the
    /// unit, the speckle and the beam (aimed by another instrument) kept.
    pub fn power_cycle(&mut self) {
        self.decoders = self
            .unit
            .velocity_decoders
            .iter()
            .map(|d| DecoderState {
                range: d.default_range,
                tracking: (!d.tracking.is_empty()).then_some(0),
                low_pass: (!d.low_pass.is_empty()).then_some(0),
            })
            .collect();
        self.remote = "Local".into();
        self.echo = self.unit.echo_at_power_up;
        self.focus_span = "Full".into();
        self.focus_polls_left = None;
        self.dropout_queries_left = 0;
    }

    /// The unit.
    pub fn unit(&self) -> &UnitSpec {
        &self.unit
    }

    /// Puts the beam on (`x_m`, `y_m`), rounded to whole micrometres ([`BEAM_RESOLUTION_M`]; the speckle is drawn
    /// per micrometre); a new spot is tracked afresh, so a dropout in progress ends.
    pub fn set_beam(&mut self, x_m: f64, y_m: f64) {
        let um = |v: f64| (v / BEAM_RESOLUTION_M).round().clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        self.beam_um = Some((um(x_m), um(y_m)));
        self.dropout_queries_left = 0;
    }

    /// Where the beam is, m (whole micrometres); `None` before it was first aimed.
    pub fn beam_m(&self) -> Option<(f64, f64)> {
        self.beam_um.map(|(x, y)| (f64::from(x) * BEAM_RESOLUTION_M, f64::from(y) * BEAM_RESOLUTION_M))
    }

    /// The speckle level at the beam's spot, 0 to 1 (0 before the beam was aimed).
    pub fn speckle_level(&self) -> f64 {
        self.beam_um.map_or(0.0, |(x, y)| f64::from(self.speckle.level_percent(x, y)) / 100.0)
    }

    /// Makes the next `queries` signal-level queries report a dropout ([`DROPOUT_LEVEL_PERCENT`]), until the beam
    /// moves.
    pub fn start_dropout(&mut self, queries: u32) {
        self.dropout_queries_left = queries;
    }

    /// The velocity range in force on decoder `index`, parsed; `None` for a decoder the unit lacks.
    pub fn velocity_range(&self, index: u8) -> Option<VelocityRange> {
        let spec = self.unit.velocity_decoders.get(usize::from(index))?;
        let state = self.decoders.get(usize::from(index))?;
        spec.ranges.get(state.range).and_then(|r| VelocityRange::parse(r).ok())
    }

    /// The range in force on the first velocity decoder (the one the mock lab's output follows).
    pub fn output_range(&self) -> Option<VelocityRange> {
        self.velocity_range(0)
    }

    /// The tracking filter of decoder `index`, as spelt.
    pub fn tracking(&self, index: u8) -> Option<&str> {
        let spec = self.unit.velocity_decoders.get(usize::from(index))?;
        let i = self.decoders.get(usize::from(index))?.tracking?;
        spec.tracking.get(i).map(String::as_str)
    }

    /// The remote state (`Local` at power-on).
    pub fn remote(&self) -> &str {
        &self.remote
    }

    /// Whether the interface echoes lines.
    pub fn echo(&self) -> bool {
        self.echo
    }

    /// The reply to `request`: `None` for a `Set` (the manual's sets get no reply) and for anything the unit does
    /// not take (an invalid setting is ignored, OFV-3001 manual E.2.4); `Not Available` for what it lacks.
    pub fn answer(&mut self, request: &Request) -> Option<String> {
        match request.verb() {
            Verb::Set => {
                self.set(request);
                None
            }
            Verb::Get => Some(self.get(request).unwrap_or_else(|| NOT_AVAILABLE.to_owned())),
            Verb::GetDevInfo => Some(self.dev_info(request).unwrap_or_else(|| NOT_AVAILABLE.to_owned())),
        }
    }

    fn set(&mut self, request: &Request) {
        let value = request.value().unwrap_or_default();
        let index = usize::from(request.index());
        let pick = |options: &[String]| options.iter().position(|o| o.eq_ignore_ascii_case(value));
        match (request.device(), request.index(), request.attribute()) {
            (Device::Interface, 0, "Echo") if value == "On" || value == "Off" => self.echo = value == "On",
            (Device::Controller, 0, "Remote") if value == "On" || value == "Local" => self.remote = value.to_owned(),
            (Device::SensorHead, 0, "AutoFocusSpan") if ["Full", "Medium", "Small"].contains(&value) => {
                self.focus_span = value.to_owned();
            }
            (Device::SensorHead, 0, "AutoFocus") if value == "Search" && self.unit.autofocus => {
                self.focus_polls_left = Some(FOCUS_POLLS);
            }
            (Device::VeloDec, _, attribute) => {
                let (Some(spec), Some(state)) = (self.unit.velocity_decoders.get(index), self.decoders.get_mut(index))
                else {
                    return;
                };
                match attribute {
                    "Range" => {
                        // The unit takes a range in its own spelling, or the same scale spelt otherwise.
                        let asked = VelocityRange::parse(value).ok();
                        let found = pick(&spec.ranges).or_else(|| {
                            let asked = asked?;
                            spec.ranges.iter().position(|r| {
                                VelocityRange::parse(r)
                                    .is_ok_and(|r| r.same_scale(&asked) && r.low_pass() == asked.low_pass())
                            })
                        });
                        if let Some(i) = found {
                            state.range = i;
                        }
                    }
                    "TrackingFilter" => state.tracking = pick(&spec.tracking).or(state.tracking),
                    "LowPass" => state.low_pass = pick(&spec.low_pass).or(state.low_pass),
                    _ => {}
                }
            }
            _ => {}
        }
    }

    fn get(&mut self, request: &Request) -> Option<String> {
        let index = usize::from(request.index());
        match (request.device(), request.index(), request.attribute()) {
            (Device::Controller, 0, "Name") => Some(self.unit.controller_name.clone()),
            (Device::Controller, 0, "Version") => Some(self.unit.controller_version.clone()),
            (Device::Controller, 0, "Remote") => Some(self.remote.clone()),
            (Device::Interface, 0, "Name") => Some("RS-232".into()),
            (Device::Interface, 0, "Echo") => Some(if self.echo { "On" } else { "Off" }.into()),
            (Device::Interface, 0, "BaudRate") => Some("115200".into()),
            (Device::SensorHead, 0, "Name") => Some(self.unit.head_name.clone()),
            (Device::SensorHead, 0, "Version") => Some(self.unit.head_version.clone()),
            (Device::SensorHead, 0, "AutoFocusSpan") if self.unit.autofocus => Some(self.focus_span.clone()),
            (Device::SensorHead, 0, "AutoFocusResult") if self.unit.autofocus => Some(self.focus_result()),
            (Device::SignalLevel, 0, "Value") => Some(self.signal().to_string()),
            (Device::VeloDec, _, attribute) => {
                let spec = self.unit.velocity_decoders.get(index)?;
                let state = self.decoders.get(index)?;
                match attribute {
                    "Name" => Some(spec.name.clone()),
                    "Range" => spec.ranges.get(state.range).cloned(),
                    "TrackingFilter" => state.tracking.and_then(|i| spec.tracking.get(i)).cloned(),
                    "LowPass" => state.low_pass.and_then(|i| spec.low_pass.get(i)).cloned(),
                    _ => None,
                }
            }
            (Device::DisplDec, _, "Name") => self.unit.displacement_decoders.get(index).cloned(),
            _ => None,
        }
    }

    fn dev_info(&self, request: &Request) -> Option<String> {
        let index = usize::from(request.index());
        match (request.device(), request.index(), request.attribute()) {
            (Device::Controller, 0, "Name") => Some(self.unit.controller_name.clone()),
            (Device::Controller, 0, "Remote") => Some("Local,On".into()),
            (Device::Interface, 0, "Echo") => Some("Off,On".into()),
            (Device::SensorHead, 0, "Name") => Some(self.unit.head_name.clone()),
            (Device::SensorHead, 0, "AutoFocus") if self.unit.autofocus => Some("Search".into()),
            (Device::SensorHead, 0, "AutoFocusSpan") if self.unit.autofocus => Some("Full,Medium,Small".into()),
            (Device::SignalLevel, 0, "Value") => Some(format!("0,{}", self.unit.signal_max)),
            (Device::VeloDec, _, attribute) => {
                let spec = self.unit.velocity_decoders.get(index)?;
                let list = |v: &[String]| (!v.is_empty()).then(|| v.join(","));
                match attribute {
                    "Name" => Some(spec.name.clone()),
                    "Range" => list(&spec.ranges),
                    "TrackingFilter" => list(&spec.tracking),
                    "LowPass" => list(&spec.low_pass),
                    _ => None,
                }
            }
            (Device::DisplDec, _, "Name") => self.unit.displacement_decoders.get(index).cloned(),
            _ => None,
        }
    }

    fn focus_result(&mut self) -> String {
        match self.focus_polls_left {
            Some(0) | None => "Found".into(),
            Some(n) => {
                self.focus_polls_left = Some(n - 1);
                "Searching".into()
            }
        }
    }

    /// The signal level, on the unit's scale.
    fn signal(&mut self) -> u32 {
        let percent = if self.dropout_queries_left > 0 {
            self.dropout_queries_left -= 1;
            DROPOUT_LEVEL_PERCENT
        } else {
            self.beam_um.map_or(0, |(x, y)| self.speckle.level_percent(x, y))
        };
        // Exact when signal_max is 100 (the lab's unit): the level is the speckle's whole percent.
        (u64::from(percent) * u64::from(self.unit.signal_max) / 100).try_into().unwrap_or(u32::MAX)
    }
}

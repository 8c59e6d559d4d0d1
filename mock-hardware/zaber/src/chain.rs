//! The chain's state machine: host bytes in, replies out, per Zaber's ASCII protocol manual.
//!
//! What each command does here, with the manual's section:
//! - addressing (*Message Format*): device 0 is every device, each replying; a device not on the chain is
//!   silent; axis 0 is the device (for `home`, `stop` and `move`, every axis; for `get`, one value per axis);
//!   an axis the device lacks is `RJ ... BADAXIS`;
//! - the empty command (*Message Format*): a reply with the status and warning flag, data `0`;
//! - `home`, `move abs N`, `move rel N`, `stop` (*Commands*): `OK BUSY` while the move runs; a target beyond
//!   `limit.min`..`limit.max` or a malformed number is `RJ ... BADDATA`;
//! - `get pos | limit.min | limit.max | resolution | maxspeed | deviceid | system.serial` (*Settings*; `maxspeed`
//!   in Zaber's velocity units, microsteps/s x 1.6384);
//! - `warnings [clear]` (*Commands*): the count and the flags; `clear` then drops the latched ones;
//! - anything else is `RJ ... BADCOMMAND`; a line that is not a command, or whose checksum is wrong, gets no
//!   reply (this mock's reading: the manual's devices drop what they cannot frame).
//!
//! The reply's warning field is the highest-priority flag (*Warning Flags*); `WR` stands until the axis is homed.

use std::sync::Arc;

use metaplate_core::clock::Clock;
use metaplate_zaber_protocol::{
    Command, LineSplitter, Message, Reply, ReplyFlag, Status, WarningFlag, format_warning_list, reason,
};

use crate::axis::{ArmedFault, AxisState};
use crate::spec::{ChainSpec, DeviceSpec};

/// Zaber's velocity unit: `maxspeed` = microsteps/s x 1.6384 (*Manual, Physical Units*).
const VELOCITY_UNITS_PER_US_PER_S: f64 = 1.6384;

#[derive(Debug)]
struct DeviceState {
    spec: DeviceSpec,
    axes: Vec<AxisState>,
}

/// A chain of mock Zaber devices on one serial line. Time comes from the clock it is given (a `VirtualClock`
/// shared with the driver in process, the real clock on a pseudo-terminal), so a move takes distance / speed.
pub struct MockChain {
    spec: ChainSpec,
    devices: Vec<DeviceState>,
    clock: Arc<dyn Clock>,
    splitter: LineSplitter,
    output: Vec<u8>,
    link_up: bool,
    host_log: Vec<u8>,
}

impl std::fmt::Debug for MockChain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MockChain").field("spec", &self.spec).field("link_up", &self.link_up).finish()
    }
}

/// Why a command is rejected: the reason word of the `RJ` reply.
type Rejection = &'static str;

impl MockChain {
    /// The chain of `spec`, powered up (every axis unhomed, at its power-up position), timed by `clock`.
    pub fn new(spec: ChainSpec, clock: Arc<dyn Clock>) -> Self {
        let devices = Self::power_up(&spec);
        Self {
            spec,
            devices,
            clock,
            splitter: LineSplitter::new(),
            output: Vec::new(),
            link_up: true,
            host_log: Vec::new(),
        }
    }

    fn power_up(spec: &ChainSpec) -> Vec<DeviceState> {
        spec.devices
            .iter()
            .map(|d| DeviceState { spec: d.clone(), axes: d.axes.iter().cloned().map(AxisState::new).collect() })
            .collect()
    }

    /// Every device loses power and comes back: positions back at power-up, references lost (`WR`), flags gone.
    pub fn power_cycle(&mut self) {
        self.devices = Self::power_up(&self.spec);
        self.splitter.clear();
        self.output.clear();
    }

    /// Arms a fault on the next move of `device`'s `axis` (numbered from 1); `false` when there is no such axis.
    pub fn arm_fault(&mut self, device: u8, axis: u8, fault: ArmedFault) -> bool {
        match self.axis_mut(device, axis) {
            Some(state) => {
                state.arm(fault);
                true
            }
            None => false,
        }
    }

    /// The position of `device`'s `axis` now, microsteps (`None` when there is no such axis).
    pub fn position_us(&mut self, device: u8, axis: u8) -> Option<i64> {
        let now_s = self.clock.now_s();
        self.axis_mut(device, axis).map(|state| {
            state.update(now_s);
            state.pos_us()
        })
    }

    /// Everything the host has sent, as received.
    pub fn host_log(&self) -> &[u8] {
        &self.host_log
    }

    /// Drops the link (the cable is pulled): nothing is heard or answered until [`MockChain::reconnect`].
    pub fn disconnect(&mut self) {
        self.link_up = false;
    }

    /// Whether the link is up.
    pub fn is_connected(&self) -> bool {
        self.link_up
    }

    /// Brings the link back (the host reopened the port); bytes in flight are lost.
    pub fn reconnect(&mut self) {
        if !self.link_up {
            self.link_up = true;
            self.splitter.clear();
            self.output.clear();
        }
    }

    /// Receives host bytes and answers every complete command. Ignored while the link is down.
    pub fn receive(&mut self, bytes: &[u8]) {
        if !self.link_up {
            return;
        }
        self.host_log.extend_from_slice(bytes);
        self.splitter.push(bytes);
        while let Some(line) = self.splitter.next_line() {
            if let Ok(command) = line.and_then(|line| Command::parse(&line)) {
                self.answer(&command);
            }
        }
    }

    /// Takes the bytes queued for the host.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.output)
    }

    fn axis_mut(&mut self, device: u8, axis: u8) -> Option<&mut AxisState> {
        let index = usize::from(axis).checked_sub(1)?;
        self.devices.iter_mut().find(|d| d.spec.address == device)?.axes.get_mut(index)
    }

    fn answer(&mut self, command: &Command) {
        let now_s = self.clock.now_s();
        let checksum = self.spec.reply_checksums;
        for device in self.devices.iter_mut().filter(|d| command.device == 0 || command.device == d.spec.address) {
            for axis in &mut device.axes {
                axis.update(now_s);
            }
            let result = execute(device, command, now_s);
            let (flag, data) = match result {
                Ok(data) => (ReplyFlag::Ok, data),
                Err(reason) => (ReplyFlag::Rejected, reason.to_owned()),
            };
            let (status, warning) = summary(device, command.axis);
            let reply =
                Reply { device: device.spec.address, axis: command.axis, id: command.id, flag, status, warning, data };
            self.output.extend(Message::Reply(reply).encode(checksum));
        }
    }
}

/// The status and highest-priority flag of the axis addressed (of every axis for axis 0; a missing axis reports
/// the device's).
fn summary(device: &DeviceState, axis: u8) -> (Status, WarningFlag) {
    let chosen: Vec<&AxisState> = match usize::from(axis).checked_sub(1).and_then(|i| device.axes.get(i)) {
        Some(one) => vec![one],
        None => device.axes.iter().collect(),
    };
    let busy = chosen.iter().any(|a| a.is_busy());
    let warning = chosen.iter().flat_map(|a| a.flags()).max_by_key(WarningFlag::priority).unwrap_or(WarningFlag::NONE);
    (if busy { Status::Busy } else { Status::Idle }, warning)
}

/// Carries out `command` on `device`; the reply's data, or why it is rejected.
fn execute(device: &mut DeviceState, command: &Command, now_s: f64) -> Result<String, Rejection> {
    let axes: Vec<usize> = match command.axis {
        0 => (0..device.axes.len()).collect(),
        n if usize::from(n) <= device.axes.len() => vec![usize::from(n) - 1],
        _ => return Err(reason::BAD_AXIS),
    };
    let words: Vec<&str> = command.words().collect();
    match words.as_slice() {
        [] => Ok("0".into()),
        ["home"] => {
            for &i in &axes {
                device.axes.get_mut(i).ok_or(reason::BAD_AXIS)?.start_home(now_s);
            }
            Ok("0".into())
        }
        ["stop"] => {
            for &i in &axes {
                device.axes.get_mut(i).ok_or(reason::BAD_AXIS)?.stop();
            }
            Ok("0".into())
        }
        ["move", kind @ ("abs" | "rel"), value] => {
            let value: i64 = value.parse().map_err(|_| reason::BAD_DATA)?;
            // Check every axis first: a rejected command moves nothing.
            let mut targets = Vec::with_capacity(axes.len());
            for &i in &axes {
                let axis = device.axes.get(i).ok_or(reason::BAD_AXIS)?;
                let target = if *kind == "abs" { Some(value) } else { axis.pos_us().checked_add(value) };
                let target = target.filter(|t| (axis.spec.limit_min_us..=axis.spec.limit_max_us).contains(t));
                targets.push((i, target.ok_or(reason::BAD_DATA)?));
            }
            for (i, target) in targets {
                device.axes.get_mut(i).ok_or(reason::BAD_AXIS)?.start_move(target, now_s);
            }
            Ok("0".into())
        }
        ["get", setting] => get(device, &axes, setting),
        ["warnings"] | ["warnings", "clear"] => {
            let mut flags: Vec<WarningFlag> = Vec::new();
            for &i in &axes {
                for flag in device.axes.get(i).map(AxisState::flags).unwrap_or_default() {
                    if !flags.contains(&flag) {
                        flags.push(flag);
                    }
                }
            }
            if words.len() == 2 {
                for &i in &axes {
                    if let Some(axis) = device.axes.get_mut(i) {
                        axis.clear_warnings();
                    }
                }
            }
            Ok(format_warning_list(&flags))
        }
        _ => Err(reason::BAD_COMMAND),
    }
}

fn get(device: &DeviceState, axes: &[usize], setting: &str) -> Result<String, Rejection> {
    match setting {
        "deviceid" => return Ok(device.spec.device_id.to_string()),
        "system.serial" => return Ok(device.spec.serial.to_string()),
        _ => {}
    }
    let value = |axis: &AxisState| -> Result<String, Rejection> {
        Ok(match setting {
            "pos" => axis.pos_us().to_string(),
            "limit.min" => axis.spec.limit_min_us.to_string(),
            "limit.max" => axis.spec.limit_max_us.to_string(),
            "resolution" => axis.spec.resolution.to_string(),
            "maxspeed" => ((axis.spec.speed_us_per_s * VELOCITY_UNITS_PER_US_PER_S).round() as i64).to_string(),
            _ => return Err(reason::BAD_COMMAND),
        })
    };
    let values = axes
        .iter()
        .map(|&i| device.axes.get(i).ok_or(reason::BAD_AXIS).and_then(value))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(values.join(" "))
}

impl metaplate_mock_ldv::ServedDevice for MockChain {
    fn is_connected(&self) -> bool {
        MockChain::is_connected(self)
    }

    fn reconnect(&mut self) {
        MockChain::reconnect(self);
    }

    fn receive(&mut self, bytes: &[u8]) {
        MockChain::receive(self, bytes);
    }

    fn take_output(&mut self) -> Vec<u8> {
        MockChain::take_output(self)
    }
}

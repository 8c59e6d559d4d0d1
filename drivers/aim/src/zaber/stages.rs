//! The aimer: two Zaber axes that put the beam on a point of the plate.
//!
//! On open (and after a reconnect) each axis is asked for its `resolution`, `limit.min` and `limit.max`; its
//! latched warnings are cleared (`warnings clear`) and read again (`warnings`): a fault that stays is an error by
//! name, and an axis without its reference (`WR`, or `WH` on firmware 6) is homed. A point is a stage position in
//! mm (the origin plus or minus the plate coordinate, minus when the plate moves), then microsteps through the
//! product's microstep size scaled by the resolution the device reports; both axes move at once (`move abs`), and
//! the aimer polls (`get pos`) until both are idle, then reads the warnings and the positions back.

use std::sync::Arc;

use metaplate_core::aim::{Aim, AimError};
use metaplate_core::clock::Clock;
use metaplate_ldv::SerialLine;
use metaplate_zaber_protocol::{Reply, Status, WarningFlag, parse_warning_list};

use crate::zaber::config::{DEFAULT_RESOLUTION, MovingPart, StageAxisConfig, ZaberConfig};
use crate::zaber::error::ZaberError;
use crate::zaber::link::Link;

/// How often the aimer asks a moving axis whether it is idle, s.
const POLL_INTERVAL_S: f64 = 0.01;

/// How far a stopped axis may sit from its target, microsteps: a closed-loop stage settles within a few
/// microsteps of it (an open-loop one on it exactly).
const POSITION_TOLERANCE_US: i64 = 4;

/// One axis as opened: its configuration and what the device reported.
#[derive(Debug, Clone)]
struct OpenedAxis {
    name: &'static str,
    config: StageAxisConfig,
    /// One microstep at the device's resolution, m.
    microstep_m: f64,
    /// The allowed stage travel, microsteps: the device's limits narrowed by the configuration's.
    min_us: i64,
    max_us: i64,
}

impl OpenedAxis {
    /// The stage position, microsteps (unrounded), that puts the beam at `plate_m` along this axis.
    fn target_us(&self, plate_m: f64, moving: MovingPart) -> f64 {
        let sign = match moving {
            MovingPart::Head => 1.0,
            MovingPart::Plate => -1.0,
        };
        (self.config.origin_mm * 1e-3 + sign * plate_m) / self.microstep_m
    }

    fn describe_travel(&self) -> String {
        let mm = |us: i64| us as f64 * self.microstep_m * 1e3;
        format!("{:.3} to {:.3} mm", mm(self.min_us), mm(self.max_us))
    }
}

/// Zaber XY stages as an aimer ([`Aim`]), over any [`SerialLine`] (the real port, or a mock chain in a test).
pub struct ZaberStages<L> {
    link: Link<L>,
    config: ZaberConfig,
    clock: Arc<dyn Clock>,
    axes: Vec<OpenedAxis>,
    last_point_m: Option<(f64, f64)>,
}

impl<L> std::fmt::Debug for ZaberStages<L> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ZaberStages").field("config", &self.config).field("last_point_m", &self.last_point_m).finish()
    }
}

impl<L: SerialLine> ZaberStages<L> {
    /// Opens the stages on `line`: queries both axes, clears latched warnings, homes an axis that has no reference.
    /// Polls and timeouts run on `clock`.
    ///
    /// # Errors
    /// [`ZaberError::Config`] for a bad configuration; any error of the queries or the homing (a fault that
    /// stays after `warnings clear` is [`ZaberError::Flags`]).
    pub fn open(config: ZaberConfig, line: L, clock: Arc<dyn Clock>) -> Result<Self, ZaberError> {
        config.validate()?;
        let link = Link::new(line, config.reply_timeout_s);
        let mut stages = Self { link, config, clock, axes: Vec::new(), last_point_m: None };
        stages.initialise()?;
        Ok(stages)
    }

    fn initialise(&mut self) -> Result<(), ZaberError> {
        let mut axes = Vec::with_capacity(2);
        let mut to_home = Vec::new();
        for (index, (name, config)) in
            [("x", self.config.x.clone()), ("y", self.config.y.clone())].into_iter().enumerate()
        {
            let (device, axis) = (config.device, config.axis);
            let resolution = self.link.get_i64(device, axis, "get resolution")?;
            let limit_min_us = self.link.get_i64(device, axis, "get limit.min")?;
            let limit_max_us = self.link.get_i64(device, axis, "get limit.max")?;
            if resolution <= 0 || limit_min_us >= limit_max_us {
                let data = format!("resolution {resolution}, limits {limit_min_us}..{limit_max_us}");
                return Err(ZaberError::BadReply { device, axis, command: "get".into(), data });
            }
            let microstep_m = config.microstep_um * 1e-6 * f64::from(DEFAULT_RESOLUTION) / resolution as f64;
            let to_us = |mm: f64| (mm * 1e-3 / microstep_m).round() as i64;
            let min_us = config.travel_min_mm.map_or(limit_min_us, |mm| to_us(mm).max(limit_min_us));
            let max_us = config.travel_max_mm.map_or(limit_max_us, |mm| to_us(mm).min(limit_max_us));
            if min_us >= max_us {
                let reason = format!(
                    "leaves no travel within the device's limits ({limit_min_us} to {limit_max_us} microsteps)"
                );
                return Err(ZaberError::Config { key: format!("{name}.travel_min_mm"), reason });
            }
            self.link.request(device, axis, "warnings clear")?;
            let flags = self.warnings(device, axis)?;
            let faults: Vec<WarningFlag> = flags.iter().copied().filter(WarningFlag::is_fault).collect();
            if !faults.is_empty() {
                return Err(ZaberError::Flags { name, device, axis, flags: faults });
            }
            if flags.iter().any(WarningFlag::needs_homing) {
                to_home.push(index);
            }
            axes.push(OpenedAxis { name, config, microstep_m, min_us, max_us });
        }
        self.axes = axes;
        for &index in &to_home {
            let config = self.axis(index)?.config.clone();
            self.link.request(config.device, config.axis, "home")?;
        }
        let flags = self.wait_idle(&to_home)?;
        for (index, flags) in to_home.iter().zip(flags) {
            // After homing, the reference must be there (a tripped limit or a fault on the way is named too).
            let failing: Vec<WarningFlag> = flags
                .into_iter()
                .filter(|f| f.is_fault() || f.needs_homing() || *f == WarningFlag::UNEXPECTED_LIMIT)
                .collect();
            if !failing.is_empty() {
                let axis = self.axis(*index)?;
                let (name, device, axis) = (axis.name, axis.config.device, axis.config.axis);
                return Err(ZaberError::Flags { name, device, axis, flags: failing });
            }
        }
        Ok(())
    }

    fn axis(&self, index: usize) -> Result<&OpenedAxis, ZaberError> {
        self.axes
            .get(index)
            .ok_or_else(|| ZaberError::Config { key: "x, y".into(), reason: format!("no axis {index}") })
    }

    /// The flags `warnings` lists for one axis.
    fn warnings(&mut self, device: u8, axis: u8) -> Result<Vec<WarningFlag>, ZaberError> {
        let reply = self.link.request(device, axis, "warnings")?;
        parse_warning_list(&reply.data).ok_or(ZaberError::BadReply {
            device,
            axis,
            command: "warnings".into(),
            data: reply.data,
        })
    }

    /// Polls the axes `indices` until every one is idle; then returns each one's flags (`warnings`, asked only of
    /// an axis whose reply showed one).
    fn wait_idle(&mut self, indices: &[usize]) -> Result<Vec<Vec<WarningFlag>>, ZaberError> {
        let start_s = self.clock.now_s();
        let mut last: Vec<Option<Reply>> = vec![None; indices.len()];
        loop {
            for (slot, &index) in last.iter_mut().zip(indices) {
                if slot.as_ref().is_some_and(|r| r.status == Status::Idle) {
                    continue;
                }
                let (device, axis) = (self.axis(index)?.config.device, self.axis(index)?.config.axis);
                // `get pos` rather than the empty command: its reply carries the status, and it is unambiguous
                // with a message id.
                let reply = self.link.request(device, axis, "get pos")?;
                *slot = Some(reply);
            }
            if last.iter().all(|r| r.as_ref().is_some_and(|r| r.status == Status::Idle)) {
                break;
            }
            if self.clock.now_s() - start_s > self.config.move_timeout_s {
                let busy = indices.iter().zip(&last).find(|(_, r)| r.as_ref().is_none_or(|r| r.status == Status::Busy));
                let index = busy.map_or(0, |(i, _)| *i);
                let axis = self.axis(index)?;
                let (name, device, axis) = (axis.name, axis.config.device, axis.config.axis);
                return Err(ZaberError::MoveTimeout { name, device, axis, timeout_s: self.config.move_timeout_s });
            }
            self.clock.sleep_s(POLL_INTERVAL_S);
        }
        let mut flags = Vec::with_capacity(indices.len());
        for (reply, &index) in last.into_iter().zip(indices) {
            let shown = reply.map_or(WarningFlag::NONE, |r| r.warning);
            if shown.is_none() {
                flags.push(Vec::new());
            } else {
                let (device, axis) = (self.axis(index)?.config.device, self.axis(index)?.config.axis);
                flags.push(self.warnings(device, axis)?);
            }
        }
        Ok(flags)
    }

    /// The stage targets for a plate point, microsteps, each checked against its axis's travel.
    fn targets_us(&self, x_m: f64, y_m: f64) -> Result<[i64; 2], AimError> {
        if !x_m.is_finite() || !y_m.is_finite() {
            return Err(AimError::InvalidArgument { detail: format!("x_m = {x_m}, y_m = {y_m}: not finite") });
        }
        let mut targets = [0i64; 2];
        for ((target, axis), plate_m) in targets.iter_mut().zip(&self.axes).zip([x_m, y_m]) {
            let us = axis.target_us(plate_m, self.config.moving);
            if !(us >= axis.min_us as f64 - 0.5 && us <= axis.max_us as f64 + 0.5) {
                let stage_mm = us * axis.microstep_m * 1e3;
                let detail = format!(
                    "{} needs the stage at {stage_mm:.3} mm (device {} axis {}), outside its travel {}",
                    axis.name,
                    axis.config.device,
                    axis.config.axis,
                    axis.describe_travel()
                );
                return Err(AimError::Unreachable { x_m, y_m, detail });
            }
            *target = (us.round() as i64).clamp(axis.min_us, axis.max_us);
        }
        Ok(targets)
    }

    fn move_to(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        let targets = self.targets_us(x_m, y_m)?;
        for (axis, target) in self.axes.clone().iter().zip(targets) {
            self.link.request(axis.config.device, axis.config.axis, &format!("move abs {target}"))?;
        }
        let flags = self.wait_idle(&[0, 1])?;
        for ((axis, target), flags) in self.axes.clone().iter().zip(targets).zip(flags) {
            let (device, number) = (axis.config.device, axis.config.axis);
            // Faults, a tripped limit and an interrupted move each mean the axis is not where it was sent.
            let failing: Vec<WarningFlag> = flags
                .into_iter()
                .filter(|f| f.is_fault() || *f == WarningFlag::UNEXPECTED_LIMIT || *f == WarningFlag::INTERRUPTED)
                .collect();
            if !failing.is_empty() {
                return Err(ZaberError::Flags { name: axis.name, device, axis: number, flags: failing }.into());
            }
            let position_us = self.link.get_i64(device, number, "get pos")?;
            if (position_us - target).abs() > POSITION_TOLERANCE_US {
                return Err(ZaberError::OffTarget { name: axis.name, position_us, target_us: target }.into());
            }
        }
        Ok(())
    }

    /// Where the beam is on the plate, m, from the positions the axes report.
    ///
    /// # Errors
    /// Any error of the queries.
    pub fn position_m(&mut self) -> Result<(f64, f64), ZaberError> {
        let mut plate_m = [0.0; 2];
        for (value, axis) in plate_m.iter_mut().zip(self.axes.clone()) {
            let us = self.link.get_i64(axis.config.device, axis.config.axis, "get pos")?;
            let offset_m = us as f64 * axis.microstep_m - axis.config.origin_mm * 1e-3;
            *value = match self.config.moving {
                MovingPart::Head => offset_m,
                MovingPart::Plate => -offset_m,
            };
        }
        Ok((plate_m[0], plate_m[1]))
    }
}

impl<L: SerialLine> Aim for ZaberStages<L> {
    fn check_reachable(&self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        self.targets_us(x_m, y_m).map(|_| ())
    }

    fn aim_at(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        self.move_to(x_m, y_m)?;
        self.last_point_m = Some((x_m, y_m));
        Ok(())
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        self.link.reopen()?;
        // A power cycle loses the reference: initialise homes again where needed.
        self.initialise()?;
        if let Some((x_m, y_m)) = self.last_point_m {
            self.move_to(x_m, y_m)?;
        }
        Ok(())
    }

    /// For example "Zaber stages moving the head: x device 1 axis 1 (0.000 to 100.000 mm), y device 2 axis 1
    /// (0.000 to 100.000 mm)" (not the port: a pseudo-terminal's name changes from run to run).
    fn describe(&self) -> String {
        let moving = match self.config.moving {
            MovingPart::Head => "the head",
            MovingPart::Plate => "the plate",
        };
        let axes: Vec<String> = self
            .axes
            .iter()
            .map(|a| format!("{} device {} axis {} ({})", a.name, a.config.device, a.config.axis, a.describe_travel()))
            .collect();
        format!("Zaber stages moving {moving}: {}", axes.join(", "))
    }
}

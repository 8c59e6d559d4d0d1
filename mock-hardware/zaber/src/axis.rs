//! One axis in motion: where it is at a given time, homing, moves at constant speed, latched warning flags, and a
//! fault a test arms for the next move.

use metaplate_zaber_protocol::WarningFlag;

use crate::spec::AxisSpec;

/// A fault a test arms on an axis: the next move stops after `fraction` of its distance and latches `flag` (for
/// example `WL`, a limit sensor tripped mid-travel; `FS`, stalled; `FQ`, an encoder error).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmedFault {
    /// The flag the axis latches.
    pub flag: WarningFlag,
    /// How far through the move it stops, 0 to 1.
    pub fraction: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct Motion {
    from_us: f64,
    to_us: f64,
    start_s: f64,
    homing: bool,
    /// Latched when the move ends here (an armed fault).
    fault: Option<WarningFlag>,
}

/// An axis's state.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AxisState {
    pub(crate) spec: AxisSpec,
    pos_us: f64,
    homed: bool,
    motion: Option<Motion>,
    latched: Vec<WarningFlag>,
    armed: Option<ArmedFault>,
}

impl AxisState {
    pub(crate) fn new(spec: AxisSpec) -> Self {
        // A power-up position outside the travel would be a spec error; clamp rather than carry it.
        let pos_us = spec.power_up_pos_us.clamp(spec.limit_min_us, spec.limit_max_us) as f64;
        Self { spec, pos_us, homed: false, motion: None, latched: Vec::new(), armed: None }
    }

    /// Brings the motion up to `now_s`: a move that has arrived ends (homing sets the reference).
    pub(crate) fn update(&mut self, now_s: f64) {
        let Some(motion) = &self.motion else { return };
        let distance_us = motion.to_us - motion.from_us;
        let travelled_us = (self.spec.speed_us_per_s * (now_s - motion.start_s).max(0.0)).min(distance_us.abs());
        self.pos_us = motion.from_us + travelled_us.copysign(distance_us);
        if travelled_us >= distance_us.abs() {
            self.pos_us = motion.to_us;
            if let Some(flag) = motion.fault {
                self.latch(flag);
            } else if motion.homing {
                // Zaber's linear stages reset their position at the home sensor (`limit.min`).
                self.homed = true;
                self.pos_us = self.spec.limit_min_us as f64;
            }
            self.motion = None;
        }
    }

    fn latch(&mut self, flag: WarningFlag) {
        if !self.latched.contains(&flag) {
            self.latched.push(flag);
        }
    }

    pub(crate) fn is_busy(&self) -> bool {
        self.motion.is_some()
    }

    /// The position, microsteps (rounded, as `get pos` reports it).
    pub(crate) fn pos_us(&self) -> i64 {
        self.pos_us.round() as i64
    }

    /// Every current flag: latched ones, then `WR` until homed.
    pub(crate) fn flags(&self) -> Vec<WarningFlag> {
        let mut flags = self.latched.clone();
        if !self.homed {
            flags.push(WarningFlag::NO_REFERENCE);
        }
        flags
    }

    /// `warnings clear`: drops the latched flags (`WR` stays until the axis is homed).
    pub(crate) fn clear_warnings(&mut self) {
        self.latched.clear();
    }

    pub(crate) fn arm(&mut self, fault: ArmedFault) {
        self.armed = Some(fault);
    }

    /// Starts a move to `target_us` at `now_s`; a move cut short by another latches `NI`.
    pub(crate) fn start_move(&mut self, target_us: i64, now_s: f64) {
        self.start(target_us as f64, now_s, false);
    }

    /// Starts homing: a move toward the home sensor at `limit.min`.
    pub(crate) fn start_home(&mut self, now_s: f64) {
        self.start(self.spec.limit_min_us as f64, now_s, true);
    }

    fn start(&mut self, to_us: f64, now_s: f64, homing: bool) {
        if self.motion.is_some() {
            self.latch(WarningFlag::INTERRUPTED);
        }
        let from_us = self.pos_us;
        let (to_us, fault) = match self.armed.take() {
            Some(armed) => (from_us + (to_us - from_us) * armed.fraction.clamp(0.0, 1.0), Some(armed.flag)),
            None => (to_us, None),
        };
        self.motion = Some(Motion { from_us, to_us, start_s: now_s, homing, fault });
        // A zero-length move ends at once.
        self.update(now_s);
    }

    /// `stop`: the axis stops where it is (the mock decelerates instantly).
    pub(crate) fn stop(&mut self) {
        self.motion = None;
    }
}

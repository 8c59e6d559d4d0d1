//! The controller's state machine: one command in, one reply out, per the protocol specification.

use metaplate_core::scene::LdvSpec;
use metaplate_ldv_protocol::{
    CalibrationState, Command, ErrorCode, ErrorText, Identity, IdentityField, LaserState, LdvProtocolError,
    MirrorAngle, MirrorAngles, PlateCoord, PlatePoint, Reply, SignalLevel, TrackingFilter, VelocityRange,
};

use crate::speckle::{DROPOUT_LEVEL_PERCENT, SpeckleModel};

/// Distance from the scanner's mirrors to the plate, m: the calibration maps a plate point (x, y) to mirror angles
/// atan(x / d), atan(y / d) (the specification's timing example assumes 1 m).
pub const STANDOFF_M: f64 = 1.0;

/// The mock controller: beam, velocity range, tracking filter, laser, calibration, a latched fault, and the signal
/// level from the scene's speckle model. Power-on state per the specification: laser off, 25 mm/s/V, tracking off,
/// mirrors at 0, 0.
#[derive(Debug, Clone)]
pub struct MockController {
    identity: Identity,
    speckle: SpeckleModel,
    calibrated: bool,
    laser: LaserState,
    range: VelocityRange,
    tracking: TrackingFilter,
    angles: MirrorAngles,
    position: PlatePoint,
    fault_latched: bool,
    dropout_queries_left: u32,
}

impl MockController {
    /// A calibrated controller at power-on, identifying as `Ometron,8330,<serial>,2.14`, with the speckle of
    /// `spec` under `seed`.
    ///
    /// # Errors
    /// [`LdvProtocolError::InvalidText`] when `serial` is not 1 to 24 printable characters without commas.
    pub fn new(spec: &LdvSpec, seed: u64, serial: &str) -> Result<Self, LdvProtocolError> {
        let identity = Identity {
            vendor: IdentityField::new("Ometron")?,
            model: IdentityField::new("8330")?,
            serial: IdentityField::new(serial)?,
            firmware: IdentityField::new("2.14")?,
        };
        Ok(Self {
            identity,
            speckle: SpeckleModel::new(spec, seed),
            calibrated: true,
            laser: LaserState::Off,
            range: VelocityRange::MmPerS25,
            tracking: TrackingFilter::Off,
            angles: MirrorAngles::default(),
            position: PlatePoint::default(),
            fault_latched: false,
            dropout_queries_left: 0,
        })
    }

    /// Power cycle: everything back to power-on defaults, the laser off; identity and speckle kept.
    pub fn power_cycle(&mut self) {
        self.reset();
        self.laser = LaserState::Off;
        self.fault_latched = false;
        self.dropout_queries_left = 0;
    }

    /// Whether a plate calibration is in force (default: yes).
    pub fn set_calibrated(&mut self, calibrated: bool) {
        self.calibrated = calibrated;
    }

    /// Latches a hardware fault (beam and laser commands fail with `ERR 8` until `*CLS` or `*RST`).
    pub fn latch_fault(&mut self) {
        self.fault_latched = true;
    }

    /// Makes the next `queries` `SIG?` queries report a dropout ([`DROPOUT_LEVEL_PERCENT`]), until the beam moves:
    /// a dropout is the speckle at one spot losing lock, and a new spot is tracked afresh (so a dropout at the end
    /// of one unit does not make the next unit's aim nudge, which a resumed run would not do).
    pub fn start_dropout(&mut self, queries: u32) {
        self.dropout_queries_left = queries;
    }

    /// The laser state.
    pub fn laser(&self) -> LaserState {
        self.laser
    }

    /// The velocity range.
    pub fn velocity_range(&self) -> VelocityRange {
        self.range
    }

    /// The tracking filter.
    pub fn tracking(&self) -> TrackingFilter {
        self.tracking
    }

    /// The beam position in the plate frame.
    pub fn position(&self) -> PlatePoint {
        self.position
    }

    /// The mirror angles.
    pub fn angles(&self) -> MirrorAngles {
        self.angles
    }

    /// The reply to one line: a command, or the error it failed to decode with.
    pub fn answer_line(&mut self, line: Result<Command, LdvProtocolError>) -> Reply {
        match line {
            Ok(command) => self.answer(&command),
            Err(error) => Reply::from_error(&error),
        }
    }

    /// The reply to `command`.
    pub fn answer(&mut self, command: &Command) -> Reply {
        match self.execute(command) {
            Ok(reply) => reply,
            Err((code, text)) => Reply::Error { code, text: ErrorText::lossy(&text) },
        }
    }

    fn execute(&mut self, command: &Command) -> Result<Reply, (ErrorCode, String)> {
        let needs_healthy = matches!(
            command,
            Command::MoveTo(_) | Command::MoveToAngles(_) | Command::SetLaser(_) | Command::QuerySignal
        );
        if needs_healthy && self.fault_latched {
            return Err((ErrorCode::HardwareFault, "mirror drive fault latched; send *CLS".into()));
        }
        let reply = match *command {
            Command::Identify => Reply::Identity(self.identity.clone()),
            Command::Reset => {
                self.reset();
                Reply::Ok
            }
            Command::ClearErrors => {
                self.fault_latched = false;
                Reply::Ok
            }
            Command::MoveTo(point) => {
                self.require_calibration()?;
                self.angles = angles_of(point).map_err(|e| (e.error_code(), e.to_string()))?;
                self.position = point;
                self.dropout_queries_left = 0;
                Reply::Ok
            }
            Command::MoveToAngles(angles) => {
                self.angles = angles;
                self.dropout_queries_left = 0;
                // Beyond the plate frame's 0.5 m the position is clamped; POS? is only meaningful on the plate.
                self.position = point_of(angles);
                Reply::Ok
            }
            Command::QueryPosition => {
                self.require_calibration()?;
                Reply::Position(self.position)
            }
            Command::QueryAngles => Reply::Angles(self.angles),
            Command::QuerySignal => Reply::Signal(self.signal()?),
            Command::SetVelocityRange(range) => {
                self.range = range;
                Reply::Ok
            }
            Command::QueryVelocityRange => Reply::VelocityRange(self.range),
            Command::SetTrackingFilter(filter) => {
                self.tracking = filter;
                Reply::Ok
            }
            Command::QueryTrackingFilter => Reply::TrackingFilter(self.tracking),
            Command::SetLaser(state) => {
                self.laser = state;
                Reply::Ok
            }
            Command::QueryLaser => Reply::Laser(self.laser),
            Command::QueryCalibration => Reply::Calibration(if self.calibrated {
                CalibrationState::Calibrated
            } else {
                CalibrationState::NotCalibrated
            }),
            Command::Sync(token) => Reply::Sync(token),
        };
        Ok(reply)
    }

    fn reset(&mut self) {
        self.range = VelocityRange::MmPerS25;
        self.tracking = TrackingFilter::Off;
        self.angles = MirrorAngles::default();
        self.position = PlatePoint::default();
        self.fault_latched = false;
    }

    fn require_calibration(&self) -> Result<(), (ErrorCode, String)> {
        if self.calibrated { Ok(()) } else { Err((ErrorCode::NotCalibrated, "no plate calibration in force".into())) }
    }

    fn signal(&mut self) -> Result<SignalLevel, (ErrorCode, String)> {
        if self.laser == LaserState::Off {
            return Err((ErrorCode::LaserOff, "laser is off".into()));
        }
        let percent = if self.dropout_queries_left > 0 {
            self.dropout_queries_left -= 1;
            DROPOUT_LEVEL_PERCENT
        } else {
            self.speckle.level_percent(self.position.x.um(), self.position.y.um())
        };
        SignalLevel::from_percent(percent).map_err(|e| (e.error_code(), e.to_string()))
    }
}

/// Mirror angles that aim the beam at `point`: atan(x / d) per axis, rounded to 0.001 degree.
fn angles_of(point: PlatePoint) -> Result<MirrorAngles, LdvProtocolError> {
    let angle = |c: PlateCoord| MirrorAngle::from_deg((c.m() / STANDOFF_M).atan().to_degrees());
    Ok(MirrorAngles { x: angle(point.x)?, y: angle(point.y)? })
}

/// The plate point the mirrors aim at: d tan(angle) per axis, clamped to the plate frame's field.
fn point_of(angles: MirrorAngles) -> PlatePoint {
    let coord = |a: MirrorAngle| {
        let x_m = (STANDOFF_M * a.deg().to_radians().tan()).clamp(-0.5, 0.5);
        PlateCoord::from_m(x_m).unwrap_or_default()
    };
    PlatePoint { x: coord(angles.x), y: coord(angles.y) }
}

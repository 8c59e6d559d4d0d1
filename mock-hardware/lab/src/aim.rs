//! The lab's own aimer: the lab knows where the beam lands, so aiming is in-process, with no link to fail.

use std::sync::{Arc, Mutex};

use metaplate_core::aim::{Aim, AimError, check_within};
use metaplate_core::clock::VirtualClock;
use metaplate_mock_ldv::MockDevice;

/// Half the width of the square the lab's beam can reach, m: the plate frame's +/- 0.5 m (the extent of the
/// beam positions the earlier, invented controller protocol took).
pub const REACH_HALF_WIDTH_M: f64 = 0.5;

/// Settling time of one move, s: small mirrors settle in about 2 ms plus 0.5 ms per degree, taken at a 5 mm grid
/// step seen from 1 m (a galvo's typical small-step figure).
pub const SETTLE_S: f64 = 0.0022;

/// Puts the beam on a point of the plate by telling the vibrometer's mock controller where it lands (the signal
/// level and speckle follow the spot), after the move's settling time on the lab's clock.
#[derive(Debug)]
pub struct LabAimer {
    ldv: Arc<Mutex<MockDevice>>,
    clock: Arc<VirtualClock>,
    last_m: Option<(f64, f64)>,
}

impl LabAimer {
    /// The aimer of the lab whose vibrometer is `ldv`, on `clock`.
    pub fn new(ldv: Arc<Mutex<MockDevice>>, clock: Arc<VirtualClock>) -> Self {
        Self { ldv, clock, last_m: None }
    }
}

impl Aim for LabAimer {
    fn check_reachable(&self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        check_within(x_m, y_m, REACH_HALF_WIDTH_M)
    }

    fn aim_at(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        self.check_reachable(x_m, y_m)?;
        let mut ldv =
            self.ldv.lock().map_err(|_| AimError::Device { message: "the lab's LDV lock is poisoned".into() })?;
        ldv.controller_mut().set_beam(x_m, y_m);
        self.clock.advance(SETTLE_S);
        self.last_m = Some((x_m, y_m));
        Ok(())
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        match self.last_m {
            Some((x_m, y_m)) => self.aim_at(x_m, y_m),
            None => Ok(()),
        }
    }

    fn describe(&self) -> String {
        "the mock lab's beam (in-process, no mirrors or stages)".to_owned()
    }
}

//! The galvo aimer: plate coordinates through the fit to the mirrors' voltages, then the settling wait.

use std::sync::Arc;

use metaplate_core::aim::{Aim, AimError, MirrorOutputs};
use metaplate_core::clock::Clock;

use super::GalvoFit;

/// How the aimer drives its mirrors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GalvoSettings {
    /// How long each move waits after the outputs hold the new voltages, s (the mirrors' step response: a few
    /// ms for small scanning mirrors). At least 0.
    pub settle_s: f64,
}

/// Aims the beam with a pair of galvanometer mirrors: [`GalvoFit`] maps a plate point to two voltages, the
/// [`MirrorOutputs`] hold them, the clock waits the settling time.
pub struct GalvoAimer {
    fit: GalvoFit,
    outputs: Box<dyn MirrorOutputs>,
    clock: Arc<dyn Clock>,
    settings: GalvoSettings,
    last_v: Option<(f64, f64)>,
}

impl std::fmt::Debug for GalvoAimer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GalvoAimer")
            .field("model", &self.fit.model())
            .field("outputs", &self.outputs.describe())
            .field("settings", &self.settings)
            .field("last_v", &self.last_v)
            .finish_non_exhaustive()
    }
}

impl GalvoAimer {
    /// The aimer of `fit` over `outputs`, waiting on `clock`.
    ///
    /// # Errors
    /// `InvalidArgument` for a negative or non-finite settling time.
    pub fn new(
        fit: GalvoFit,
        outputs: Box<dyn MirrorOutputs>,
        clock: Arc<dyn Clock>,
        settings: GalvoSettings,
    ) -> Result<GalvoAimer, AimError> {
        if !(settings.settle_s.is_finite() && settings.settle_s >= 0.0) {
            return Err(AimError::InvalidArgument { detail: format!("settle_s = {}: not >= 0", settings.settle_s) });
        }
        Ok(GalvoAimer { fit, outputs, clock, settings, last_v: None })
    }

    /// The fit in use.
    pub fn fit(&self) -> &GalvoFit {
        &self.fit
    }

    /// The voltages for (`x_m`, `y_m`), V, checked against the outputs' range.
    ///
    /// # Errors
    /// `InvalidArgument` for a non-finite point; `Unreachable` when the map has no image there or it needs more
    /// than the outputs' range.
    pub fn volts_for(&self, x_m: f64, y_m: f64) -> Result<(f64, f64), AimError> {
        if !x_m.is_finite() || !y_m.is_finite() {
            return Err(AimError::InvalidArgument { detail: format!("x_m = {x_m}, y_m = {y_m}: not finite") });
        }
        let limit_v = self.outputs.limit_v();
        let (x_v, y_v) = self.fit.volts_at(x_m, y_m).ok_or_else(|| AimError::Unreachable {
            x_m,
            y_m,
            detail: "beyond the galvo fit's horizon (the mirrors cannot put the beam there)".into(),
        })?;
        if x_v.abs() > limit_v || y_v.abs() > limit_v {
            return Err(AimError::Unreachable {
                x_m,
                y_m,
                detail: format!("needs ({x_v:.4} V, {y_v:.4} V) on the mirrors, beyond their +/- {limit_v} V outputs"),
            });
        }
        Ok((x_v, y_v))
    }
}

impl Aim for GalvoAimer {
    fn check_reachable(&self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        self.volts_for(x_m, y_m).map(|_| ())
    }

    fn aim_at(&mut self, x_m: f64, y_m: f64) -> Result<(), AimError> {
        let (x_v, y_v) = self.volts_for(x_m, y_m)?;
        self.outputs.set_volts(x_v, y_v)?;
        self.last_v = Some((x_v, y_v));
        self.clock.sleep_s(self.settings.settle_s);
        Ok(())
    }

    fn reconnect(&mut self) -> Result<(), AimError> {
        self.outputs.reconnect()?;
        if let Some((x_v, y_v)) = self.last_v {
            self.outputs.set_volts(x_v, y_v)?;
            self.clock.sleep_s(self.settings.settle_s);
        }
        Ok(())
    }

    /// The fit (model, points, residual) and the outputs that drive the mirrors.
    fn describe(&self) -> String {
        let r = self.fit.residual();
        format!(
            "galvo mirrors ({} fit of {} points, residual rms {:.3} mm) on {}",
            self.fit.model().name(),
            self.fit.points().len(),
            r.rms_mm,
            self.outputs.describe()
        )
    }
}

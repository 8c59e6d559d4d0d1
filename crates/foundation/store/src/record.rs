//! One row of a dataset: an impulse response and what it belongs to.

use crate::error::StoreError;
use crate::manifest::GridSpec;
use crate::schema::{RowKind, Status};

/// Everything about one impulse response except its samples: which point and actuator, where, and how well it was
/// measured. One row of a batch file, without the `ir` column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IrMeta {
    /// Grid point index, `iy * grid.nx + ix`.
    pub point_index: u32,
    /// Grid column, `0..grid.nx`.
    pub ix: u32,
    /// Grid row, `0..grid.ny`.
    pub iy: u32,
    /// x of the point, m (finite; the commanded or measured position, which may differ from the nominal grid).
    pub x_m: f64,
    /// y of the point, m (finite).
    pub y_m: f64,
    /// Actuator number, 0-based.
    pub actuator: u16,
    /// Sample rate of the impulse response, Hz (finite, positive; the same for the whole dataset).
    pub sample_rate_hz: f64,
    /// Signal-to-noise ratio, dB (finite when present); `None` when not measured (simulation).
    pub snr_db: Option<f64>,
    /// Quality flag; `None` when not assessed.
    pub status: Option<Status>,
    /// Re-measurements of this point; `None` when not tracked.
    pub retries: Option<u32>,
    /// Measurement time, µs since the Unix epoch (UTC); `None` when not measured (simulation).
    pub measured_at_unix_us: Option<i64>,
    /// What a calibration row holds; `None` for the rows of a scan or a simulation.
    pub kind: Option<RowKind>,
    /// The response's estimated error against the truth over 80..600 Hz, dB (finite when present), from the spread
    /// of its repetitions or shots; `None` where nothing estimates it.
    pub estimated_error_db: Option<f64>,
}

/// One impulse response with its metadata: what a recipe commits and the writer stores as one row.
#[derive(Debug, Clone, PartialEq)]
pub struct IrRecord {
    /// Which point and actuator, and how well measured.
    pub meta: IrMeta,
    /// The impulse response, sampled at `meta.sample_rate_hz`: at least one sample, all finite, and the same length
    /// for the whole dataset. Stored as f32 (about 7 significant digits, far below any measurement's noise floor).
    pub ir: Vec<f32>,
}

impl IrMeta {
    /// Metadata of grid point `(ix, iy)` and `actuator` at its nominal grid position, with no quality information
    /// (what a simulation produces).
    ///
    /// # Errors
    /// [`StoreError::InvalidRecord`] if `(ix, iy)` lies outside `grid` or `sample_rate_hz` is not finite and positive.
    pub fn at_grid(grid: &GridSpec, ix: u32, iy: u32, actuator: u16, sample_rate_hz: f64) -> Result<Self, StoreError> {
        let invalid = |reason: String| StoreError::InvalidRecord { location: "IrMeta::at_grid".into(), reason };
        let point_index =
            grid_point_index(grid, ix, iy).ok_or_else(|| invalid(format!("point ({ix}, {iy}) is outside the grid")))?;
        let (x_m, y_m) = grid.position_m(point_index as usize);
        let meta = IrMeta {
            point_index,
            ix,
            iy,
            x_m,
            y_m,
            actuator,
            sample_rate_hz,
            snr_db: None,
            status: None,
            retries: None,
            measured_at_unix_us: None,
            kind: None,
            estimated_error_db: None,
        };
        meta.check(grid).map_err(invalid)?;
        Ok(meta)
    }

    /// The dataset key of this row: `(point_index, actuator)`.
    pub fn key(&self) -> (u32, u16) {
        (self.point_index, self.actuator)
    }

    /// Checks this row against `grid` and the valid ranges on the fields; the reason on failure.
    pub(crate) fn check(&self, grid: &GridSpec) -> Result<(), String> {
        match grid_point_index(grid, self.ix, self.iy) {
            None => {
                return Err(format!(
                    "grid indices ({}, {}) lie outside the {} x {} grid",
                    self.ix, self.iy, grid.nx, grid.ny
                ));
            }
            Some(expected) if expected != self.point_index => {
                return Err(format!(
                    "point_index {} does not match (ix, iy) = ({}, {}), which is point {expected}",
                    self.point_index, self.ix, self.iy
                ));
            }
            Some(_) => {}
        }
        for (name, v) in [("x_m", self.x_m), ("y_m", self.y_m)] {
            if !v.is_finite() {
                return Err(format!("{name} must be finite, got {v}"));
            }
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(format!("sample_rate_hz must be finite and positive, got {}", self.sample_rate_hz));
        }
        if let Some(snr_db) = self.snr_db
            && !snr_db.is_finite()
        {
            return Err(format!("snr_db must be finite when present, got {snr_db}"));
        }
        if let Some(error_db) = self.estimated_error_db
            && !error_db.is_finite()
        {
            return Err(format!("estimated_error_db must be finite when present, got {error_db}"));
        }
        Ok(())
    }
}

/// Index `iy * nx + ix` of point `(ix, iy)`, or `None` if the point lies outside `grid` (a valid grid has at most
/// `metaplate_core::grid::MAX_GRID_POINTS` points, so the index fits a u32).
fn grid_point_index(grid: &GridSpec, ix: u32, iy: u32) -> Option<u32> {
    let (ix, iy) = (ix as usize, iy as usize);
    if ix < grid.nx && iy < grid.ny { u32::try_from(grid.index(ix, iy)).ok() } else { None }
}

/// Checks an impulse response: at least one sample, all finite; the reason on failure.
pub(crate) fn check_ir(ir: &[f32]) -> Result<(), String> {
    if ir.is_empty() {
        return Err("ir is empty".into());
    }
    match ir.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(format!("ir holds a non-finite value ({}) at sample {index}", ir[index])),
        None => Ok(()),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    const GRID: GridSpec = GridSpec { nx: 4, ny: 3, spacing_m: 0.005, origin_x_m: 0.0, origin_y_m: 0.0 };

    #[test]
    fn at_grid_fills_index_and_position_and_checks_bounds() {
        let meta = IrMeta::at_grid(&GRID, 3, 2, 7, 24_000.0).unwrap();
        assert_eq!(meta.key(), (2 * 4 + 3, 7));
        assert_eq!((meta.x_m, meta.y_m), (3.0 * 0.005, 2.0 * 0.005));
        assert!(meta.check(&GRID).is_ok());
        assert!(matches!(IrMeta::at_grid(&GRID, 4, 0, 0, 24_000.0), Err(StoreError::InvalidRecord { .. })));
        assert!(matches!(IrMeta::at_grid(&GRID, 0, 3, 0, 24_000.0), Err(StoreError::InvalidRecord { .. })));
        for rate in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(IrMeta::at_grid(&GRID, 0, 0, 0, rate).is_err(), "rate {rate}");
        }
    }

    #[test]
    fn check_refuses_each_bad_field() {
        let good = IrMeta::at_grid(&GRID, 1, 1, 0, 24_000.0).unwrap();
        let bad = [
            IrMeta { point_index: 0, ..good },
            IrMeta { x_m: f64::NAN, ..good },
            IrMeta { y_m: f64::NEG_INFINITY, ..good },
            IrMeta { snr_db: Some(f64::INFINITY), ..good },
            IrMeta { estimated_error_db: Some(f64::NAN), ..good },
            IrMeta { sample_rate_hz: 0.0, ..good },
        ];
        for meta in bad {
            assert!(meta.check(&GRID).is_err(), "{meta:?}");
        }
        // Extremes that are in range.
        let edge = IrMeta {
            snr_db: Some(-300.0),
            estimated_error_db: Some(-400.0),
            sample_rate_hz: f64::MIN_POSITIVE,
            x_m: -1e300,
            ..good
        };
        assert!(edge.check(&GRID).is_ok());
    }

    #[test]
    fn check_ir_refuses_empty_and_non_finite() {
        assert!(check_ir(&[0.0]).is_ok());
        assert!(check_ir(&[f32::MAX, f32::MIN, f32::MIN_POSITIVE, -0.0]).is_ok());
        assert!(check_ir(&[]).is_err());
        let err = check_ir(&[0.0, 1.0, f32::NAN]).unwrap_err();
        assert!(err.contains("sample 2"), "{err}");
        assert!(check_ir(&[f32::INFINITY]).is_err());
    }
}

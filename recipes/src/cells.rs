//! Which points a scan plans, read from its configuration, and the per-point reduction of its rows that the status
//! and SNR maps draw (the report's page and the monitor's): one home for both readers.

use metaplate_core::grid::GridSpec;
use metaplate_figures::CellStatus;
use metaplate_store::{IrMeta, Status};
use serde_json::{Map, Value};

/// Fixed SNR colour scale of the maps, dB: 0 is no signal; the scan's default gate (20 dB) sits a fifth of the way
/// up, and the mock lab's taped plates (60 to 80 dB) stay below the top.
pub const SNR_SCALE_DB: (f64, f64) = (0.0, 100.0);

/// The grid points a scan plans to measure: its configuration's `points` (grid indices, as a scan writes them in
/// its manifest), or none when the configuration has no such list (a calibration).
pub fn planned_points(config: &Map<String, Value>) -> Vec<u32> {
    config
        .get("points")
        .and_then(Value::as_array)
        .map(|points| points.iter().filter_map(Value::as_u64).filter_map(|p| u32::try_from(p).ok()).collect())
        .unwrap_or_default()
}

/// A committed row's status as a map cell: valid and ground-truth rows (and rows without a status) are measured.
pub fn cell_status(status: Option<Status>) -> CellStatus {
    match status {
        Some(Status::ReMeasured) => CellStatus::ReMeasured,
        Some(Status::Overrange) => CellStatus::Overrange,
        Some(Status::Dropout) => CellStatus::Dropout,
        Some(Status::Failed) => CellStatus::Failed,
        Some(Status::Valid | Status::GroundTruth) | None => CellStatus::Measured,
    }
}

/// The worst status of `rows` as a map cell (later in [`CellStatus::ALL`]'s legend order is worse, up to failed), or
/// `None` for no rows.
pub fn worst_status<'a>(rows: impl IntoIterator<Item = &'a IrMeta>) -> Option<CellStatus> {
    rows.into_iter().map(|m| cell_status(m.status)).max_by_key(|s| rank(*s))
}

/// Position of `status` in the legend's order: the larger, the worse.
pub fn rank(status: CellStatus) -> usize {
    CellStatus::ALL.iter().position(|x| *x == status).unwrap_or(0)
}

/// Per grid point of `grid` (indexed `iy * nx + ix`): the worst status over its actuators (not planned when
/// `planned` does not hold it, pending when planned and not committed), and its lowest finite SNR, dB (`None` when
/// no row of the point has one). `planned` holds grid indices (see [`planned_points`]); rows outside the grid are
/// ignored.
pub fn grid_cells<'a>(
    grid: &GridSpec,
    planned: &[u32],
    rows: impl IntoIterator<Item = &'a IrMeta>,
) -> (Vec<CellStatus>, Vec<Option<f64>>) {
    let mut states = vec![CellStatus::NotPlanned; grid.len()];
    for &p in planned {
        if let Some(s) = states.get_mut(p as usize) {
            *s = CellStatus::Pending;
        }
    }
    let mut snr: Vec<Option<f64>> = vec![None; grid.len()];
    let mut seen = vec![false; grid.len()];
    for meta in rows {
        let i = meta.point_index as usize;
        let (Some(state), Some(cell_snr), Some(seen)) = (states.get_mut(i), snr.get_mut(i), seen.get_mut(i)) else {
            continue;
        };
        let row_state = cell_status(meta.status);
        // Worst over the actuators: later in the legend's order is worse, up to failed.
        if !*seen || rank(row_state) > rank(*state) {
            *state = row_state;
        }
        *seen = true;
        if let Some(v) = meta.snr_db.filter(|v| v.is_finite()) {
            *cell_snr = Some(cell_snr.map_or(v, |c: f64| c.min(v)));
        }
    }
    (states, snr)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests may unwrap: a failure is the test failing.
mod tests {
    use super::*;

    #[test]
    fn a_point_takes_its_worst_status_and_lowest_snr_and_unplanned_points_stay_unplanned() {
        let grid = GridSpec::centred(3, 2, 0.005);
        let row = |point: u32, actuator: u16, status: Status, snr: f64| {
            let mut meta = IrMeta::at_grid(&grid, point % 3, point / 3, actuator, 24_000.0).unwrap();
            meta.status = Some(status);
            meta.snr_db = Some(snr);
            meta
        };
        let rows =
            [row(0, 0, Status::Valid, 60.0), row(0, 1, Status::Dropout, 30.0), row(1, 0, Status::Valid, f64::NAN)];
        let (states, snr) = grid_cells(&grid, &[0, 1, 2], &rows);
        assert_eq!(
            states,
            [
                CellStatus::Dropout,
                CellStatus::Measured,
                CellStatus::Pending,
                CellStatus::NotPlanned,
                CellStatus::NotPlanned,
                CellStatus::NotPlanned
            ]
        );
        assert_eq!(snr, [Some(30.0), None, None, None, None, None]);
        assert_eq!(worst_status(&rows), Some(CellStatus::Dropout));
        assert_eq!(worst_status(&[]), None);
    }

    #[test]
    fn the_planned_points_are_the_configurations_points_and_a_calibration_plans_none() {
        let scan = serde_json::json!({"points": [4, 0, 7], "gates": {}});
        assert_eq!(planned_points(scan.as_object().unwrap()), [4, 0, 7]);
        let calibration = serde_json::json!({"actuator_sites_m": [[0.0, 0.0]]});
        assert_eq!(planned_points(calibration.as_object().unwrap()), Vec::<u32>::new());
        let odd = serde_json::json!({"points": [1, -1, "2", 5_000_000_000u64, 3]});
        assert_eq!(planned_points(odd.as_object().unwrap()), [1, 3], "only grid indices count");
    }
}

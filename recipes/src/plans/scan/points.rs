//! The scan plan's state: which actuators each point still needs, what a processed result means for the point
//! (settled, deferred to the end for a re-measure, or committed with a status), and the rows to commit. Pure data:
//! no instrument and no dataset, so it is tested with synthetic outcomes.

use std::collections::{BTreeMap, VecDeque};

use metaplate_core::grid::GridSpec;
use metaplate_dsp::excitation::AdaptiveTarget;
use metaplate_store::{IrMeta, IrRecord, Status};

use crate::engine::acquire::AcquisitionProblem;
use crate::engine::aim::Aimed;
use crate::error::RecipeError;

/// Why a row is not (yet) good.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Problem {
    Clipped,
    Gap,
    Processing(String),
    LowSnr(f64),
    Drift(f64),
    /// An adaptive protocol's target (SNR or estimated error), not reached within its rounds (final: not
    /// deferred); `value_db` is where the row ended.
    Unreached {
        target: AdaptiveTarget,
        value_db: Option<f64>,
        rounds: usize,
    },
}

impl Problem {
    /// The status a row ends with when this is its last problem.
    pub(crate) fn status(&self) -> Status {
        match self {
            Problem::Clipped => Status::Overrange,
            Problem::Gap | Problem::Processing(_) => Status::Dropout,
            Problem::LowSnr(_) | Problem::Drift(_) | Problem::Unreached { .. } => Status::Failed,
        }
    }

    /// Whether a re-measure is pointless (the problem already is the outcome of a bounded effort).
    pub(crate) fn is_final(&self) -> bool {
        matches!(self, Problem::Unreached { .. })
    }

    pub(crate) fn describe(&self) -> String {
        match self {
            Problem::Clipped => "clipped".into(),
            Problem::Gap => "gap or underrun in the recording".into(),
            Problem::Processing(e) => format!("processing failed: {e}"),
            Problem::LowSnr(snr) => format!("SNR {snr:.1} dB below the limit"),
            Problem::Drift(ppm) => format!("clock drift {ppm:.0} ppm beyond the limit"),
            Problem::Unreached { target, value_db, rounds } => format!(
                "{} {} short of the adaptive target {:.1} dB after {rounds} rounds",
                target.quantity(),
                value_db.map_or("unknown".to_string(), |v| format!("{v:.1} dB")),
                target.db()
            ),
        }
    }
}

/// One actuator's row at a point, across visits.
#[derive(Debug, Clone)]
pub(crate) struct Row {
    /// Acquisitions made for the row over every visit (`retries` is one less).
    pub acquisitions: u32,
    /// Best result so far, and where.
    pub result: Option<(Measured, Aimed)>,
    /// The last visit's problem, if any.
    pub problem: Option<Problem>,
    /// Settled: nothing more to measure for it.
    pub done: bool,
}

/// A point being measured.
#[derive(Debug, Clone)]
struct PointState {
    visit: u32,
    rows: Vec<Row>,
}

impl From<AcquisitionProblem> for Problem {
    fn from(p: AcquisitionProblem) -> Self {
        match p {
            AcquisitionProblem::Gap => Problem::Gap,
            AcquisitionProblem::Clipped => Problem::Clipped,
        }
    }
}

/// A response as processed: what a row commits when it is the best of its visits.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Measured {
    /// The impulse response, m/s per full scale.
    pub ir: Vec<f64>,
    /// SNR from the spread of repetitions, dB.
    pub snr_db: Option<f64>,
    /// The response's estimated error over the error band, dB, from the same spread
    /// (`ChannelResult::estimated_error_db`).
    pub error_db: Option<f64>,
}

/// One processed channel: actuator, the response when processing succeeded, problem.
pub(crate) type Outcome = (usize, Option<Measured>, Option<Problem>);

/// What settling a processed visit decided for the point.
#[derive(Debug, Clone)]
pub(crate) enum Settled {
    /// Every row is settled: commit these rows (indexed by actuator).
    Commit(Vec<Row>),
    /// Some row failed and visits remain: the point is queued for a re-measure at the end of the run.
    Deferred {
        /// The visit the re-measure will be (1 for the first deferral).
        visit: u32,
        /// What went wrong, one entry per row with a problem.
        reasons: Vec<String>,
    },
}

/// The points in progress and the deferred queue.
#[derive(Debug, Clone)]
pub(crate) struct PointBook {
    actuators: usize,
    deferred_visits: u32,
    states: BTreeMap<usize, PointState>,
    /// Points waiting for a re-measure, in the order they were deferred.
    pub deferred: VecDeque<usize>,
    /// Points deferred at least once.
    pub deferred_points: usize,
}

impl PointBook {
    /// A book for `actuators` actuators per point and `deferred_visits` extra visits of a failing point.
    pub(crate) fn new(actuators: usize, deferred_visits: u32) -> Self {
        Self { actuators, deferred_visits, states: BTreeMap::new(), deferred: VecDeque::new(), deferred_points: 0 }
    }

    /// Starts a visit of `point`: its visit number (0 for the first) and the actuators still to measure there.
    pub(crate) fn visit(&mut self, point: usize) -> (u32, Vec<usize>) {
        let actuators = self.actuators;
        let state = self.states.entry(point).or_insert_with(|| PointState {
            visit: 0,
            rows: vec![Row { acquisitions: 0, result: None, problem: None, done: false }; actuators],
        });
        (state.visit, (0..actuators).filter(|&a| !state.rows[a].done).collect())
    }

    /// Counts `acquisitions` more for `actuator`'s row at `point` (a point not being visited is ignored).
    pub(crate) fn count_acquisitions(&mut self, point: usize, actuator: usize, acquisitions: u32) {
        if let Some(row) = self.states.get_mut(&point).and_then(|s| s.rows.get_mut(actuator)) {
            row.acquisitions += acquisitions;
        }
    }

    /// Merges a visit's processed `outcomes` (measured with the beam at `aimed`) into the point's rows: the point is
    /// committed when every row is settled (good, a final problem, or its last visit), else deferred.
    ///
    /// # Errors
    /// [`RecipeError::Internal`] for a point that was never visited.
    pub(crate) fn settle(
        &mut self,
        point: usize,
        aimed: Aimed,
        outcomes: Vec<Outcome>,
    ) -> Result<Settled, RecipeError> {
        let Some(state) = self.states.get_mut(&point) else {
            return Err(RecipeError::Internal(format!("point {point} was processed but never acquired")));
        };
        let last_visit = state.visit >= self.deferred_visits;
        for (actuator, result, problem) in outcomes {
            let Some(row) = state.rows.get_mut(actuator) else {
                return Err(RecipeError::Internal(format!("an outcome for actuator {actuator} of {}", self.actuators)));
            };
            if let Some(measured) = result {
                row.result = Some((measured, aimed));
            }
            row.done = problem.as_ref().is_none_or(Problem::is_final);
            row.problem = problem;
            if last_visit {
                row.done = true;
            }
        }
        if state.rows.iter().all(|r| r.done) {
            let rows = self.states.remove(&point).map(|s| s.rows).unwrap_or_default();
            return Ok(Settled::Commit(rows));
        }
        let reasons = state.rows.iter().filter_map(|r| r.problem.as_ref().map(Problem::describe)).collect();
        state.visit += 1;
        if state.visit == 1 {
            self.deferred_points += 1;
        }
        self.deferred.push_back(point);
        Ok(Settled::Deferred { visit: state.visit, reasons })
    }
}

/// A committed row's status: its problem's, else re-measured when it took more than one acquisition.
pub(crate) fn row_status(row: &Row) -> Status {
    match &row.problem {
        Some(p) => p.status(),
        None if row.acquisitions > 1 => Status::ReMeasured,
        None => Status::Valid,
    }
}

/// The records of `point`'s settled `rows` (indexed by actuator) on `grid`: responses as f32, a zero response of
/// `ir_len` where none was measured, `retries` one less than the acquisitions, every row stamped `measured_at`.
///
/// # Errors
/// [`RecipeError::Store`] for a point outside the grid or a bad rate.
pub(crate) fn point_records(
    grid: &GridSpec,
    point: usize,
    rows: Vec<Row>,
    ir_len: usize,
    fs: f64,
    measured_at_unix_us: i64,
) -> Result<Vec<(IrRecord, Status)>, RecipeError> {
    let (ix, iy) = grid.indices(point);
    rows.into_iter()
        .enumerate()
        .map(|(actuator, row)| {
            let status = row_status(&row);
            let (measured, x_m, y_m) = match row.result {
                Some((measured, aimed)) => (measured, aimed.x_m, aimed.y_m),
                None => {
                    let (x, y) = grid.position_m(point);
                    (Measured { ir: vec![0.0; ir_len], snr_db: None, error_db: None }, x, y)
                }
            };
            let Measured { ir, snr_db, error_db } = measured;
            let meta = IrMeta {
                x_m,
                y_m,
                snr_db,
                estimated_error_db: error_db,
                status: Some(status),
                retries: Some(row.acquisitions.saturating_sub(1)),
                measured_at_unix_us: Some(measured_at_unix_us),
                ..IrMeta::at_grid(grid, ix as u32, iy as u32, actuator as u16, fs)?
            };
            Ok((IrRecord { meta, ir: ir.iter().map(|v| *v as f32).collect() }, status))
        })
        .collect()
}

/// Order of badness of a status, for the worst row of a point.
pub(crate) fn severity(status: Status) -> u8 {
    match status {
        Status::Valid | Status::GroundTruth => 0,
        Status::ReMeasured => 1,
        Status::Overrange => 2,
        Status::Dropout => 3,
        Status::Failed => 4,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    const HERE: Aimed = Aimed { x_m: 0.0, y_m: 0.0, level: 1.0 };

    /// A one-sample response with this SNR, its estimated error the SNR's opposite.
    pub(crate) fn measured(sample: f64, snr_db: f64) -> Measured {
        Measured { ir: vec![sample], snr_db: Some(snr_db), error_db: Some(-snr_db) }
    }

    fn good(actuator: usize) -> Outcome {
        (actuator, Some(measured(1.0, 40.0)), None)
    }

    fn low_snr(actuator: usize) -> Outcome {
        (actuator, Some(measured(0.5, 10.0)), Some(Problem::LowSnr(10.0)))
    }

    fn visit_all(book: &mut PointBook, point: usize) -> Vec<usize> {
        let (_, pending) = book.visit(point);
        for &a in &pending {
            book.count_acquisitions(point, a, 1);
        }
        pending
    }

    #[test]
    fn a_good_visit_commits_valid_rows() {
        let mut book = PointBook::new(2, 2);
        assert_eq!(visit_all(&mut book, 7), vec![0, 1]);
        let Settled::Commit(rows) = book.settle(7, HERE, vec![good(0), good(1)]).unwrap() else { panic!() };
        assert!(rows.iter().all(|r| row_status(r) == Status::Valid));
        assert!(book.deferred.is_empty());
    }

    #[test]
    fn a_failing_row_defers_the_point_and_only_it_is_re_measured() {
        let mut book = PointBook::new(2, 2);
        visit_all(&mut book, 3);
        let Settled::Deferred { visit, reasons } = book.settle(3, HERE, vec![good(0), low_snr(1)]).unwrap() else {
            panic!()
        };
        assert_eq!((visit, reasons.len()), (1, 1));
        assert_eq!(book.deferred, VecDeque::from([3]));
        assert_eq!(book.deferred_points, 1);
        // The re-visit measures actuator 1 alone; once good, the point commits with it re-measured.
        assert_eq!(visit_all(&mut book, 3), vec![1]);
        let Settled::Commit(rows) = book.settle(3, HERE, vec![good(1)]).unwrap() else { panic!() };
        assert_eq!(row_status(&rows[0]), Status::Valid);
        assert_eq!(row_status(&rows[1]), Status::ReMeasured);
        assert_eq!(rows[1].acquisitions, 2);
    }

    #[test]
    fn a_row_failing_every_visit_is_committed_flagged() {
        let mut book = PointBook::new(1, 2);
        for visit in 0..2 {
            visit_all(&mut book, 0);
            let settled = book.settle(0, HERE, vec![low_snr(0)]).unwrap();
            assert!(matches!(settled, Settled::Deferred { visit: v, .. } if v == visit + 1));
        }
        visit_all(&mut book, 0);
        let Settled::Commit(rows) = book.settle(0, HERE, vec![low_snr(0)]).unwrap() else { panic!() };
        assert_eq!(row_status(&rows[0]), Status::Failed);
        assert_eq!(rows[0].acquisitions, 3);
        // Counted once however often it was deferred.
        assert_eq!(book.deferred_points, 1);
    }

    #[test]
    fn a_final_problem_is_not_deferred() {
        let mut book = PointBook::new(1, 2);
        visit_all(&mut book, 0);
        let unreached = Problem::Unreached { target: AdaptiveTarget::SnrDb(30.0), value_db: Some(20.0), rounds: 8 };
        let settled = book.settle(0, HERE, vec![(0, Some(measured(1.0, 20.0)), Some(unreached))]).unwrap();
        let Settled::Commit(rows) = settled else { panic!() };
        assert_eq!(row_status(&rows[0]), Status::Failed);
    }

    #[test]
    fn clipping_is_overrange_and_a_point_never_visited_is_an_internal_error() {
        let mut book = PointBook::new(1, 0);
        visit_all(&mut book, 0);
        let clipped = (0, Some(measured(1.0, 40.0)), Some(Problem::from(AcquisitionProblem::Clipped)));
        let Settled::Commit(rows) = book.settle(0, HERE, vec![clipped]).unwrap() else { panic!() };
        assert_eq!(row_status(&rows[0]), Status::Overrange);
        assert!(matches!(book.settle(9, HERE, vec![]), Err(RecipeError::Internal(_))));
    }

    #[test]
    fn records_carry_retries_and_a_zero_response_where_nothing_was_measured() {
        let grid = GridSpec { nx: 2, ny: 1, spacing_m: 0.01, origin_x_m: 0.0, origin_y_m: 0.0 };
        let rows = vec![Row { acquisitions: 3, result: None, problem: Some(Problem::Gap), done: true }];
        let records = point_records(&grid, 1, rows, 4, 1000.0, 5).unwrap();
        let (record, status) = &records[0];
        assert_eq!(*status, Status::Dropout);
        assert_eq!(record.meta.retries, Some(2));
        assert_eq!(record.ir, vec![0.0; 4]);
        assert_eq!((record.meta.x_m, record.meta.measured_at_unix_us), (0.01, Some(5)));
    }
}

//! Which response an import takes for a (point, actuator) that the files give several of one kind: frequency
//! responses by several estimators (Polytec PSV's H1 and H2), responses in several directions (a 3-D scan head's X,
//! Y and Z); the others are listed as skipped.

use std::collections::BTreeSet;
use std::path::PathBuf;

use super::{SkippedRecord, Survey, record_at};
use crate::ImportOptions;
use crate::error::{InterchangeError, refuse};

/// The estimators of a frequency response a writer names in ID line 2 (Polytec PSV writes `Vib  Ref1  H1 Velocity
/// / Force`, one record per estimator it exports), in the order an import prefers them when the files hold several
/// of one pair and [`ImportOptions::estimator`] names none.
pub const ESTIMATORS: [&str; 5] = ["H1", "H2", "H3", "Hv", "FRF"];

/// The largest angle between the points' plane normal and a coordinate axis for which, of responses in several
/// directions at one point (a 3-D scan head's X, Y and Z), the one along that axis is kept as the plate's normal
/// velocity, degrees: its error is 1 - cos(5°) = 0.4 % of the normal velocity plus sin(5°) = 9 % of the in-plane
/// velocity, which is small on a plate driven in bending.
pub const MAX_AXIS_ANGLE_DEG: f64 = 5.0;

/// The estimator ID line 2 names (one of [`ESTIMATORS`], as a separate word), if any.
pub(crate) fn estimator(id_line_2: &str) -> Option<&'static str> {
    id_line_2.split_whitespace().find_map(|w| ESTIMATORS.iter().find(|e| **e == w).copied())
}

/// The estimator `options` asks for, as one of [`ESTIMATORS`].
///
/// # Errors
/// [`InterchangeError::Refused`] for a name that is none of them.
pub(crate) fn wanted_estimator(options: &ImportOptions) -> Result<Option<&'static str>, InterchangeError> {
    match &options.estimator {
        None => Ok(None),
        Some(name) => match ESTIMATORS.iter().copied().find(|e| e == name) {
            Some(e) => Ok(Some(e)),
            None => refuse!("--estimator {name}: accepted are {}", ESTIMATORS.join(", ")),
        },
    }
}

/// Chooses among several responses of one kind for one key, and lists those it leaves.
pub(crate) struct Chooser<'a> {
    files: &'a [PathBuf],
    survey: &'a Survey,
    /// The estimator asked for ([`wanted_estimator`]); `None`: the first of [`ESTIMATORS`] present.
    wanted: Option<&'static str>,
    /// Unit normal of the points' plane.
    normal: [f64; 3],
    not_chosen: Vec<SkippedRecord>,
    estimator: Option<&'static str>,
    direction: Option<i8>,
}

impl<'a> Chooser<'a> {
    pub(crate) fn new(
        files: &'a [PathBuf],
        survey: &'a Survey,
        wanted: Option<&'static str>,
        normal: [f64; 3],
    ) -> Self {
        Self { files, survey, wanted, normal, not_chosen: Vec::new(), estimator: None, direction: None }
    }

    /// The responses not chosen, the estimator chosen and the response direction chosen (where any key had to).
    pub(crate) fn finish(self) -> (Vec<SkippedRecord>, Option<&'static str>, Option<i8>) {
        (self.not_chosen, self.estimator, self.direction)
    }

    fn leave(&mut self, i: usize, what: String) {
        let seen = &self.survey.functions[i];
        self.not_chosen.push(SkippedRecord {
            file: self.files[seen.at.0].display().to_string(),
            record: seen.at.1,
            line: seen.line,
            what,
        });
    }

    /// Of FRFs by several estimators (ID line 2), those of the one asked for, else of the first of [`ESTIMATORS`]
    /// present. Responses that name none, or one, are kept as they are.
    pub(crate) fn by_estimator(&mut self, key: (u32, u16), pool: Vec<usize>) -> Result<Vec<usize>, InterchangeError> {
        let named: BTreeSet<Option<&'static str>> = pool.iter().map(|&i| self.survey.functions[i].estimator).collect();
        if named.len() < 2 {
            return Ok(pool);
        }
        let first_present = ESTIMATORS.iter().copied().find(|e| named.contains(&Some(*e)));
        // Two or more named: at least one is of ESTIMATORS.
        let wanted = self.wanted.or(first_present).unwrap_or(ESTIMATORS[0]);
        let (kept, left): (Vec<usize>, Vec<usize>) =
            pool.into_iter().partition(|&i| self.survey.functions[i].estimator == Some(wanted));
        if kept.is_empty() {
            let present: Vec<&str> = named.iter().map(|e| e.unwrap_or("none named")).collect();
            refuse!(
                "point {} actuator {}: {} holds frequency responses by the estimators {} (ID line 2), none by {wanted}; \
                 --estimator takes one of {}",
                key.0,
                key.1,
                record_at(self.files, &self.survey.functions[left[0]]),
                present.join(", "),
                ESTIMATORS.join(", ")
            );
        }
        for i in left {
            let other = self.survey.functions[i].estimator.unwrap_or("no named");
            self.leave(i, format!("dataset 58, {other} estimate (not chosen: the {wanted} estimate is imported)"));
        }
        self.estimator = Some(wanted);
        Ok(kept)
    }

    /// Of responses in several directions at one point (a 3-D scan head's X, Y and Z), the one along the axis
    /// nearest the points' plane normal, when that axis is within [`MAX_AXIS_ANGLE_DEG`] of it.
    pub(crate) fn by_direction(&mut self, key: (u32, u16), pool: Vec<usize>) -> Result<Vec<usize>, InterchangeError> {
        let directions: BTreeSet<i8> = pool.iter().map(|&i| self.survey.functions[i].response_direction).collect();
        if directions.len() < 2 {
            return Ok(pool);
        }
        let n = self.normal;
        let axis = (0..3).max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap_or(2);
        let angle_deg = n[axis].abs().clamp(0.0, 1.0).acos().to_degrees();
        let listed: Vec<String> = directions.iter().map(i8::to_string).collect();
        let first = record_at(self.files, &self.survey.functions[pool[0]]);
        if angle_deg > MAX_AXIS_ANGLE_DEG {
            refuse!(
                "point {} actuator {}: {first} and others hold responses in the directions {} (record 6); the points' \
                 plane normal ({:.3}, {:.3}, {:.3}) is {angle_deg:.1}° from the nearest axis, and an import keeps the \
                 component along an axis within {MAX_AXIS_ANGLE_DEG}° of the normal (the normal velocity of a tilted \
                 plate combines the components, which it does not do)",
                key.0,
                key.1,
                listed.join(", "),
                n[0],
                n[1],
                n[2]
            );
        }
        let code = i8::try_from(axis + 1).unwrap_or(3);
        let (kept, left): (Vec<usize>, Vec<usize>) =
            pool.into_iter().partition(|&i| self.survey.functions[i].response_direction.abs() == code);
        if kept.is_empty() {
            refuse!(
                "point {} actuator {}: {first} and others hold responses in the directions {} (record 6), none along \
                 the points' plane normal (direction ±{code})",
                key.0,
                key.1,
                listed.join(", ")
            );
        }
        for i in left {
            let d = self.survey.functions[i].response_direction;
            self.leave(i, format!("dataset 58, response direction {d} (not chosen: the plate's normal is ±{code})"));
        }
        self.direction = Some(code);
        Ok(kept)
    }
}

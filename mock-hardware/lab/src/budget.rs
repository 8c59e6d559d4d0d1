//! An error budget: what each imperfection of the mock lab adds to the Green's-function error against the ground
//! truth, and the processing floor under them all.
//!
//! The scene is measured as several variants ([`BudgetPart`]): every imperfection off (the floor: what the
//! processing itself leaves), each imperfection the scene has alone, and the scene itself (all on). Each variant's
//! measured rows are compared with the same truth ([`MockLab::response_error_db`]) over [`ERROR_BAND_HZ`] and over
//! its octave bands ([`BUDGET_BANDS_HZ`]), and summarised by median and 95th percentile ([`ErrorSummary`]).
//! Whether the terms add up is checked on powers: if the error components are independent, the all-on error power
//! is the floor's plus each term's excess over the floor ([`Budget::predicted_all_on_median_db`]).
//!
//! **The truth for a nonlinear actuator** is the small-signal linear part of the chain ([`MockLab::true_response`]:
//! the voice coil's linear filter times the plate's Green's function), not what a sweep at a given level would
//! measure. The Green's function is a property of the plate and the coil's linear response, the thing the paper's
//! focusing (a linear superposition of time-reversed responses) relies on; what the cubic term adds at the drive
//! level is an error of the measurement, which an exponential sweep's harmonic separation removes for the
//! harmonics and leaves for the compressed fundamental. Defining the truth as "what the paper's procedure would
//! measure" would hide exactly the bias a budget must show, and would depend on the drive level and protocol.
//!
//! The measurement itself (a scan through the recipes) lives above this crate; the binary's `metaplate budget`
//! runs it for each [`Budget::variants`] entry and hands the rows back here.

use metaplate_core::scene::{Imperfection, Scene};
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::quantile;

pub use metaplate_dsp::accuracy::ERROR_BAND_HZ;

use crate::{LabError, MockLab};

/// The octave bands within [`ERROR_BAND_HZ`] a budget reports separately, Hz (the last one cut at 600 Hz).
pub const BUDGET_BANDS_HZ: [(f64, f64); 3] = [(80.0, 160.0), (160.0, 320.0), (320.0, 600.0)];

/// Which variant of the scene a budget measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BudgetPart {
    /// Every imperfection off: the processing floor.
    Floor,
    /// This imperfection alone.
    Alone(Imperfection),
    /// The scene as it is.
    AllOn,
}

impl BudgetPart {
    /// Its name in tables: `floor`, the imperfection's name, `all-on`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Floor => "floor",
            Self::Alone(i) => i.name(),
            Self::AllOn => "all-on",
        }
    }
}

/// One measured row's error against the truth, dB: over [`ERROR_BAND_HZ`] and over each of [`BUDGET_BANDS_HZ`].
#[derive(Debug, Clone, PartialEq)]
pub struct RowError {
    /// Over the whole band, dB.
    pub overall_db: f64,
    /// Per band of [`BUDGET_BANDS_HZ`], in its order, dB.
    pub bands_db: Vec<f64>,
}

/// Median and 95th percentile (nearest rank) of a set of rows' errors, dB.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantiles {
    /// Median, dB.
    pub median_db: f64,
    /// 95th percentile, dB.
    pub p95_db: f64,
}

impl Quantiles {
    /// The quantiles of `values`, dB.
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] for no value or a non-finite one.
    pub fn of(values: &[f64]) -> Result<Quantiles, LabError> {
        let bad = || LabError::InvalidOption {
            name: "row errors",
            reason: format!("{} values, none or some not finite", values.len()),
        };
        let median_db = quantile(&mut values.to_vec(), 0.5).ok_or_else(bad)?;
        let p95_db = quantile(&mut values.to_vec(), 0.95).ok_or_else(bad)?;
        Ok(Quantiles { median_db, p95_db })
    }
}

/// A variant's errors: overall, and per band of [`BUDGET_BANDS_HZ`].
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorSummary {
    /// Rows compared.
    pub rows: usize,
    /// Over [`ERROR_BAND_HZ`].
    pub overall: Quantiles,
    /// Per band, in the order of [`BUDGET_BANDS_HZ`].
    pub bands: Vec<Quantiles>,
}

impl ErrorSummary {
    /// The summary of `rows`.
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] for no row, a row with another number of bands, or a non-finite error.
    pub fn of(rows: &[RowError]) -> Result<ErrorSummary, LabError> {
        let overall: Vec<f64> = rows.iter().map(|r| r.overall_db).collect();
        let bands = (0..BUDGET_BANDS_HZ.len())
            .map(|b| {
                let values: Vec<f64> = rows
                    .iter()
                    .map(|r| {
                        r.bands_db.get(b).copied().ok_or(LabError::InvalidOption {
                            name: "row errors",
                            reason: format!("a row with {} bands", r.bands_db.len()),
                        })
                    })
                    .collect::<Result<_, _>>()?;
                Quantiles::of(&values)
            })
            .collect::<Result<_, _>>()?;
        Ok(ErrorSummary { rows: rows.len(), overall: Quantiles::of(&overall)?, bands })
    }
}

/// One term of a budget: an imperfection alone.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetTerm {
    /// The imperfection.
    pub imperfection: Imperfection,
    /// Its errors with every other imperfection off.
    pub errors: ErrorSummary,
}

/// A measured error budget.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    /// Every imperfection off.
    pub floor: ErrorSummary,
    /// Each imperfection the scene has, alone, in the order of [`Imperfection::all`].
    pub terms: Vec<BudgetTerm>,
    /// The scene as it is.
    pub all_on: ErrorSummary,
}

impl Budget {
    /// The variants of `scene` to measure, in order: the floor, each imperfection the scene has alone
    /// ([`Imperfection::is_present`]), all on.
    pub fn variants(scene: &Scene) -> Vec<(BudgetPart, Scene)> {
        let mut parts = vec![(BudgetPart::Floor, scene.with_only(&[]))];
        parts.extend(
            Imperfection::all()
                .iter()
                .filter(|i| i.is_present(scene))
                .map(|&i| (BudgetPart::Alone(i), scene.with_only(&[i]))),
        );
        parts.push((BudgetPart::AllOn, scene.clone()));
        parts
    }

    /// The budget of the measured variants, given as [`Budget::variants`] lists them with their rows' errors.
    ///
    /// # Errors
    /// [`LabError::InvalidOption`] when the floor or all-on is missing, or as [`ErrorSummary::of`].
    pub fn from_parts(parts: &[(BudgetPart, Vec<RowError>)]) -> Result<Budget, LabError> {
        let find = |want: BudgetPart| {
            parts
                .iter()
                .find(|(p, _)| *p == want)
                .ok_or(LabError::InvalidOption { name: "budget parts", reason: format!("no {} measured", want.name()) })
        };
        let terms = parts
            .iter()
            .filter_map(|(p, rows)| match p {
                BudgetPart::Alone(i) => Some((*i, rows)),
                _ => None,
            })
            .map(|(imperfection, rows)| Ok(BudgetTerm { imperfection, errors: ErrorSummary::of(rows)? }))
            .collect::<Result<_, LabError>>()?;
        Ok(Budget {
            floor: ErrorSummary::of(&find(BudgetPart::Floor)?.1)?,
            terms,
            all_on: ErrorSummary::of(&find(BudgetPart::AllOn)?.1)?,
        })
    }

    /// The all-on median error the terms predict if they add as independent powers, dB: the floor's power plus,
    /// per term, its power in excess of the floor's (none when a term measures at or below the floor).
    pub fn predicted_all_on_median_db(&self) -> f64 {
        let power = |db: f64| 10f64.powf(db / 10.0);
        let floor = power(self.floor.overall.median_db);
        let excess: f64 = self.terms.iter().map(|t| (power(t.errors.overall.median_db) - floor).max(0.0)).sum();
        10.0 * (floor + excess).log10()
    }

    /// How far the measured all-on median lies above the prediction, dB (negative: below). Within about 1 dB the
    /// terms account for the total; far above, imperfections interact (for example speckle, which only scales the
    /// noise and so adds nothing alone).
    pub fn closure_db(&self) -> f64 {
        self.all_on.overall.median_db - self.predicted_all_on_median_db()
    }
}

impl MockLab {
    /// The error of a measured response against the truth over [`ERROR_BAND_HZ`] and over each of
    /// [`BUDGET_BANDS_HZ`] ([`MockLab::response_error_db`] for each); `ir[0]` lies at time `-pre_samples`.
    ///
    /// # Errors
    /// As [`MockLab::response_error_db`].
    pub fn row_error(
        &self,
        point: usize,
        actuator: usize,
        ir: &[f64],
        pre_samples: usize,
        sample_rate_hz: f64,
        compensation: Option<&KirkebyFilter>,
    ) -> Result<RowError, LabError> {
        let ir = crate::time_zero_first(ir, pre_samples);
        let error = |band| self.response_error_db(point, actuator, &ir, sample_rate_hz, band, compensation);
        Ok(RowError {
            overall_db: error(ERROR_BAND_HZ)?,
            bands_db: BUDGET_BANDS_HZ.iter().map(|&b| error(b)).collect::<Result<_, _>>()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(db: f64) -> Vec<RowError> {
        vec![RowError { overall_db: db, bands_db: vec![db; BUDGET_BANDS_HZ.len()] }; 3]
    }

    #[test]
    fn terms_that_add_as_powers_close_the_budget() {
        let parts = vec![
            (BudgetPart::Floor, rows(-100.0)),
            (BudgetPart::Alone(Imperfection::LdvNoise), rows(-40.0)),
            (BudgetPart::Alone(Imperfection::Nonlinearity), rows(-40.0)),
            (BudgetPart::Alone(Imperfection::Speckle), rows(-100.0)),
            (BudgetPart::AllOn, rows(-37.0)),
        ];
        let budget = Budget::from_parts(&parts).unwrap();
        assert_eq!(budget.terms.len(), 3);
        // Two equal terms: 3 dB above either.
        assert!((budget.predicted_all_on_median_db() - (-36.99)).abs() < 0.01);
        assert!(budget.closure_db().abs() < 0.02);
        assert!(Budget::from_parts(&parts[1..]).is_err(), "no floor");
    }

    #[test]
    fn the_variants_are_floor_each_term_and_all_on() {
        let scene = Scene::builtin("homogeneous").unwrap();
        let v = Budget::variants(&scene);
        assert_eq!(v.first().map(|(p, _)| *p), Some(BudgetPart::Floor));
        assert_eq!(v.last().map(|(p, s)| (*p, s == &scene)), Some((BudgetPart::AllOn, true)));
        // The built-ins have every imperfection but scheduled faults and an aiming error.
        assert_eq!(v.len(), Imperfection::all().len());
    }
}

//! An error budget: what each imperfection of the mock lab adds to the Green's-function error against the ground
//! truth, and the processing floor under them all.
//!
//! The scene is measured as several variants ([`BudgetPart`]): every imperfection off (the floor: what the
//! processing itself leaves), each imperfection the scene has alone, and the scene itself (all on). Each variant's
//! measured rows are compared with the same truths ([`MockLab::windowed_truth`]: the full truth, as
//! [`MockLab::response_error_db`]; the truth as the window keeps it; for a periodic excitation, the truth folded
//! modulo its period) over [`ERROR_BAND_HZ`] and over its octave bands ([`BUDGET_BANDS_HZ`]), and summarised by
//! median and 95th percentile ([`ErrorSummary`]). The processing floor is the floor against the windowed truth;
//! the truncation (the windowed truth against the full one, from the truth alone) is what a perfect measurement of
//! the window still misses, and the aliasing (the folded truth against the windowed one) what a period shorter
//! than the response wraps onto it. The imperfections' terms and all on are judged against the full truth, the
//! Green's-function error a user of the dataset sees.
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
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::quantile;

pub use metaplate_dsp::accuracy::ERROR_BAND_HZ;

use crate::windowed_truth::Truth;
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

/// One row's error, dB: over [`ERROR_BAND_HZ`] and over each of [`BUDGET_BANDS_HZ`].
#[derive(Debug, Clone, PartialEq)]
pub struct BandErrors {
    /// Over the whole band, dB.
    pub overall_db: f64,
    /// Per band of [`BUDGET_BANDS_HZ`], in its order, dB.
    pub bands_db: Vec<f64>,
}

impl BandErrors {
    /// `error(band)` over [`ERROR_BAND_HZ`] and each of [`BUDGET_BANDS_HZ`].
    ///
    /// # Errors
    /// The first error `error` returns.
    pub fn by_band(error: impl Fn((f64, f64)) -> Result<f64, LabError>) -> Result<BandErrors, LabError> {
        Ok(BandErrors {
            overall_db: error(ERROR_BAND_HZ)?,
            bands_db: BUDGET_BANDS_HZ.iter().map(|&b| error(b)).collect::<Result<_, _>>()?,
        })
    }

    /// Overall and per band, the power sum of `self` and `other`, dB (two independent errors together).
    pub fn power_sum(&self, other: &BandErrors) -> BandErrors {
        let sum = |a: f64, b: f64| 10.0 * (power(a) + power(b)).log10();
        BandErrors {
            overall_db: sum(self.overall_db, other.overall_db),
            bands_db: self.bands_db.iter().zip(&other.bands_db).map(|(&a, &b)| sum(a, b)).collect(),
        }
    }
}

/// `10^(db / 10)`: a level as a power ratio.
fn power(db: f64) -> f64 {
    10f64.powf(db / 10.0)
}

/// One measured row's errors against each truth ([`crate::windowed_truth`]), and what its truth alone loses to the
/// window and to the excitation's period.
#[derive(Debug, Clone, PartialEq)]
pub struct RowError {
    /// Against the full truth: the Green's-function error a user of the dataset sees.
    pub full: BandErrors,
    /// Against the truth as the window keeps it: what the processing does to the part of the response the dataset
    /// keeps.
    pub windowed: BandErrors,
    /// The truncation: the windowed truth against the full truth (the truth alone, no measurement): what a perfect
    /// measurement of the window still misses.
    pub truncation: BandErrors,
    /// For a periodic excitation: against the truth folded modulo its period, then windowed.
    pub periodic: Option<BandErrors>,
    /// For a periodic excitation: the folded truth against the windowed truth (the truth alone): what the period's
    /// wrap of the response's tail adds.
    pub aliasing: Option<BandErrors>,
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

/// A set of rows' errors: overall, and per band of [`BUDGET_BANDS_HZ`].
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
    pub fn of<'a>(rows: impl IntoIterator<Item = &'a BandErrors>) -> Result<ErrorSummary, LabError> {
        let rows: Vec<&BandErrors> = rows.into_iter().collect();
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

/// A measured variant's errors against each truth.
#[derive(Debug, Clone, PartialEq)]
pub struct PartErrors {
    /// Against the full truth.
    pub full: ErrorSummary,
    /// Against the truth as the window keeps it.
    pub windowed: ErrorSummary,
    /// Against the truth a periodic excitation measures (folded, then windowed), for a periodic one.
    pub periodic: Option<ErrorSummary>,
}

impl PartErrors {
    /// The summaries of `rows` against each truth.
    ///
    /// # Errors
    /// As [`ErrorSummary::of`].
    pub fn of(rows: &[RowError]) -> Result<PartErrors, LabError> {
        let periodic: Option<Vec<&BandErrors>> = rows.iter().map(|r| r.periodic.as_ref()).collect();
        Ok(PartErrors {
            full: ErrorSummary::of(rows.iter().map(|r| &r.full))?,
            windowed: ErrorSummary::of(rows.iter().map(|r| &r.windowed))?,
            periodic: periodic.map(ErrorSummary::of).transpose()?,
        })
    }
}

/// One term of a budget: an imperfection alone.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetTerm {
    /// The imperfection.
    pub imperfection: Imperfection,
    /// Its errors with every other imperfection off.
    pub errors: PartErrors,
}

/// A measured error budget.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    /// Every imperfection off. Against the windowed truth it is the processing floor.
    pub floor: PartErrors,
    /// The truncation of the floor's rows (the truth alone): the response outside the window.
    pub truncation: ErrorSummary,
    /// For a periodic excitation, the aliasing of the floor's rows (the truth alone): the period's wrap.
    pub aliasing: Option<ErrorSummary>,
    /// Per floor row, how far its error against the full truth lies from its error against the windowed truth
    /// plus its truncation, added as powers, dB (absolute): median and 95th percentile. Near 0 dB, the two
    /// account for the error against the full truth.
    pub truncation_split: Quantiles,
    /// As `truncation_split`, for the error against the windowed truth from the error against the folded truth
    /// plus the aliasing (a periodic excitation).
    pub aliasing_split: Option<Quantiles>,
    /// Each imperfection the scene has, alone, in the order of [`Imperfection::all`].
    pub terms: Vec<BudgetTerm>,
    /// The scene as it is.
    pub all_on: PartErrors,
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
                .map(|(_, rows)| rows)
                .ok_or(LabError::InvalidOption { name: "budget parts", reason: format!("no {} measured", want.name()) })
        };
        let terms = parts
            .iter()
            .filter_map(|(p, rows)| match p {
                BudgetPart::Alone(i) => Some((*i, rows)),
                _ => None,
            })
            .map(|(imperfection, rows)| Ok(BudgetTerm { imperfection, errors: PartErrors::of(rows)? }))
            .collect::<Result<_, LabError>>()?;
        let floor = find(BudgetPart::Floor)?;
        let aliasing: Option<Vec<&BandErrors>> = floor.iter().map(|r| r.aliasing.as_ref()).collect();
        let (truncation_split, aliasing_split) = splits(floor)?;
        Ok(Budget {
            floor: PartErrors::of(floor)?,
            truncation: ErrorSummary::of(floor.iter().map(|r| &r.truncation))?,
            aliasing: aliasing.map(ErrorSummary::of).transpose()?,
            truncation_split,
            aliasing_split,
            terms,
            all_on: PartErrors::of(find(BudgetPart::AllOn)?)?,
        })
    }

    /// The all-on median error against the full truth that the terms predict if they add as independent powers,
    /// dB: the floor's power plus, per term, its power in excess of the floor's (none when a term measures at or
    /// below the floor), all against the full truth.
    pub fn predicted_all_on_median_db(&self) -> f64 {
        let floor = power(self.floor.full.overall.median_db);
        let excess: f64 = self.terms.iter().map(|t| (power(t.errors.full.overall.median_db) - floor).max(0.0)).sum();
        10.0 * (floor + excess).log10()
    }

    /// How far the measured all-on median lies above the prediction, dB (negative: below). Within about 1 dB the
    /// terms account for the total; far above, imperfections interact (for example speckle, which only scales the
    /// noise and so adds nothing alone).
    pub fn closure_db(&self) -> f64 {
        self.all_on.full.overall.median_db - self.predicted_all_on_median_db()
    }
}

/// How well each row's error splits into independent parts, as powers, over [`ERROR_BAND_HZ`]: the absolute
/// difference, dB, between its error against the full truth and its error against the windowed truth plus its
/// truncation (first), and, when every row has a periodic truth, between its error against the windowed truth
/// and its error against the folded truth plus its aliasing (second); median and 95th percentile over the rows.
///
/// # Errors
/// As [`Quantiles::of`] (no row).
pub fn splits(rows: &[RowError]) -> Result<(Quantiles, Option<Quantiles>), LabError> {
    let split =
        |whole: &BandErrors, a: &BandErrors, b: &BandErrors| (whole.overall_db - a.power_sum(b).overall_db).abs();
    let truncation: Vec<f64> = rows.iter().map(|r| split(&r.full, &r.windowed, &r.truncation)).collect();
    let aliasing: Option<Vec<f64>> =
        rows.iter().map(|r| Some(split(&r.windowed, r.periodic.as_ref()?, r.aliasing.as_ref()?))).collect();
    Ok((Quantiles::of(&truncation)?, aliasing.map(|a| Quantiles::of(&a)).transpose()?))
}

impl MockLab {
    /// The errors of a measured response against each truth over [`ERROR_BAND_HZ`] and over each of
    /// [`BUDGET_BANDS_HZ`], and its truth's truncation (and aliasing, with `period_samples`): `ir` is `window.ir_len`
    /// samples, `ir[0]` at time `-window.pre_samples`, band-limited by `window.band` (see
    /// [`MockLab::windowed_truth`]).
    ///
    /// # Errors
    /// As [`MockLab::windowed_truth`] and [`crate::windowed_truth::WindowedTruth::error_db`].
    pub fn row_error(
        &self,
        point: usize,
        actuator: usize,
        ir: &[f64],
        window: &DeconvConfig,
        period_samples: Option<usize>,
        compensation: Option<&KirkebyFilter>,
    ) -> Result<RowError, LabError> {
        let truth = self.windowed_truth(point, actuator, window, period_samples, compensation)?;
        let ir = crate::time_zero_first(ir, window.pre_samples);
        let against = |t: Truth| BandErrors::by_band(|band| truth.error_db(&ir, t, band));
        let periodic = period_samples.is_some();
        Ok(RowError {
            full: against(Truth::Full)?,
            windowed: against(Truth::Windowed)?,
            truncation: BandErrors::by_band(|band| truth.truncation_db(band))?,
            periodic: if periodic { Some(against(Truth::Periodic)?) } else { None },
            aliasing: if periodic { Some(BandErrors::by_band(|band| truth.aliasing_db(band))?) } else { None },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(db: f64) -> BandErrors {
        BandErrors { overall_db: db, bands_db: vec![db; BUDGET_BANDS_HZ.len()] }
    }

    /// Rows at `db` against the full truth whose windowed error and truncation each carry half its power.
    fn rows(db: f64) -> Vec<RowError> {
        let half = db - 10.0 * 2f64.log10();
        vec![
            RowError {
                full: errors(db),
                windowed: errors(half),
                truncation: errors(half),
                periodic: None,
                aliasing: None
            };
            3
        ]
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
        // Each row's windowed error and truncation add to its full error exactly (rounding only).
        assert!(budget.truncation_split.p95_db < 1e-9, "{:?}", budget.truncation_split);
        assert_eq!(budget.aliasing_split, None);
        assert!((budget.truncation.overall.median_db - (-103.01)).abs() < 0.01);
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

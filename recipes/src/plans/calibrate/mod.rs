//! Actuator calibration: per actuator, the beam on its magnet, the calibration sweep, the response, a Kirkeby
//! inverse filter, and a verification measurement through the filter; one commit per actuator.
//!
//! The calibration dataset is a store dataset on a 3 x 1 "grid" whose columns are the three responses kept per
//! actuator, each row at the magnet's position (x_m, y_m), its `kind` column saying what it is (readers go by
//! `kind`, [`calibration_row`]; the grid column keeps the store's (point, actuator) keys distinct):
//! - `ix = 0` ([`FILTER_IX`]): the Kirkeby filter taps (1 / (m/s per full scale), normalised so that the compensated
//!   actuator's in-band gain is its uncompensated median gain);
//! - `ix = 1` ([`RESPONSE_IX`]): the measured response, m/s per full scale, two-sided (`pre_samples` before time 0);
//! - `ix = 2` ([`VERIFY_IX`]): the verification response through the filter, same units and layout; its flatness
//!   over the scan band is the calibration's pass criterion (status `valid`, else `failed`).
//!
//! The calibration is a [`crate::engine::plan::Plan`] (`plan`): per actuator, attempts of a response step and a
//! verification step; `processing` designs the filter and judges the verification on the engine's worker thread;
//! `load` reads a calibration back for a scan.
//!
//! Taps are stored as f32: 7 significant digits, a relative error of 6e-8 (-144 dB), far below any measurement.

mod load;
mod plan;
mod processing;

use metaplate_core::rig::Rig;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::equalise::{CALIBRATION_MEASURED_BAND_HZ, EqualiserConfig};
use metaplate_dsp::kirkeby::{KirkebyConfig, KirkebyFilter};
use metaplate_dsp::sweep::SweepSpec;
use metaplate_store::{Dataset, GridSpec, RowKind, Status};
use serde_json::{Map, Value, json};

use crate::engine::acquire::RetryPolicy;
use crate::engine::aim::AimPolicy;
use crate::engine::plan::Settings;
use crate::engine::run::run;
use crate::engine::session::RecoveryPolicy;
use crate::error::RecipeError;
use crate::events::{Observer, RunControl};
use crate::output::Output;
use crate::quality::Flatness;
pub use load::Calibration;
use plan::CalibrationPlan;

/// Recipe name in the manifest.
pub const RECIPE: &str = "calibrate";
/// Grid column of the filter taps (`kind` filter).
pub const FILTER_IX: u32 = 0;
/// Grid column of the measured response.
pub const RESPONSE_IX: u32 = 1;
/// Grid column of the verification response.
pub const VERIFY_IX: u32 = 2;

/// The calibration grid: three columns, one row (see the module documentation). Spacing 1 m is nominal only.
pub const CALIBRATION_GRID: GridSpec = GridSpec { nx: 3, ny: 1, spacing_m: 1.0, origin_x_m: 0.0, origin_y_m: 0.0 };

/// What a calibration does.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationConfig {
    /// The calibration sweep (its `sample_rate_hz` is replaced by the DAQ's).
    pub sweep: SweepSpec,
    /// Deconvolution of the response (the tested recipe: [`DeconvConfig::calibration`]).
    pub deconv: DeconvConfig,
    /// The inverse filter design ([`KirkebyConfig::calibration`] of `deconv`).
    pub kirkeby: KirkebyConfig,
    /// Band where the compensated response must be flat, Hz (the scan's band).
    pub check_band_hz: (f64, f64),
    /// Largest deviation from the median accepted over the band, dB.
    pub max_deviation_db: f64,
    /// Octave fraction (3: a third of an octave) over which the response's power is averaged before it is
    /// inverted, and the verification before its flatness is judged: the plate's driving-point modes, narrow peaks
    /// and notches at the magnet, are the plate's and are left alone (see [`metaplate_dsp::smooth`]). Windows are
    /// cut at the check band's edges, so the roll-off outside it does not count.
    pub smoothing_fraction: f64,
    /// Whether the compensated response must also be flat within `max_deviation_db` on pyfar's standard smoothing
    /// (same fraction, over the check band; [`crate::quality::standard_flatness`]), as others would measure it: the
    /// equaliser aims between both smoothings and the verdict takes both. Its window reaches half a window past the
    /// check band, which the sweep, the deconvolution's band and the Kirkeby band must cover.
    pub standard_smoothing: bool,
    /// The design is refined until the predicted compensated response (the measured one through the taps) is this
    /// flat, dB, or `max_designs` were made (see [`metaplate_dsp::equalise`]).
    pub design_tolerance_db: f64,
    /// Designs at most per measured response.
    pub max_designs: usize,
    /// Measurements per actuator before it is committed as failed.
    pub max_attempts: u32,
    /// Velocity range asked of the vibrometer first, m/s (widened tenfold on clipping).
    pub max_velocity_m_s: f64,
    /// Aiming at the magnet.
    pub aim: AimPolicy,
    /// Waiting for devices.
    pub recovery: RecoveryPolicy,
    /// Seed of every random choice (beam nudges).
    pub seed: u64,
}

impl Default for CalibrationConfig {
    /// The paper's calibration, measured over a wider band: a 3 s linear sweep (amplitude 0.5) and the
    /// deconvolution's and Kirkeby band over [`CALIBRATION_MEASURED_BAND_HZ`] (50..710 Hz; the paper's sweep is
    /// 50..625 Hz) so that the standard smoothing's window at 625 Hz averages measured response,
    /// [`DeconvConfig::calibration`] and [`KirkebyConfig::calibration`] otherwise, flat within +/-1 dB over 62..625
    /// Hz on both smoothings, 3 attempts, 0.1 m/s range.
    fn default() -> Self {
        let (lo_hz, hi_hz) = CALIBRATION_MEASURED_BAND_HZ;
        let paper = DeconvConfig::calibration();
        let deconv =
            DeconvConfig { band: paper.band.map(|b| metaplate_dsp::band::BandLimit { lo_hz, hi_hz, ..b }), ..paper };
        // The equaliser's settings have one home, shared with the ground truth (the Kirkeby band among them).
        let equaliser = EqualiserConfig::calibration(KirkebyConfig::calibration(&deconv));
        Self {
            sweep: SweepSpec { f1_hz: lo_hz, f2_hz: hi_hz, amplitude: 0.5, ..SweepSpec::default() },
            kirkeby: equaliser.kirkeby,
            deconv,
            standard_smoothing: equaliser.standard,
            check_band_hz: equaliser.band_hz,
            max_deviation_db: 1.0,
            smoothing_fraction: equaliser.fraction,
            design_tolerance_db: equaliser.tolerance_db,
            max_designs: equaliser.max_designs,
            max_attempts: 3,
            max_velocity_m_s: 0.1,
            aim: AimPolicy::default(),
            recovery: RecoveryPolicy::default(),
            seed: 0,
        }
    }
}

impl CalibrationConfig {
    /// The configuration as stored in the manifest (everything that changes the result).
    pub fn to_json(&self, sites_m: &[(f64, f64)]) -> Map<String, Value> {
        let s = &self.sweep;
        let d = &self.deconv;
        let k = &self.kirkeby;
        let value = json!({
            "sweep": { "f1_hz": s.f1_hz, "f2_hz": s.f2_hz, "duration_s": s.duration_s, "amplitude": s.amplitude,
                       "fade_in_s": s.fade_in_s, "fade_out_s": s.fade_out_s, "kind": format!("{:?}", s.kind) },
            "deconv": { "ir_len": d.ir_len, "pre_samples": d.pre_samples, "regularisation": d.regularisation,
                        "band": d.band.map(|b| [b.lo_hz, b.hi_hz, b.lo_transition_hz, b.hi_transition_hz]) },
            "kirkeby": { "fir_len": k.fir_len, "modelling_delay_samples": k.modelling_delay_samples, "beta": k.beta,
                         "target": format!("{:?}", k.target),
                         "profile": [k.profile.band.lo_hz, k.profile.band.hi_hz, k.profile.band.lo_transition_hz,
                                     k.profile.band.hi_transition_hz, k.profile.in_band, k.profile.out_of_band] },
            "check_band_hz": [self.check_band_hz.0, self.check_band_hz.1],
            "max_deviation_db": self.max_deviation_db,
            "smoothing_fraction": self.smoothing_fraction,
            "standard_smoothing": self.standard_smoothing,
            "design_tolerance_db": self.design_tolerance_db,
            "max_designs": self.max_designs,
            "max_attempts": self.max_attempts,
            "max_velocity_m_s": self.max_velocity_m_s,
            "aim": { "min_signal_level": self.aim.min_signal_level, "nudge_m": self.aim.nudge_m,
                     "max_nudges": self.aim.max_nudges },
            "actuator_sites_m": sites_m.iter().map(|(x, y)| [*x, *y]).collect::<Vec<_>>(),
        });
        match value {
            Value::Object(map) => map,
            _ => Map::new(),
        }
    }
}

/// The outcome for one actuator.
#[derive(Debug, Clone, PartialEq)]
pub struct ActuatorCalibration {
    /// Actuator number.
    pub actuator: usize,
    /// The inverse filter.
    pub filter: KirkebyFilter,
    /// Flatness of the verification response over the check band, on the calibration's own smoothing (the
    /// verdict: [`crate::quality::smoothed_flatness`]).
    pub flatness: Flatness,
    /// The same on pyfar's standard smoothing ([`crate::quality::standard_flatness`]), as others would report it
    /// (part of the verdict with [`CalibrationConfig::standard_smoothing`]).
    pub standard_flatness: Flatness,
    /// Attempts made (1 when the first passed).
    pub attempts: u32,
    /// `Valid` when flat within the limit (on both smoothings with [`CalibrationConfig::standard_smoothing`]),
    /// `Failed` otherwise.
    pub status: Status,
}

impl std::fmt::Display for ActuatorCalibration {
    /// One line: `actuator 3: valid (flat within 1.20 dB; 1.50 dB on pyfar's standard smoothing; 1 attempt(s), boost
    /// 12.0 dB)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "actuator {}: {} (flat within {:.2} dB; {:.2} dB on pyfar's standard smoothing; {} attempt(s), boost \
             {:.1} dB)",
            self.actuator,
            self.status.as_str(),
            self.flatness.deviation_db(),
            self.standard_flatness.deviation_db(),
            self.attempts,
            self.filter.max_boost_db
        )
    }
}

/// The grid column a calibration row of `kind` is written in.
fn kind_ix(kind: RowKind) -> u32 {
    match kind {
        RowKind::Filter => FILTER_IX,
        RowKind::Response => RESPONSE_IX,
        RowKind::Verification => VERIFY_IX,
    }
}

/// The row of the calibration dataset `dataset` that holds `kind` for `actuator`: by its `kind` column, or, in a
/// calibration written before the column existed (no row has a kind), by the grid column it was written in.
pub fn calibration_row(dataset: &Dataset, kind: RowKind, actuator: u16) -> Option<usize> {
    let rows = dataset.rows();
    let by_kind = rows.iter().position(|m| m.actuator == actuator && m.kind == Some(kind));
    if by_kind.is_some() || rows.iter().any(|m| m.kind.is_some()) {
        return by_kind;
    }
    rows.iter().position(|m| m.actuator == actuator && m.ix == kind_ix(kind))
}

/// Acquisitions per calibration measurement at most (the first included).
pub const MEASURE_ATTEMPTS: u32 = 8;

/// Calibrates every actuator not yet committed in `out` (all of them for a fresh run), committing each.
/// `sites_m[a]` is actuator `a`'s magnet position, m.
///
/// # Errors
/// [`RecipeError::Interrupted`] when stopped on request (what was committed stays); device, store and
/// configuration errors as [`RecipeError`] says.
pub fn calibrate(
    rig: &mut Rig,
    sites_m: &[(f64, f64)],
    cfg: &CalibrationConfig,
    out: &Output,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<Vec<ActuatorCalibration>, RecipeError> {
    if sites_m.len() != rig.wiring.actuator_channels.len() {
        return Err(RecipeError::Config(format!(
            "{} actuator positions for {} wired actuators",
            sites_m.len(),
            rig.wiring.actuator_channels.len()
        )));
    }
    let settings = Settings {
        max_velocity_m_s: cfg.max_velocity_m_s,
        retry: RetryPolicy { max_attempts: MEASURE_ATTEMPTS },
        aim: cfg.aim,
        seed: cfg.seed,
        recovery: cfg.recovery,
    };
    let mut plan = CalibrationPlan::new(sites_m, cfg);
    run(&mut plan, settings, rig, out, control, observer)?;
    Ok(plan.results)
}

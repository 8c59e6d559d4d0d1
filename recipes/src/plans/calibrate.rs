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
//! Taps are stored as f32: 7 significant digits, a relative error of 6e-8 (-144 dB), far below any measurement.

use metaplate_core::rig::Rig;
use metaplate_dsp::deconv::{DeconvConfig, deconvolve_with_reference};
use metaplate_dsp::equalise::{EqualiserConfig, design_equaliser};
use metaplate_dsp::kirkeby::{KirkebyConfig, KirkebyFilter};
use metaplate_dsp::sweep::SweepSpec;
use metaplate_store::{Dataset, DatasetDescription, DatasetMeta, GridSpec, IrMeta, IrRecord, RowKind, Status};
use serde_json::{Map, Value, json};

use crate::drive::{DrivePlayback, excitation};
use crate::engine::acquire::{AcquisitionProblem, RetryPolicy, acquire, record_samples};
use crate::engine::aim::{AimPolicy, aim};
use crate::engine::now_unix_us;
use crate::engine::run::Run;
use crate::engine::session::{Acquisition, Instruments, RecoveryPolicy, SessionState};
use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};
use crate::output::Output;
use metaplate_dsp::stats::median;

use crate::quality::{Flatness, smoothed_flatness};

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
    /// The paper's calibration: 3 s linear sweep 50..625 Hz (amplitude 0.5), [`DeconvConfig::calibration`],
    /// [`KirkebyConfig::calibration`], flat within +/-1 dB over 62..625 Hz, 3 attempts, 0.1 m/s range.
    fn default() -> Self {
        let deconv = DeconvConfig::calibration();
        let kirkeby = KirkebyConfig::calibration(&deconv);
        // The equaliser's settings have one home, shared with the ground truth.
        let equaliser = EqualiserConfig::calibration(kirkeby);
        Self {
            sweep: SweepSpec { f1_hz: 50.0, amplitude: 0.5, ..SweepSpec::default() },
            kirkeby,
            deconv,
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
    /// Flatness of the verification response over the check band.
    pub flatness: Flatness,
    /// Attempts made (1 when the first passed).
    pub attempts: u32,
    /// `Valid` when flat within the limit, `Failed` otherwise.
    pub status: Status,
}

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
    let meta = DatasetMeta::new(
        RECIPE,
        cfg.to_json(sites_m),
        out.scene.clone(),
        out.software_version.clone(),
        cfg.seed,
        CALIBRATION_GRID,
    )
    .with_description(DatasetDescription {
        ir_unit: "by kind: filter taps 1/(m/s per full scale); response and verification m/s per full scale".into(),
        pre_samples: u32::try_from(cfg.deconv.pre_samples).unwrap_or(u32::MAX),
    });
    let mut run = Run::open(out, meta, rig.clock.clone(), control)?;
    let total = sites_m.len();
    let is_committed = |a: usize| run.committed_keys.contains(&(FILTER_IX, a as u16));
    let done_before = (0..total).filter(|a| is_committed(*a)).count();
    let todo: Vec<usize> = (0..total).filter(|a| !is_committed(*a)).collect();
    run.start(total, done_before, observer);
    let state = run.session_state(SessionState { velocity_range_m_s: cfg.max_velocity_m_s });
    let mut instruments = Instruments::new(rig, state, cfg.recovery, control, observer)?;
    let fs = instruments.daq_rate_hz();
    let sweep = excitation(&cfg.sweep, fs)?;
    let deconv = DeconvConfig { sample_rate_hz: fs, ..cfg.deconv };
    let kirkeby = KirkebyConfig { sample_rate_hz: fs, ..cfg.kirkeby };
    let mut results = Vec::new();
    for actuator in todo {
        if control.stop_requested() {
            break;
        }
        let site = sites_m[actuator];
        let Some(result) =
            calibrate_one(&mut instruments, actuator, site, &sweep, (&deconv, &kirkeby), cfg, control, observer)?
        else {
            break;
        };
        let records = result.records(actuator, site, fs)?;
        let status = result.calibration.status.as_str();
        run.commit(&records, instruments.state(), actuator, None, status, control, observer)?;
        tracing::info!(
            actuator,
            deviation_db = result.calibration.flatness.deviation_db(),
            status,
            "actuator committed"
        );
        results.push(result.calibration);
    }
    run.finish(observer)?;
    Ok(results)
}

/// One actuator's calibration with the responses to store.
struct ActuatorMeasurement {
    calibration: ActuatorCalibration,
    /// Acquisitions repeated (gaps, underruns, clipping) over every attempt.
    acquisition_retries: u32,
    response: Vec<f64>,
    verification: Vec<f64>,
}

impl ActuatorMeasurement {
    fn records(&self, actuator: usize, (x_m, y_m): (f64, f64), fs: f64) -> Result<Vec<IrRecord>, RecipeError> {
        // Every repeat counts: design attempts after the first and repeated acquisitions.
        let retries = self.calibration.attempts.saturating_sub(1) + self.acquisition_retries;
        let rows: [(RowKind, &[f64]); 3] = [
            (RowKind::Filter, &self.calibration.filter.taps),
            (RowKind::Response, &self.response),
            (RowKind::Verification, &self.verification),
        ];
        rows.iter()
            .map(|(kind, ir)| {
                let ix = kind_ix(*kind);
                let meta = IrMeta {
                    x_m,
                    y_m,
                    status: Some(self.calibration.status),
                    retries: Some(retries),
                    measured_at_unix_us: Some(now_unix_us()),
                    kind: Some(*kind),
                    ..IrMeta::at_grid(&CALIBRATION_GRID, ix, 0, actuator as u16, fs)?
                };
                Ok(IrRecord { meta, ir: ir.iter().map(|v| *v as f32).collect() })
            })
            .collect()
    }
}

#[allow(clippy::too_many_arguments)] // One call site; the pieces are distinct.
fn calibrate_one(
    instruments: &mut Instruments<'_>,
    actuator: usize,
    site: (f64, f64),
    sweep: &[f64],
    (deconv, kirkeby): (&DeconvConfig, &KirkebyConfig),
    cfg: &CalibrationConfig,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<Option<ActuatorMeasurement>, RecipeError> {
    let fs = deconv.sample_rate_hz;
    let mut last: Option<ActuatorMeasurement> = None;
    let mut acquisition_retries = 0;
    for attempt in 0..cfg.max_attempts.max(1) {
        if attempt > 0 {
            observer.event(&Event::Retry { unit: actuator, attempt, reason: "not flat enough".into() });
        }
        aim(instruments, site, (cfg.seed, actuator as u64, attempt), &cfg.aim, control, observer)?;
        // The response: the raw sweep, with a tail for the response to ring out.
        let raw = DrivePlayback::new(sweep, 1, deconv.ir_len, None)?;
        let Some(acq) = measure(instruments, &raw, actuator, &mut acquisition_retries, control, observer)? else {
            return Ok(None);
        };
        let response = to_response(&acq, deconv, instruments)?;
        let mut in_band = in_band_magnitudes(&response, fs, cfg.check_band_hz)?;
        let reference_gain = median(&mut in_band).filter(|g| *g > 0.0).ok_or_else(|| {
            RecipeError::Config(format!("actuator {actuator}: no response in the band (is it connected?)"))
        })?;
        let normalised: Vec<f64> = response.iter().map(|v| v / reference_gain).collect();
        // The broadband response, with the plate's narrow driving-point modes averaged out, is what is flattened.
        let equaliser = design_equaliser(
            &normalised,
            &EqualiserConfig {
                kirkeby: *kirkeby,
                fraction: cfg.smoothing_fraction,
                band_hz: cfg.check_band_hz,
                tolerance_db: cfg.design_tolerance_db,
                max_designs: cfg.max_designs,
            },
        )?;
        let (predicted_db, designs) = (equaliser.predicted_deviation_db(), equaliser.designs);
        let filter = equaliser.filter;
        // Verification: the sweep through the filter; the loopback carries the modelling delay, so the result is the
        // compensated response about time 0.
        let compensated = DrivePlayback::new(sweep, 1, deconv.ir_len + filter.taps.len(), Some(&filter))?;
        let Some(acq) = measure(instruments, &compensated, actuator, &mut acquisition_retries, control, observer)?
        else {
            return Ok(None);
        };
        let verification = to_response(&acq, deconv, instruments)?;
        let flat = smoothed_flatness(&verification, fs, cfg.check_band_hz, cfg.smoothing_fraction)?;
        let pass = flat.deviation_db() <= cfg.max_deviation_db;
        tracing::info!(
            actuator,
            attempt,
            deviation_db = flat.deviation_db(),
            predicted_db,
            designs,
            boost_db = filter.max_boost_db,
            "verified"
        );
        let status = if pass { Status::Valid } else { Status::Failed };
        let measured = ActuatorMeasurement {
            calibration: ActuatorCalibration { actuator, filter, flatness: flat, attempts: attempt + 1, status },
            acquisition_retries,
            response,
            verification,
        };
        if pass {
            return Ok(Some(measured));
        }
        last = Some(measured);
    }
    last.map(Some).ok_or_else(|| RecipeError::Internal("no calibration attempt was made".into()))
}

/// Magnitudes of `ir`'s spectrum at the bins inside `band_hz`.
fn in_band_magnitudes(ir: &[f64], fs: f64, band_hz: (f64, f64)) -> Result<Vec<f64>, RecipeError> {
    let n = metaplate_dsp::fft::fast_len(ir.len())?;
    let spectrum = metaplate_dsp::fft::forward(ir, n)?;
    Ok(spectrum
        .iter()
        .enumerate()
        .filter(|(k, _)| (band_hz.0..=band_hz.1).contains(&metaplate_dsp::fft::bin_freq_hz(*k, n, fs)))
        .map(|(_, c)| c.norm())
        .collect())
}

/// Plays `playback` on `actuator`'s channel and records it whole, with the engine's retry policy at
/// [`MEASURE_ATTEMPTS`] (gaps and underruns repeated, clipping widening the velocity range); adds the repeats to
/// `retries`. A recording still clipped at the widest range is kept (the verification judges it); `None` when
/// abandoned on request.
///
/// # Errors
/// [`RecipeError::Device`] when every recording had a gap; device errors as [`RecipeError`] says.
fn measure(
    instruments: &mut Instruments<'_>,
    playback: &DrivePlayback,
    actuator: usize,
    retries: &mut u32,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<Option<Acquisition>, RecipeError> {
    let fs = instruments.daq_rate_hz();
    let buffers = playback.audio_buffers(&instruments.rig.wiring, actuator, fs)?;
    let record = record_samples(playback, fs);
    let policy = RetryPolicy { max_attempts: MEASURE_ATTEMPTS };
    let Some(acquired) = acquire(instruments, &buffers, record, policy, actuator, control, observer)? else {
        return Ok(None);
    };
    *retries += acquired.attempts - 1;
    if acquired.problem == Some(AcquisitionProblem::Gap) {
        return Err(RecipeError::Device(format!(
            "actuator {actuator}: {MEASURE_ATTEMPTS} recordings in a row had gaps"
        )));
    }
    Ok(Some(acquired.acquisition))
}

/// Acquisitions per calibration measurement at most (the first included).
pub const MEASURE_ATTEMPTS: u32 = 8;

/// The response, m/s per full scale, from a recording: velocity (V times the range's m/s per V) over loopback (V
/// over the loopback's V per full scale).
fn to_response(
    acq: &Acquisition,
    deconv: &DeconvConfig,
    instruments: &Instruments<'_>,
) -> Result<Vec<f64>, RecipeError> {
    let volts_per_fs = instruments.rig.wiring.loopback_volts_per_full_scale;
    let ir = deconvolve_with_reference(&acq.recording.velocity_v, &acq.recording.loopback_v, deconv)?;
    Ok(ir.iter().map(|v| v * acq.scale.m_s_per_v * volts_per_fs).collect())
}

/// A calibration read back for a scan: one inverse filter per actuator and a hash that identifies it.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Inverse filter of each actuator, indexed by actuator.
    pub filters: Vec<KirkebyFilter>,
    /// Status of each actuator's calibration.
    pub statuses: Vec<Status>,
    /// SHA-256 over the calibration's configuration hash and batch checksums, `"sha256:<hex>"`: a scan stores it,
    /// and a resumed scan refuses a different one.
    pub content_hash: String,
}

impl Calibration {
    /// Reads and verifies (checksums) the calibration dataset in `dir`, expecting `actuators` actuators.
    ///
    /// # Errors
    /// [`RecipeError::Store`] for an unreadable or corrupt dataset; [`RecipeError::Calibration`] for one that is not
    /// a calibration, lacks an actuator or has the wrong number of them.
    pub fn load(dir: &std::path::Path, actuators: usize) -> Result<Self, RecipeError> {
        let bad = |reason: String| RecipeError::Calibration { dir: dir.display().to_string(), reason };
        let dataset = Dataset::open(dir)?;
        let manifest = dataset.manifest();
        if manifest.meta.recipe != RECIPE {
            return Err(bad(format!("is a `{}` dataset, not a calibration", manifest.meta.recipe)));
        }
        let delay = manifest
            .meta
            .config
            .get("kirkeby")
            .and_then(|k| k.get("modelling_delay_samples"))
            .and_then(Value::as_u64)
            .ok_or_else(|| bad("its configuration lacks kirkeby.modelling_delay_samples".into()))?;
        let band = manifest
            .meta
            .config
            .get("check_band_hz")
            .and_then(Value::as_array)
            .and_then(|b| Some((b.first()?.as_f64()?, b.get(1)?.as_f64()?)))
            .ok_or_else(|| bad("its configuration lacks check_band_hz".into()))?;
        let fs = dataset.sample_rate_hz();
        let mut filters = Vec::with_capacity(actuators);
        let mut statuses = Vec::with_capacity(actuators);
        for a in 0..actuators {
            let key = a as u16;
            let filter_row = calibration_row(&dataset, RowKind::Filter, key);
            let (Some(taps), Some(meta)) =
                (filter_row.and_then(|r| dataset.row_ir(r)), filter_row.and_then(|r| dataset.rows().get(r)))
            else {
                return Err(bad(format!("actuator {a} is not calibrated (run calibrate again with --resume)")));
            };
            let taps: Vec<f64> = taps.iter().map(|v| f64::from(*v)).collect();
            let response = calibration_row(&dataset, RowKind::Response, key).and_then(|r| dataset.row_ir(r));
            let max_boost_db = match response {
                Some(response) => boost_db(&taps, response, fs, band)?,
                None => return Err(bad(format!("actuator {a}'s measured response is missing"))),
            };
            filters.push(KirkebyFilter {
                taps,
                sample_rate_hz: fs,
                modelling_delay_samples: delay as usize,
                max_boost_db,
            });
            statuses.push(meta.status.unwrap_or(Status::Failed));
        }
        if dataset.actuators().iter().any(|a| usize::from(*a) >= actuators) {
            return Err(bad(format!("holds more actuators than the {actuators} wired")));
        }
        let mut identity = manifest.config_hash.clone();
        for batch in &manifest.batches {
            identity.push('\n');
            identity.push_str(&batch.checksum);
        }
        Ok(Self { filters, statuses, content_hash: metaplate_store::sha256(identity.as_bytes()) })
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

/// `20 log10(max |H| max |C_n|)`, dB, with `C_n` the response normalised by its median in-band gain as the design
/// saw it: the filter's boost, as [`KirkebyFilter::max_boost_db`] defines it.
fn boost_db(taps: &[f64], response: &[f32], fs: f64, band_hz: (f64, f64)) -> Result<f64, RecipeError> {
    let response: Vec<f64> = response.iter().map(|v| f64::from(*v)).collect();
    let reference_gain = median(&mut in_band_magnitudes(&response, fs, band_hz)?).unwrap_or(0.0);
    let n = metaplate_dsp::fft::fast_len(2 * taps.len().max(response.len()))?;
    let peak = |x: &[f64]| -> Result<f64, RecipeError> {
        Ok(metaplate_dsp::fft::forward(x, n)?.iter().map(|c| c.norm()).fold(0.0, f64::max))
    };
    let db = 20.0 * (peak(taps)? * peak(&response)? / reference_gain).log10();
    if db.is_finite() { Ok(db) } else { Err(RecipeError::Config("a calibration filter or response is zero".into())) }
}

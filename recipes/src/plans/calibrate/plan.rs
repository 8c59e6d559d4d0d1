//! The calibration as a plan: per actuator, attempts of two steps each (the response, aimed at the magnet; then the
//! verification through the filter designed from it), until the verification is flat or the attempts run out.
//! Every step waits for the last one's result, so nothing overlaps; a stop is honoured between actuators.

use std::collections::{BTreeSet, VecDeque};

use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::equalise::EqualiserConfig;
use metaplate_dsp::kirkeby::{KirkebyConfig, KirkebyFilter};
use metaplate_store::{DatasetDescription, DatasetMeta, IrMeta, IrRecord, RowKind, Status};

use crate::drive::{DrivePlayback, excitation};
use crate::engine::acquire::{AcquisitionProblem, record_samples};
use crate::engine::aim::Aimed;
use crate::engine::now_unix_us;
use crate::engine::plan::{AimAt, Lab, Next, Plan, Step, Verdict};
use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::output::Output;
use crate::plans::calibrate::processing::{CalibrationProcessor, Phase, Processed, Recorded};
use crate::plans::calibrate::{
    ActuatorCalibration, CALIBRATION_GRID, CalibrationConfig, FILTER_IX, MEASURE_ATTEMPTS, RECIPE, kind_ix,
};

/// The actuator being calibrated.
struct InProgress {
    actuator: usize,
    /// The attempt (0 for the first).
    attempt: u32,
    /// The step to take next.
    phase: Phase,
    /// Acquisitions repeated (gaps, underruns, clipping) over every attempt.
    acquisition_retries: u32,
    /// The attempt's measured response and filter, once designed.
    designed: Option<(Vec<f64>, KirkebyFilter)>,
}

/// The calibration's plan state.
pub(super) struct CalibrationPlan<'a> {
    sites_m: &'a [(f64, f64)],
    cfg: &'a CalibrationConfig,
    /// Actuators not yet committed, in order.
    todo: VecDeque<usize>,
    current: Option<InProgress>,
    /// The calibration sweep at the DAQ rate (set up with the rig).
    sweep: Vec<f64>,
    ir_len: usize,
    fs: f64,
    /// The actuators committed by this run.
    pub results: Vec<ActuatorCalibration>,
}

impl<'a> CalibrationPlan<'a> {
    pub(super) fn new(sites_m: &'a [(f64, f64)], cfg: &'a CalibrationConfig) -> Self {
        Self {
            sites_m,
            cfg,
            todo: VecDeque::new(),
            current: None,
            sweep: Vec::new(),
            ir_len: cfg.deconv.ir_len,
            fs: 0.0,
            results: Vec::new(),
        }
    }

    fn step(&self, current: &InProgress) -> Step<Phase> {
        let aim = (current.phase == Phase::Response)
            .then(|| AimAt { position_m: self.sites_m[current.actuator], visit: current.attempt });
        Step { unit: current.actuator, aim, detail: current.phase }
    }

    /// The three rows of a settled actuator: filter, response and verification at the magnet.
    fn records(
        &self,
        calibration: &ActuatorCalibration,
        retries: u32,
        response: &[f64],
        verification: &[f64],
    ) -> Result<Vec<IrRecord>, RecipeError> {
        let (x_m, y_m) = self.sites_m[calibration.actuator];
        let rows: [(RowKind, &[f64]); 3] = [
            (RowKind::Filter, &calibration.filter.taps),
            (RowKind::Response, response),
            (RowKind::Verification, verification),
        ];
        rows.iter()
            .map(|(kind, ir)| {
                let meta = IrMeta {
                    x_m,
                    y_m,
                    status: Some(calibration.status),
                    retries: Some(retries),
                    measured_at_unix_us: Some(now_unix_us()),
                    kind: Some(*kind),
                    ..IrMeta::at_grid(&CALIBRATION_GRID, kind_ix(*kind), 0, calibration.actuator as u16, self.fs)?
                };
                Ok(IrRecord { meta, ir: ir.iter().map(|v| *v as f32).collect() })
            })
            .collect()
    }
}

impl Plan for CalibrationPlan<'_> {
    type Detail = Phase;
    type Processor = CalibrationProcessor;

    fn aim_points(&self) -> Vec<(f64, f64)> {
        self.sites_m.to_vec()
    }

    fn meta(&self, out: &Output) -> DatasetMeta {
        DatasetMeta::new(
            RECIPE,
            self.cfg.to_json(self.sites_m),
            out.scene.clone(),
            out.software_version.clone(),
            self.cfg.seed,
            CALIBRATION_GRID,
        )
        .with_description(DatasetDescription {
            ir_unit: "by kind: filter taps 1/(m/s per full scale); response and verification m/s per full scale".into(),
            pre_samples: u32::try_from(self.cfg.deconv.pre_samples).unwrap_or(u32::MAX),
        })
    }

    fn start(&mut self, committed: &BTreeSet<(u32, u16)>) -> (usize, usize) {
        let total = self.sites_m.len();
        self.todo = (0..total).filter(|a| !committed.contains(&(FILTER_IX, *a as u16))).collect();
        (total, total - self.todo.len())
    }

    fn setup(&mut self, instruments: &Instruments<'_>) -> Result<CalibrationProcessor, RecipeError> {
        let fs = instruments.daq_rate_hz();
        let cfg = self.cfg;
        self.sweep = excitation(&cfg.sweep, fs)?;
        self.fs = fs;
        let deconv = DeconvConfig { sample_rate_hz: fs, ..cfg.deconv };
        self.ir_len = deconv.ir_len;
        let equaliser = EqualiserConfig {
            kirkeby: KirkebyConfig { sample_rate_hz: fs, ..cfg.kirkeby },
            fraction: cfg.smoothing_fraction,
            band_hz: cfg.check_band_hz,
            tolerance_db: cfg.design_tolerance_db,
            max_designs: cfg.max_designs,
            standard: cfg.standard_smoothing,
        };
        let volts_per_fs = instruments.rig.wiring.loopback_volts_per_full_scale;
        Ok(CalibrationProcessor { deconv, equaliser, volts_per_fs })
    }

    fn next(&mut self, in_flight: bool) -> Next<Phase> {
        if in_flight {
            return Next::Wait;
        }
        if let Some(current) = &self.current {
            return Next::Step(self.step(current));
        }
        let Some(actuator) = self.todo.pop_front() else {
            return Next::Done;
        };
        let current =
            InProgress { actuator, attempt: 0, phase: Phase::Response, acquisition_retries: 0, designed: None };
        let step = self.step(&current);
        self.current = Some(current);
        Next::Step(step)
    }

    fn mid_unit(&self) -> bool {
        self.current.is_some()
    }

    /// Plays the raw sweep (the response) or the sweep through the attempt's filter (the verification) on the
    /// actuator's channel, recorded whole with the engine's retry policy ([`MEASURE_ATTEMPTS`]); a recording still
    /// clipped at the widest range is kept (the verification judges it).
    ///
    /// # Errors
    /// [`RecipeError::Device`] when every recording had a gap.
    fn record(
        &mut self,
        step: &Step<Phase>,
        _aimed: Option<Aimed>,
        _processor: &CalibrationProcessor,
        lab: &mut Lab<'_, '_>,
    ) -> Result<Option<Recorded>, RecipeError> {
        let actuator = step.unit;
        let playback = match (step.detail, self.current.as_ref().and_then(|c| c.designed.as_ref())) {
            // The response: the raw sweep, with a tail for the response to ring out.
            (Phase::Response, _) => DrivePlayback::new(&self.sweep, 1, self.ir_len, None)?,
            // The verification: the sweep through the filter; the loopback carries the modelling delay, so the
            // result is the compensated response about time 0.
            (Phase::Verification, Some((_, filter))) => {
                DrivePlayback::new(&self.sweep, 1, self.ir_len + filter.taps.len(), Some(filter))?
            }
            (Phase::Verification, None) => {
                return Err(RecipeError::Internal(format!("actuator {actuator}: a verification without a filter")));
            }
        };
        let fs = lab.daq_rate_hz();
        let buffers = playback.audio_buffers(lab.wiring(), actuator, fs)?;
        let Some(acquired) = lab.acquire(&buffers, record_samples(&playback, fs), actuator)? else {
            return Ok(None);
        };
        if let Some(current) = self.current.as_mut() {
            current.acquisition_retries += acquired.attempts - 1;
        }
        if acquired.problem == Some(AcquisitionProblem::Gap) {
            return Err(RecipeError::Device(format!(
                "actuator {actuator}: {MEASURE_ATTEMPTS} recordings in a row had gaps"
            )));
        }
        Ok(Some(Recorded { actuator, phase: step.detail, acquisition: acquired.acquisition }))
    }

    fn settle(&mut self, processed: Result<Processed, RecipeError>) -> Result<Verdict, RecipeError> {
        let Some(mut current) = self.current.take() else {
            return Err(RecipeError::Internal("a calibration result with no actuator in progress".into()));
        };
        let processed = processed?;
        let (Processed::Designed { actuator, .. } | Processed::Verified { actuator, .. }) = &processed;
        if *actuator != current.actuator {
            return Err(RecipeError::Internal(format!(
                "a result for actuator {actuator} while calibrating {}",
                current.actuator
            )));
        }
        match processed {
            Processed::Designed { response, filter, predicted_db, predicted_standard_db, designs, .. } => {
                tracing::debug!(
                    actuator = current.actuator,
                    predicted_db,
                    predicted_standard_db,
                    designs,
                    "inverse filter designed"
                );
                current.designed = Some((response, filter));
                current.phase = Phase::Verification;
                self.current = Some(current);
                Ok(Verdict::Continue { retry: None })
            }
            Processed::Verified { actuator, verification, flatness, standard } => {
                let Some((response, filter)) = current.designed.take() else {
                    return Err(RecipeError::Internal(format!("actuator {actuator}: verified without a filter")));
                };
                let limit = self.cfg.max_deviation_db;
                let pass = flatness.deviation_db() <= limit
                    && (!self.cfg.standard_smoothing || standard.deviation_db() <= limit);
                tracing::info!(
                    actuator,
                    attempt = current.attempt,
                    deviation_db = flatness.deviation_db(),
                    standard_deviation_db = standard.deviation_db(),
                    boost_db = filter.max_boost_db,
                    "verified"
                );
                let attempts = current.attempt + 1;
                if !pass && attempts < self.cfg.max_attempts.max(1) {
                    current.attempt = attempts;
                    current.phase = Phase::Response;
                    self.current = Some(current);
                    return Ok(Verdict::Continue { retry: Some((actuator, attempts, "not flat enough".into())) });
                }
                let status = if pass { Status::Valid } else { Status::Failed };
                let calibration =
                    ActuatorCalibration { actuator, filter, flatness, standard_flatness: standard, attempts, status };
                // Every repeat counts: design attempts after the first and repeated acquisitions.
                let retries = current.attempt + current.acquisition_retries;
                let records = self.records(&calibration, retries, &response, &verification)?;
                tracing::info!(actuator, deviation_db = calibration.flatness.deviation_db(), "actuator settled");
                self.results.push(calibration);
                Ok(Verdict::Commit { unit: actuator, records, status, snr_db: None })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quality::Flatness;

    fn filter() -> KirkebyFilter {
        KirkebyFilter { taps: vec![1.0, 0.5], sample_rate_hz: 24_000.0, modelling_delay_samples: 1, max_boost_db: 3.0 }
    }

    fn designed(actuator: usize) -> Result<Processed, RecipeError> {
        Ok(Processed::Designed {
            actuator,
            response: vec![0.25; 4],
            filter: filter(),
            predicted_db: 0.5,
            predicted_standard_db: Some(0.5),
            designs: 1,
        })
    }

    fn verified(actuator: usize, deviation_db: f64) -> Result<Processed, RecipeError> {
        let flatness = Flatness { median_db: 0.0, min_db: -deviation_db, max_db: deviation_db };
        Ok(Processed::Verified { actuator, verification: vec![0.5; 4], flatness, standard: flatness })
    }

    fn plan<'a>(sites: &'a [(f64, f64)], cfg: &'a CalibrationConfig) -> CalibrationPlan<'a> {
        let mut plan = CalibrationPlan::new(sites, cfg);
        plan.fs = 24_000.0;
        plan
    }

    const SITES: [(f64, f64); 2] = [(0.1, 0.2), (0.3, 0.4)];

    #[test]
    fn an_attempt_is_a_response_aimed_at_the_magnet_then_an_unaimed_verification() {
        let cfg = CalibrationConfig::default();
        let mut plan = plan(&SITES, &cfg);
        // Actuator 0 committed by an earlier run: only actuator 1 is left.
        assert_eq!(plan.start(&BTreeSet::from([(FILTER_IX, 0)])), (2, 1));
        let Next::Step(step) = plan.next(false) else { panic!("a step") };
        assert_eq!(
            step,
            Step { unit: 1, aim: Some(AimAt { position_m: SITES[1], visit: 0 }), detail: Phase::Response }
        );
        assert!(plan.mid_unit());
        // Every step needs the last one's result.
        assert_eq!(plan.next(true), Next::Wait);
        assert_eq!(plan.settle(designed(1)).unwrap(), Verdict::Continue { retry: None });
        let Next::Step(step) = plan.next(false) else { panic!("a step") };
        assert_eq!((step.unit, step.aim, step.detail), (1, None, Phase::Verification));
        let Verdict::Commit { unit, records, status, .. } = plan.settle(verified(1, 0.5)).unwrap() else {
            panic!("a commit")
        };
        assert_eq!((unit, status), (1, Status::Valid));
        // Filter, response and verification, at the magnet, with no retry.
        let kinds: Vec<_> = records.iter().map(|r| (r.meta.kind, r.meta.ix)).collect();
        assert_eq!(
            kinds,
            vec![(Some(RowKind::Filter), 0), (Some(RowKind::Response), 1), (Some(RowKind::Verification), 2)]
        );
        assert!(records.iter().all(|r| (r.meta.x_m, r.meta.y_m) == SITES[1] && r.meta.retries == Some(0)));
        assert_eq!(records[0].ir, vec![1.0, 0.5]);
        assert!(!plan.mid_unit());
        assert_eq!(plan.next(false), Next::Done);
        assert_eq!(plan.results.len(), 1);
    }

    #[test]
    fn a_verification_not_flat_enough_is_retried_nudged_then_committed_failed() {
        let cfg = CalibrationConfig { max_attempts: 2, max_deviation_db: 1.0, ..CalibrationConfig::default() };
        let mut plan = plan(&SITES, &cfg);
        plan.start(&BTreeSet::new());
        for attempt in 0..2u32 {
            let Next::Step(step) = plan.next(false) else { panic!("a step") };
            // Each attempt aims afresh, on its own visit (its own nudges).
            assert_eq!(step.aim.map(|a| a.visit), Some(attempt));
            plan.settle(designed(0)).unwrap();
            assert!(matches!(plan.next(false), Next::Step(Step { detail: Phase::Verification, .. })));
            let verdict = plan.settle(verified(0, 2.0)).unwrap();
            if attempt == 0 {
                assert_eq!(verdict, Verdict::Continue { retry: Some((0, 1, "not flat enough".into())) });
            } else {
                let Verdict::Commit { status, records, .. } = verdict else { panic!("a commit") };
                assert_eq!(status, Status::Failed);
                assert!(records.iter().all(|r| r.meta.retries == Some(1)));
            }
        }
        assert_eq!(plan.results[0].attempts, 2);
    }

    #[test]
    fn a_verification_flat_on_one_smoothing_only_fails_when_both_are_judged() {
        let flat = Flatness { median_db: 0.0, min_db: -0.3, max_db: 0.3 };
        let steppy = Flatness { median_db: 0.0, min_db: -1.6, max_db: 0.4 };
        for (standard_smoothing, expected) in [(true, Status::Failed), (false, Status::Valid)] {
            let cfg = CalibrationConfig { max_attempts: 1, standard_smoothing, ..CalibrationConfig::default() };
            let mut plan = plan(&SITES, &cfg);
            plan.start(&BTreeSet::new());
            plan.next(false);
            plan.settle(designed(0)).unwrap();
            plan.next(false);
            let verdict = plan
                .settle(Ok(Processed::Verified {
                    actuator: 0,
                    verification: vec![0.5; 4],
                    flatness: flat,
                    standard: steppy,
                }))
                .unwrap();
            let Verdict::Commit { status, .. } = verdict else { panic!("a commit") };
            assert_eq!(status, expected, "standard smoothing judged: {standard_smoothing}");
        }
    }

    #[test]
    fn results_out_of_turn_are_internal_errors() {
        let cfg = CalibrationConfig::default();
        let mut plan = plan(&SITES, &cfg);
        plan.start(&BTreeSet::new());
        assert!(matches!(plan.settle(designed(0)), Err(RecipeError::Internal(_))));
        plan.next(false);
        assert!(matches!(plan.settle(designed(1)), Err(RecipeError::Internal(_))));
        plan.next(false);
        // A verification before any filter was designed.
        assert!(matches!(plan.settle(verified(0, 0.1)), Err(RecipeError::Internal(_))));
    }
}

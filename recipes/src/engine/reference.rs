//! The reference check after a recovery: a committed point re-measured and compared with what was committed.

use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{ExcitationProtocol, Scheme};
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_store::{Dataset, Status, StoreError};

use crate::drive::{DrivePlayback, excitation};
use crate::engine::acquire::{RetryPolicy, acquire, record_samples};
use crate::engine::session::Instruments;
use crate::error::RecipeError;
use crate::events::{Event, Observer, RunControl};
use metaplate_dsp::accuracy::relative_error_db;

/// What the reference check re-measures and how it judges it: the narrow part of a scan's configuration it needs.
#[derive(Debug, Clone)]
pub struct ReferenceSpec {
    /// The plan's points, in order: the first committed valid or re-measured is the reference.
    pub points: Vec<usize>,
    /// The scan's protocol: its sweep, repetitions and deconvolution (their rates replaced by the DAQ's), played
    /// by one actuator alone.
    pub protocol: ExcitationProtocol,
    /// Each actuator's inverse filter, if the scan is compensated.
    pub filters: Option<Vec<KirkebyFilter>>,
    /// Deviation above which the check warns, dB.
    pub limit_db: f64,
    /// The scan's SNR gate: a re-measure below it (a dropout in the middle) is repeated, not compared.
    pub min_snr_db: f64,
    /// The scan's retry policy for the re-measure's acquisitions.
    pub retry: RetryPolicy,
}

/// After a device recovery, before the next point, a scan re-measures one committed point (the plan's first one
/// committed valid or re-measured, one actuator) and compares it with what was committed: the check the issue asks
/// of every recovery (reconnect, drain, re-apply settings, re-measure a reference point), so that a rig that came
/// back different (a setting not restored, a moved beam or plate) is reported instead of silently measured.
///
/// The reference is re-measured with one actuator alone, the scan protocol's sweep and repetitions and the
/// actuator's inverse filter: for a simultaneous protocol (Hadamard) that is the same response by superposition,
/// in the same units. The deviation is logged and reported as [`Event::ReferenceChecked`]; above
/// [`crate::engine::session::RecoveryPolicy::reference_limit_db`] it is a warning (the scan goes on: a person decides).
pub(crate) struct ReferenceCheck<'a> {
    spec: ReferenceSpec,
    /// The dataset directory holding the committed responses.
    dir: &'a std::path::Path,
    actuator: usize,
    /// Loaded at the first check.
    reference: Option<Reference>,
}

/// A committed point to re-measure: grid index, beam position (m), committed response (m/s per full scale).
type Reference = (usize, (f64, f64), Vec<f64>);

impl<'a> ReferenceCheck<'a> {
    /// The check of `spec` against the dataset in `dir`, on actuator 0.
    pub(crate) fn new(spec: ReferenceSpec, dir: &'a std::path::Path) -> Self {
        Self { spec, dir, actuator: 0, reference: None }
    }

    /// If a device was recovered since the last call, re-measures the reference point and reports the deviation;
    /// returns it, dB (`None` when nothing was recovered or nothing is committed yet to compare with).
    ///
    /// # Errors
    /// Device errors that recovery cannot fix; [`RecipeError::Store`] if the committed reference cannot be read.
    pub(crate) fn after_recovery(
        &mut self,
        instruments: &mut Instruments<'_>,
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Option<f64>, RecipeError> {
        if !instruments.recovered {
            return Ok(None);
        }
        // Cleared first: a recovery during the re-measure sets it again, and the next point checks once more.
        instruments.recovered = false;
        if self.reference.is_none() {
            self.reference = self.load()?;
        }
        let Some((point, position_m, committed)) = &self.reference else {
            tracing::info!("device recovered before any point was committed: no reference to re-measure");
            return Ok(None);
        };
        let Some(measured) = self.measure(instruments, *position_m, control, observer)? else {
            tracing::warn!(point, "the reference re-measure failed the scan's gates three times; not compared");
            return Ok(None);
        };
        let n = measured.len().min(committed.len());
        let deviation_db = relative_error_db(&measured[..n], &committed[..n])?;
        if deviation_db > self.spec.limit_db {
            tracing::warn!(
                point,
                deviation_db,
                limit_db = self.spec.limit_db,
                "after recovery the reference point differs from its committed response: check the rig"
            );
        } else {
            tracing::info!(point, deviation_db, "reference point re-measured after recovery");
        }
        observer.event(&Event::ReferenceChecked {
            point: *point,
            actuator: self.actuator,
            deviation_db,
            limit_db: self.spec.limit_db,
        });
        Ok(Some(deviation_db))
    }

    /// The plan's first point whose reference row is committed as valid or re-measured.
    fn load(&self) -> Result<Option<Reference>, RecipeError> {
        let dataset = match Dataset::open(self.dir) {
            Ok(d) => d,
            Err(StoreError::EmptyDataset { .. }) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        let key = self.actuator as u16;
        for &p in &self.spec.points {
            let (Some(meta), Some(ir)) = (dataset.meta(p as u32, key), dataset.ir(p as u32, key)) else {
                continue;
            };
            if matches!(meta.status, Some(Status::Valid | Status::ReMeasured)) {
                let ir = ir.iter().map(|v| f64::from(*v)).collect();
                return Ok(Some((p, (meta.x_m, meta.y_m), ir)));
            }
        }
        Ok(None)
    }

    /// One response of the reference actuator at `position_m`, m/s per full scale; `None` if three recordings in a
    /// row were unusable (as the retry policy judges) or failed the SNR gate, or `None` when abandoned on request.
    fn measure(
        &self,
        instruments: &mut Instruments<'_>,
        (x_m, y_m): (f64, f64),
        control: &RunControl,
        observer: &mut dyn Observer,
    ) -> Result<Option<Vec<f64>>, RecipeError> {
        const ATTEMPTS: u32 = 3;
        let fs = instruments.daq_rate_hz();
        let protocol = &self.spec.protocol;
        let sweep = excitation(&protocol.sweep, fs)?;
        let deconv = DeconvConfig { sample_rate_hz: fs, ..protocol.deconv };
        // The scan's tail: the response and the longest filter.
        let fir_len = self.spec.filters.as_ref().map_or(0, |f| f.iter().map(|k| k.taps.len()).max().unwrap_or(0));
        let filter = self.spec.filters.as_ref().and_then(|f| f.get(self.actuator));
        let playback = DrivePlayback::new(&sweep, protocol.repetitions, deconv.ir_len + fir_len, filter)?;
        let buffers = playback.audio_buffers(&instruments.rig.wiring, self.actuator, fs)?;
        let record = record_samples(&playback, fs);
        // One actuator alone whatever the scan's scheme: the protocol's sequential decoder, for one actuator.
        let alone = ExcitationProtocol { scheme: Scheme::Sequential, adaptive: None, ..protocol.clone() };
        let decoder = alone.decoder(1, &deconv)?;
        instruments.with_recovery(control, observer, |i| i.aim(x_m, y_m))?;
        for _ in 0..ATTEMPTS {
            let Some(acquired) =
                acquire(instruments, &buffers, record, self.spec.retry, self.actuator, control, observer)?
            else {
                return Ok(None);
            };
            if acquired.problem.is_some() {
                continue;
            }
            let acq = acquired.acquisition;
            // A processing failure is a bad recording (as the scan treats it), not a reason to stop the scan.
            let Ok(result) = decoder.decode_shot(&acq.recording.velocity_v, &acq.recording.loopback_v) else {
                continue;
            };
            if result.snr_db.is_some_and(|snr| snr < self.spec.min_snr_db) {
                continue;
            }
            let to_units = acq.scale.m_s_per_v * instruments.rig.wiring.loopback_volts_per_full_scale;
            return Ok(Some(result.ir.iter().map(|v| v * to_units).collect()));
        }
        Ok(None)
    }
}

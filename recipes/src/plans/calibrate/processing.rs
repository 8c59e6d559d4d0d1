//! The calibration's processing of a recording (on the engine's worker thread): the response deconvolved and its
//! Kirkeby inverse filter designed, or the verification response and its flatness.

use metaplate_dsp::deconv::{DeconvConfig, deconvolve_with_reference};
use metaplate_dsp::equalise::{EqualiserConfig, design_equaliser};
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_dsp::stats::median;

use crate::engine::plan::Processor;
use crate::engine::session::Acquisition;
use crate::error::RecipeError;
use crate::quality::{Flatness, smoothed_flatness, standard_flatness};

/// Which measurement of an attempt a recording is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Phase {
    /// The raw sweep: the response the filter is designed from.
    Response,
    /// The sweep through the filter: the compensated response that is judged.
    Verification,
}

/// A recording sent for processing.
pub(super) struct Recorded {
    pub actuator: usize,
    pub phase: Phase,
    pub acquisition: Acquisition,
}

/// What processing made of a recording.
pub(super) enum Processed {
    /// The measured response (m/s per full scale) and the filter designed from it.
    /// `predicted_db`: the equaliser's predicted deviation on the project's smoothing, `predicted_standard_db` on
    /// pyfar's (when judged).
    Designed {
        actuator: usize,
        response: Vec<f64>,
        filter: KirkebyFilter,
        predicted_db: f64,
        predicted_standard_db: Option<f64>,
        designs: usize,
    },
    /// The verification response (m/s per full scale) and its flatness over the check band.
    /// `flatness` on the project's smoothing (the verdict), `standard` on pyfar's (reported).
    Verified { actuator: usize, verification: Vec<f64>, flatness: Flatness, standard: Flatness },
}

/// The calibration's processing at the DAQ rate: deconvolution, the equaliser's design and the flatness judged over
/// the check band.
pub(super) struct CalibrationProcessor {
    pub deconv: DeconvConfig,
    pub equaliser: EqualiserConfig,
    /// The loopback's volts per full scale (to convert responses to m/s per full scale).
    pub volts_per_fs: f64,
}

impl Processor for CalibrationProcessor {
    type Recorded = Recorded;
    type Processed = Result<Processed, RecipeError>;

    fn process(&self, recorded: Recorded) -> Result<Processed, RecipeError> {
        let Recorded { actuator, phase, acquisition } = recorded;
        let response = self.to_response(&acquisition)?;
        let fs = self.deconv.sample_rate_hz;
        let band_hz = self.equaliser.band_hz;
        match phase {
            Phase::Response => {
                let mut in_band = in_band_magnitudes(&response, fs, band_hz)?;
                let reference_gain = median(&mut in_band).filter(|g| *g > 0.0).ok_or_else(|| {
                    RecipeError::Config(format!("actuator {actuator}: no response in the band (is it connected?)"))
                })?;
                let normalised: Vec<f64> = response.iter().map(|v| v / reference_gain).collect();
                // The broadband response, with the plate's narrow driving-point modes averaged out, is what is
                // flattened.
                let equaliser = design_equaliser(&normalised, &self.equaliser)?;
                Ok(Processed::Designed {
                    actuator,
                    response,
                    predicted_db: equaliser.predicted_deviation_db(),
                    predicted_standard_db: equaliser.predicted_standard_deviation_db(),
                    designs: equaliser.designs,
                    filter: equaliser.filter,
                })
            }
            Phase::Verification => {
                let flatness = smoothed_flatness(&response, fs, band_hz, self.equaliser.fraction)?;
                let standard = standard_flatness(&response, fs, band_hz, self.equaliser.fraction)?;
                Ok(Processed::Verified { actuator, verification: response, flatness, standard })
            }
        }
    }
}

impl CalibrationProcessor {
    /// The response, m/s per full scale, from a recording: velocity (V times the range's m/s per V) over loopback
    /// (V over the loopback's V per full scale).
    fn to_response(&self, acq: &Acquisition) -> Result<Vec<f64>, RecipeError> {
        let ir = deconvolve_with_reference(&acq.recording.velocity_v, &acq.recording.loopback_v, &self.deconv)?;
        Ok(ir.iter().map(|v| v * acq.scale.m_s_per_v * self.volts_per_fs).collect())
    }
}

/// Magnitudes of `ir`'s spectrum at the bins inside `band_hz`.
pub(super) fn in_band_magnitudes(ir: &[f64], fs: f64, band_hz: (f64, f64)) -> Result<Vec<f64>, RecipeError> {
    let n = metaplate_dsp::fft::fast_len(ir.len())?;
    let spectrum = metaplate_dsp::fft::forward(ir, n)?;
    Ok(spectrum
        .iter()
        .enumerate()
        .filter(|(k, _)| (band_hz.0..=band_hz.1).contains(&metaplate_dsp::fft::bin_freq_hz(*k, n, fs)))
        .map(|(_, c)| c.norm())
        .collect())
}

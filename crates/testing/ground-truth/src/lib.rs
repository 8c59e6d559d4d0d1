//! The ground truth of a simulated plate as the paper measured it: the one fixture of the wave-field crates'
//! (`metaplate-control`, `metaplate-analysis`) tests, benchmarks and examples, and a dev-dependency only.
//!
//! The paper measured every Green's function with the actuators' Kirkeby compensation in the chain (Materials and
//! Methods), so what it focused with and analysed is plate x voice coil x inverse filter, not the plate's response to
//! a force. The magnet responses fall about 30 dB over the band; compensation lifts the short, high-frequency waves,
//! which nearly halves time reversal's half-maximum pixel area on the metamaterial plate (9.22 cm^2 uncompensated,
//! 4.99 compensated) and leaves the inverse filter's, which solves per bin, alone (2.51 and 2.53 cm^2).
//!
//! [`GroundTruth::new`] does what `metaplate calibrate` and `metaplate scan` do on the mock lab, without noise:
//! 1. the plate model's Green's functions (velocity per unit force) at the measured points and at each actuator's
//!    driving point (its magnet), from [`metaplate_plate::greens_functions`] and its cache;
//! 2. through each actuator's voice coil (its linear part, [`VoiceCoil::frequency_response`] at the lab's audio
//!    rate), giving velocity per unit drive;
//! 3. per actuator, the driving-point response normalised by its median in-band gain, equalised by
//!    [`design_equaliser`] with the calibration recipe's settings ([`CompensationConfig::calibration`], over
//!    `EqualiserConfig::calibration`, the one home of the paper's calibration settings);
//! 4. every response through its actuator's filter, the filter's modelling delay removed, cut to the request's
//!    length with a 10 ms fade-out.
//!
//! Steps 2 and 4 multiply spectra on an FFT at least as long as response plus filter, so the filter's convolution is
//! linear; the coil's response is applied on the same grid, which wraps its ring-down (under 0.1 s for a 70 Hz
//! suspension with Q 2) around a period of about 0.85 s, far below the plate's own truncation.
//!
//! [`GroundTruth::propagation`] hands the result over as control's
//! [`PropagationMatrices`](metaplate_control::PropagationMatrices), the form the focusing and the analyses take;
//! [`GroundTruth::builtin`] does the same for a built-in scene, and [`GroundTruthOptions`]' default is the paper's
//! chain (0.5 s at 2 kHz, model band 40 to 700 Hz, compensated as the calibration recipe does it).

use std::path::Path;

use num_complex::Complex64;

use metaplate_control::{ControlError, PropagationMatrices};
use metaplate_core::scene::{Scene, SceneError};
use metaplate_dsp::equalise::{Equaliser, EqualiserConfig, design_equaliser};
use metaplate_dsp::kirkeby::KirkebyConfig;
use metaplate_dsp::{DspError, fft, window};
use metaplate_plate::actuator::VoiceCoil;
use metaplate_plate::{
    EntrySettings, GreensFunctions, GreensRequest, ModelOptions, PlateError, greens_functions, greens_functions_within,
};

/// Errors of the ground truth, each from the layer that raised it.
#[derive(Debug, thiserror::Error)]
pub enum GroundTruthError {
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The plate model or its cache failed.
    #[error(transparent)]
    Plate(#[from] PlateError),
    /// A signal-processing step (FFT, equaliser design) refused its input.
    #[error(transparent)]
    Dsp(#[from] DspError),
    /// The propagation matrices could not be built.
    #[error(transparent)]
    Control(#[from] ControlError),
    /// The options contradict each other.
    #[error("invalid {name}: {reason}")]
    InvalidOption {
        /// The option's name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// An actuator's driving point shows no response in the compensation band (so nothing to equalise).
    #[error("actuator {actuator}: no response at its driving point in the compensation band")]
    NoResponse {
        /// Scene index of the actuator.
        actuator: usize,
    },
}

/// How the actuators are compensated.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationConfig {
    /// The equaliser; its Kirkeby sample rate must be the Green's functions' and its response delay 0 (the model's
    /// responses are causal).
    pub equaliser: EqualiserConfig,
}

impl CompensationConfig {
    /// The calibration recipe's settings (`metaplate calibrate`: Kirkeby inverse of the third-octave-smoothed
    /// magnet response, flat within 0.25 dB predicted over 62 to 625 Hz on the project's and pyfar's standard
    /// smoothing, Kirkeby band 50 to 710 Hz, at most 16 designs) at `sample_rate_hz`, with the filter's length and
    /// modelling delay kept in seconds (341 ms, 20 ms). The model's band (40 to 700 Hz by default, tapered from 630
    /// Hz) ends below where the standard window at 625 Hz reaches (701.5 Hz): there the standard smoothing sees the
    /// model's taper, above the analyses' band.
    ///
    /// Valid range: `sample_rate_hz` above 1820 Hz (twice the regularisation's upper corner, 910 Hz).
    pub fn calibration(sample_rate_hz: f64) -> Self {
        let recipe = KirkebyConfig::calibration_default();
        let scale = sample_rate_hz / recipe.sample_rate_hz;
        let kirkeby = KirkebyConfig {
            sample_rate_hz,
            fir_len: ((recipe.fir_len as f64 * scale).round() as usize).max(2),
            modelling_delay_samples: (recipe.modelling_delay_samples as f64 * scale).round() as usize,
            response_delay_samples: 0,
            ..recipe
        };
        Self { equaliser: EqualiserConfig::calibration(kirkeby) }
    }
}

/// What ground truth to compute.
///
/// Valid range: as [`GreensRequest`] for `duration_s`, `sample_rate_hz` and `model_band_hz`; a compensation whose
/// band lies inside `model_band_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundTruthOptions {
    /// The plate model's options.
    pub model: ModelOptions,
    /// Band the model computes, Hz (zero outside, tapered just inside).
    pub model_band_hz: (f64, f64),
    /// Length of each response, s.
    pub duration_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// The actuators' compensation; `None` for the uncompensated chain (voice coil and plate, as an uncalibrated
    /// scan measures it).
    pub compensation: Option<CompensationConfig>,
    /// The cache entry to cut the plate's responses from when its bins include this model band's
    /// ([`greens_functions_within`]: bit for bit the same responses); `None` for an entry of their own.
    pub cache_entry: Option<EntrySettings>,
}

impl Default for GroundTruthOptions {
    /// The paper's chain: 0.5 s at 2 kHz (the focusing band, 75 to 400 Hz, lies far below 1 kHz), model band 40 to
    /// 700 Hz, compensated as the calibration recipe does it; the plate's responses cut from the mock lab's default
    /// cache entry (24 kHz DAQ, 40 to 800 Hz, 0.5 s), which scans of the same plate compute anyway.
    fn default() -> Self {
        let sample_rate_hz = 2000.0;
        Self {
            model: ModelOptions::default(),
            model_band_hz: (40.0, 700.0),
            duration_s: 0.5,
            sample_rate_hz,
            compensation: Some(CompensationConfig::calibration(sample_rate_hz)),
            cache_entry: Some(EntrySettings { band_hz: (40.0, 800.0), duration_s: 0.5, sample_rate_hz: 24_000.0 }),
        }
    }
}

/// A plate's ground truth: responses from each actuator's drive to the plate's velocity at every measured point.
#[derive(Debug, Clone)]
pub struct GroundTruth {
    /// The scene.
    pub scene: Scene,
    /// Responses at the scene's measured points, point-major, in m/s per unit drive (through the compensation when
    /// there is one: then about the actuator's median in-band gain across the band).
    pub responses: GreensFunctions,
    /// The same chain at the actuators' driving points (on the magnets, where the calibration aims the beam):
    /// point `k` is actuator k's own (flat index `grid.len() + k`), with every actuator's response there.
    pub driving_points: GreensFunctions,
    /// Each actuator's equaliser, in actuator order; empty without compensation.
    pub equalisers: Vec<Equaliser>,
}

impl GroundTruth {
    /// The ground truth of the built-in scene `name` (see [`GroundTruth::new`]).
    ///
    /// # Errors
    /// [`GroundTruthError::Scene`] for an unknown name; otherwise as [`GroundTruth::new`].
    pub fn builtin(
        name: &str,
        options: &GroundTruthOptions,
        cache_dir: Option<&Path>,
    ) -> Result<Self, GroundTruthError> {
        Self::new(Scene::builtin(name)?, options, cache_dir)
    }

    /// The ground truth of `scene` at its measured points for all its actuators; the plate model's Green's functions
    /// come from `cache_dir` when they are there (and are stored there otherwise).
    ///
    /// # Errors
    /// [`GroundTruthError::Plate`] from the model or the cache, [`GroundTruthError::Dsp`] from the equaliser design
    /// (a configuration outside its range), [`GroundTruthError::NoResponse`] for an actuator without response in
    /// the compensation band.
    pub fn new(scene: Scene, options: &GroundTruthOptions, cache_dir: Option<&Path>) -> Result<Self, GroundTruthError> {
        if let Some(c) = &options.compensation {
            check_compensation(c, options)?;
        }
        let grid_len = scene.grid.len();
        let measured = scene.measured_points();
        let n_act = scene.actuators.len();
        // One request for the measured points and the driving points (index grid_len + k): one model solve.
        let request = GreensRequest {
            points: measured.iter().copied().chain((0..n_act).map(|k| grid_len + k)).collect(),
            actuators: (0..n_act).collect(),
            band_hz: options.model_band_hz,
            duration_s: options.duration_s,
            sample_rate_hz: options.sample_rate_hz,
        };
        let force = match &options.cache_entry {
            Some(entry) => greens_functions_within(&scene, &options.model, &request, entry, cache_dir)?,
            None => greens_functions(&scene, &options.model, &request, cache_dir)?,
        };
        let ir_len = force.ir_len;
        let fs = force.sample_rate_hz;
        let delay = options.compensation.as_ref().map_or(0, |c| c.equaliser.kirkeby.modelling_delay_samples);
        let fir_len = options.compensation.as_ref().map_or(1, |c| c.equaliser.kirkeby.fir_len);
        let n = fft::fast_len(ir_len + fir_len)?;
        let freqs: Vec<f64> = (0..fft::bin_count(n)).map(|k| fft::bin_freq_hz(k, n, fs)).collect();
        // The coils as the lab runs them, at the audio rate; their response is evaluated at this grid's bins.
        let coils = VoiceCoil::for_scene(&scene, scene.audio.sample_rate_hz)?;
        let mut filters: Vec<Vec<Complex64>> = Vec::with_capacity(n_act);
        let mut equalisers = Vec::new();
        for (a, coil) in coils.iter().enumerate() {
            let coil_spectrum: Vec<Complex64> = freqs.iter().map(|&f| coil.frequency_response(f)).collect();
            let Some(compensation) = &options.compensation else {
                filters.push(coil_spectrum);
                continue;
            };
            let driving = force.ir(measured.len() + a, a).ok_or(GroundTruthError::NoResponse { actuator: a })?;
            let mut spectrum = fft::forward(driving, n)?;
            spectrum.iter_mut().zip(&coil_spectrum).for_each(|(s, c)| *s *= c);
            let mut response = fft::inverse(&spectrum, n)?;
            response.truncate(ir_len);
            let gain = median_gain(&spectrum, &freqs, compensation.equaliser.band_hz)
                .ok_or(GroundTruthError::NoResponse { actuator: a })?;
            response.iter_mut().for_each(|v| *v /= gain);
            let equaliser = design_equaliser(&response, &compensation.equaliser)?;
            let taps = fft::forward(&equaliser.filter.taps, n)?;
            filters.push(coil_spectrum.iter().zip(&taps).map(|(c, h)| c * h / gain).collect());
            equalisers.push(equaliser);
        }
        let fade = window::fade_out(((0.010 * fs).round() as usize).clamp(1, ir_len.div_ceil(10)));
        let through_chain = |points: std::ops::Range<usize>| -> Result<GreensFunctions, GroundTruthError> {
            let mut data = Vec::with_capacity(points.len() * n_act * ir_len);
            let mut spectrum = vec![Complex64::new(0.0, 0.0); fft::bin_count(n)];
            let mut chain = vec![0.0; n];
            let mut out_points = Vec::with_capacity(points.len());
            for p in points {
                out_points.push(force.points[p]);
                for (a, filter) in filters.iter().enumerate() {
                    let ir = force.ir(p, a).ok_or(GroundTruthError::NoResponse { actuator: a })?;
                    fft::forward_into(ir, n, &mut spectrum)?;
                    spectrum.iter_mut().zip(filter).for_each(|(s, h)| *s *= h);
                    fft::inverse_into(&spectrum, n, &mut chain)?;
                    let start = data.len();
                    data.extend_from_slice(&chain[delay..delay + ir_len]);
                    let tail = &mut data[start + ir_len - fade.len()..];
                    tail.iter_mut().zip(&fade).for_each(|(v, w)| *v *= w);
                }
            }
            Ok(GreensFunctions {
                sample_rate_hz: fs,
                ir_len,
                points: out_points,
                actuators: force.actuators.clone(),
                data,
            })
        };
        let responses = through_chain(0..measured.len())?;
        let driving_points = through_chain(measured.len()..measured.len() + n_act)?;
        Ok(Self { scene, responses, driving_points, equalisers })
    }

    /// `G(omega)` over the FFT bins (of the responses' own length) inside `band_hz`, every measured point, every
    /// actuator (see [`PropagationMatrices::from_impulse_responses`]).
    ///
    /// # Errors
    /// [`GroundTruthError::Control`] for a band without bins or outside the valid range.
    pub fn propagation(&self, band_hz: (f64, f64)) -> Result<PropagationMatrices, GroundTruthError> {
        let r = &self.responses;
        Ok(PropagationMatrices::from_impulse_responses(
            r.points.iter().map(|&p| p as u32).collect(),
            r.actuators.iter().map(|&a| a as u16).collect(),
            r.sample_rate_hz,
            band_hz,
            |m, n| r.ir(m, n),
        )?)
    }
}

/// The compensation must run at the responses' rate, on causal responses, inside the model's band.
fn check_compensation(c: &CompensationConfig, options: &GroundTruthOptions) -> Result<(), GroundTruthError> {
    let invalid = |name, reason| Err(GroundTruthError::InvalidOption { name, reason });
    let k = &c.equaliser.kirkeby;
    if k.sample_rate_hz != options.sample_rate_hz {
        return invalid(
            "compensation.equaliser.kirkeby.sample_rate_hz",
            format!("{} Hz, but the responses are sampled at {} Hz", k.sample_rate_hz, options.sample_rate_hz),
        );
    }
    if k.response_delay_samples != 0 {
        return invalid(
            "compensation.equaliser.kirkeby.response_delay_samples",
            format!("must be 0 (the model's responses are causal), got {}", k.response_delay_samples),
        );
    }
    let (lo, hi) = c.equaliser.band_hz;
    if !(options.model_band_hz.0 <= lo && hi <= options.model_band_hz.1) {
        return invalid(
            "compensation.equaliser.band_hz",
            format!("{lo} to {hi} Hz is not inside the model's band {:?} Hz", options.model_band_hz),
        );
    }
    Ok(())
}

/// Median magnitude of `spectrum` over the bins inside `band_hz` (`None` when there are none or it is zero).
fn median_gain(spectrum: &[Complex64], freqs: &[f64], band_hz: (f64, f64)) -> Option<f64> {
    let mut gains: Vec<f64> = spectrum
        .iter()
        .zip(freqs)
        .filter(|(_, f)| (band_hz.0..=band_hz.1).contains(*f))
        .map(|(s, _)| s.norm())
        .collect();
    metaplate_dsp::stats::median(&mut gains).filter(|g| *g > 0.0)
}

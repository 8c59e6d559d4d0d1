//! A simultaneous protocol (every actuator at once: Hadamard, interleaved) ready to play and decode, and the
//! coherent average of an adaptive protocol's rounds.

use metaplate_dsp::accuracy::estimated_error_db;
use metaplate_dsp::deconv::DeconvConfig;
use metaplate_dsp::excitation::{Adaptive, Decoder, ExcitationProtocol};
use metaplate_dsp::pipeline::ChannelResult;

use crate::drive::SimultaneousPlayback;
use crate::engine::session::{Acquisition, Instruments};
use crate::error::RecipeError;
use crate::plans::calibrate::Calibration;
use crate::plans::scan::gates::{Gates, gated, in_units};
use crate::plans::scan::points::{Outcome, Problem};

/// A simultaneous protocol ready to play and decode.
pub(crate) struct Simultaneous {
    pub playback: SimultaneousPlayback,
    pub adaptive: Option<Adaptive>,
    /// The DAQ's rate, Hz: the responses' sample rate.
    pub sample_rate_hz: f64,
}

impl Simultaneous {
    pub(crate) fn new(
        instruments: &Instruments<'_>,
        protocol: &ExcitationProtocol,
        deconv: &DeconvConfig,
        calibration: Option<&Calibration>,
    ) -> Result<Self, RecipeError> {
        let wiring = &instruments.rig.wiring;
        let fs = instruments.daq_rate_hz();
        protocol.validate(wiring.actuator_channels.len(), deconv.ir_len as f64 / fs)?;
        let fir_len = calibration.map_or(0, |c| c.filters.iter().map(|f| f.taps.len()).max().unwrap_or(0));
        // The tail holds the last response (ir_len) and the filter's own length, as in the sequential playback.
        let filters = calibration.map(|c| c.filters.as_slice());
        let playback = SimultaneousPlayback::new(protocol, wiring, fs, deconv.ir_len + fir_len, filters)?;
        Ok(Self { playback, adaptive: protocol.adaptive, sample_rate_hz: fs })
    }

    /// Every actuator's response (m/s per full scale of its compensated drive) and SNR from one round of shots,
    /// decoded by the scan's `decoder` (the protocol's).
    pub(crate) fn decode(
        &self,
        decoder: &Decoder,
        acquisitions: &[Acquisition],
        gates: &Gates,
    ) -> Result<Vec<ChannelResult>, Problem> {
        // Velocity in m/s per loopback full scale, so that the responses come out in m/s per full scale.
        let velocities: Vec<Vec<f64>> = acquisitions
            .iter()
            .map(|a| a.recording.velocity_v.iter().map(|v| v * a.scale.m_s_per_v * gates.volts_per_fs).collect())
            .collect();
        let pairs: Vec<(&[f64], &[f64])> = velocities
            .iter()
            .zip(acquisitions)
            .map(|(v, a)| (v.as_slice(), a.recording.loopback_v.as_slice()))
            .collect();
        let results = decoder.decode(&pairs).map_err(|e| Problem::Processing(e.to_string()))?;
        Ok(results.into_iter().zip(&self.playback.response_gain).map(|(r, &gain)| in_units(r, gain)).collect())
    }

    /// Outcomes of the pending actuators from decoded results (or why there are none), gated like sequential ones;
    /// an acquisition problem explains a gate failure better than the gate itself.
    pub(crate) fn outcomes(
        &self,
        pending: &[usize],
        decoded: Result<Vec<Option<ChannelResult>>, Problem>,
        problem: Option<Problem>,
        gates: &Gates,
    ) -> Vec<Outcome> {
        pending
            .iter()
            .map(|&a| match &decoded {
                Err(e) => (a, None, problem.clone().or_else(|| Some(e.clone()))),
                Ok(results) => match results.get(a).cloned().flatten() {
                    None => (a, None, problem.clone().or(Some(Problem::Processing(format!("no response {a}"))))),
                    Some(r) => gated(a, r, problem.clone(), gates, self.sample_rate_hz),
                },
            })
            .collect()
    }
}

/// Coherent average of adaptive rounds, each weighted (equal rounds: 1 each; a sequential row's shots: their
/// periods), with the noise of the average from each round's SNR, and its noise within the error band from each
/// round's (the row's error estimate): independent rounds of noise `N_i` weighted `w_i` leave `sum w_i^2 N_i / (sum
/// w_i)^2` in the average.
pub(crate) struct Averager {
    pub count: usize,
    /// Sum of the rounds' weights.
    weight: f64,
    /// Per actuator: weighted sum of the responses, and of the rounds' noise energies times their weights squared
    /// (`None` once a round had none).
    sums: Vec<(Vec<f64>, Option<f64>)>,
    /// Per actuator: the same for the noise energies within the error band.
    band_noise: Vec<Option<f64>>,
    drift_ppm: f64,
}

impl Averager {
    pub(crate) fn new(actuators: usize) -> Self {
        Self {
            count: 0,
            weight: 0.0,
            sums: vec![(Vec::new(), Some(0.0)); actuators],
            band_noise: vec![Some(0.0); actuators],
            drift_ppm: 0.0,
        }
    }

    /// Adds a round of weight 1.
    pub(crate) fn add(&mut self, results: &[ChannelResult]) {
        self.add_weighted(results, 1.0);
    }

    /// Adds a round of weight `weight` (> 0: its share of the average is `weight` over the sum of the weights).
    pub(crate) fn add_weighted(&mut self, results: &[ChannelResult], weight: f64) {
        self.count += 1;
        self.weight += weight;
        let w2 = weight * weight;
        for (((sum, noise), band_noise), r) in self.sums.iter_mut().zip(&mut self.band_noise).zip(results) {
            sum.resize(r.ir.len(), 0.0);
            sum.iter_mut().zip(&r.ir).for_each(|(s, v)| *s += weight * v);
            // A round's noise energy from its SNR: energy / 10^(snr/10).
            *noise = noise.zip(r.snr_db).map(|(n, snr)| n + w2 * energy(&r.ir) / 10f64.powf(snr / 10.0));
            *band_noise = band_noise.zip(r.noise_energy).map(|(n, e)| n + w2 * e);
        }
        self.drift_ppm = self.drift_ppm.max(results.iter().fold(0.0f64, |m, r| m.max(r.drift_ppm.abs())));
    }

    /// The weights' sum (1 before any round, so that nothing divides by 0).
    fn total(&self) -> f64 {
        if self.weight > 0.0 { self.weight } else { 1.0 }
    }

    /// The averaged responses, with the average's SNR and noise within the error band.
    pub(crate) fn averaged(&self) -> Vec<Option<ChannelResult>> {
        let w = self.total();
        (0..self.sums.len())
            .map(|a| {
                let (sum, _) = &self.sums[a];
                let ir: Vec<f64> = sum.iter().map(|v| v / w).collect();
                let snr_db = self.snr_db(&[a]).into_iter().next().flatten();
                let noise_energy = self.band_noise[a].map(|e| e / (w * w));
                Some(ChannelResult { ir, snr_db, drift_ppm: self.drift_ppm, latency_samples: 0.0, noise_energy })
            })
            .collect()
    }

    /// Estimated error of the average for each of `actuators` over the error band, dB
    /// ([`metaplate_dsp::accuracy::estimated_error_db`] of the averaged response and its noise); `None` where
    /// unknown.
    pub(crate) fn error_db(&self, actuators: &[usize], sample_rate_hz: f64) -> Vec<Option<f64>> {
        let w = self.total();
        actuators
            .iter()
            .map(|&a| {
                let (sum, _) = self.sums.get(a)?;
                let noise = (*self.band_noise.get(a)?)? / (w * w);
                let mean: Vec<f64> = sum.iter().map(|v| v / w).collect();
                estimated_error_db(&mean, noise, sample_rate_hz).ok()
            })
            .collect()
    }

    /// SNR of the average for each of `actuators`, dB; `None` where unknown.
    pub(crate) fn snr_db(&self, actuators: &[usize]) -> Vec<Option<f64>> {
        let w = self.total();
        actuators
            .iter()
            .map(|&a| {
                let (sum, noise) = self.sums.get(a)?;
                let signal = energy(sum) / (w * w);
                let noise = (*noise)? / (w * w);
                (noise > 0.0 && signal > 0.0).then(|| 10.0 * (signal / noise).log10())
            })
            .collect()
    }
}

fn energy(signal: &[f64]) -> f64 {
    signal.iter().map(|x| x * x).sum()
}

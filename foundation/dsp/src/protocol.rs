//! Excitation protocols: how the actuators are played to measure every actuator's impulse response at one grid
//! point, and how the recordings are turned back into one response per actuator.
//!
//! A protocol is a list of [`Shot`]s. In a shot every actuator plays the same excitation (one sweep period,
//! repeated back to back), each with its own gain (+1, -1 or 0 for silent) and start delay; the loopback reference
//! plays the excitation undelayed with gain +1. The recipe plays each shot (applying the actuators' Kirkeby
//! compensation to their drives), records velocity and loopback, and hands the recordings to
//! [`Protocol::decode`].
//!
//! | protocol | shots | assumptions |
//! |---|---|---|
//! | [`Protocol::Sequential`] (the paper's, with a linear sweep) | one per actuator, the others silent | none beyond the per-channel pipeline's: responses shorter than one period |
//! | [`Protocol::Hadamard`] | `N` (the power of two `>= actuators`), all actuators at once with the signs of row `s` of the Sylvester Hadamard matrix | linearity and superposition (the actuators' responses add at the plate); distortion of one actuator leaks into the others' responses as noise |
//! | [`Protocol::Interleaved`] (multiple exponential sweeps) | one: all actuators play one exponential sweep, actuator `k` delayed by `k * slot_s` | linearity; the response plus the harmonics' advance `L ln 3` fit in one slot; player and recorder on one clock (no drift estimate: a drift `d` moves actuator `k`'s response by `k slot_s d`) |
//!
//! Energy: with the same sweep and repetitions, each actuator gets as much excitation energy in a Hadamard scan as
//! in a sequential one, and every shot measures all of them: `N` shots of `N` actuators instead of `N` shots of
//! one. Decoding averages `N` shots, so the noise in each response falls by `N` in power, and the same accuracy
//! needs `N` times less playing time: the 8 x limit for 8 actuators.

use crate::deconv::{DeconvConfig, deconvolve_with_reference};
use crate::error::{DspError, check_result};
use crate::pipeline::{ChannelResult, PreparedLayout, RepetitionLayout};
use crate::sweep::{SweepKind, SweepSpec};

/// Largest actuator count a protocol accepts (a 64 x 64 Hadamard matrix at most).
pub const MAX_ACTUATORS: usize = 64;

/// Harmonic orders the interleaved protocol keeps out of the other actuators' windows (2 and 3: the voice coils'
/// quadratic and cubic distortion).
const INTERLEAVED_MAX_ORDER: f64 = 3.0;

/// An excitation protocol for one grid point.
#[derive(Debug, Clone, PartialEq)]
pub enum Protocol {
    /// Each actuator alone, `repetitions` periods of `sweep` (the paper's protocol: a 3 s linear sweep, 5 times).
    Sequential {
        /// The sweep (its sample rate is replaced by the player's and the recorder's as needed).
        sweep: SweepSpec,
        /// Periods per shot, at least 1.
        repetitions: usize,
    },
    /// All actuators at once, `N` shots signed by a Sylvester Hadamard matrix, decoded by its transpose.
    Hadamard {
        /// The sweep.
        sweep: SweepSpec,
        /// Periods per shot, at least 1.
        repetitions: usize,
    },
    /// All actuators in one shot, playing one exponential sweep staggered by `slot_s` (the multiple exponential
    /// sweep method); one period, so no SNR estimate.
    Interleaved {
        /// An exponential sweep.
        sweep: SweepSpec,
        /// Delay between consecutive actuators' starts, s. Delays are rounded to whole samples at each rate; a
        /// slot that is a whole number of samples at both the player's and the recorder's rate (a multiple of
        /// 1 ms for 48 and 24 kHz) keeps the two roundings equal.
        slot_s: f64,
    },
}

/// One playback of a protocol: what every actuator and the loopback play.
#[derive(Debug, Clone, PartialEq)]
pub struct Shot {
    /// Per actuator: the excitation's gain (+1, -1, or 0 for silent).
    pub gains: Vec<f64>,
    /// Per actuator: start delay, s (a whole number of samples at the rates used).
    pub delays_s: Vec<f64>,
}

impl Protocol {
    /// The paper's protocol: [`SweepSpec::default`] (3 s linear sweep, 62 to 625 Hz), 5 repetitions, sequential.
    pub fn paper() -> Self {
        Protocol::Sequential { sweep: SweepSpec::default(), repetitions: 5 }
    }

    /// The sweep every shot plays.
    pub fn sweep(&self) -> &SweepSpec {
        match self {
            Protocol::Sequential { sweep, .. }
            | Protocol::Hadamard { sweep, .. }
            | Protocol::Interleaved { sweep, .. } => sweep,
        }
    }

    /// Periods per shot.
    pub fn repetitions(&self) -> usize {
        match self {
            Protocol::Sequential { repetitions, .. } | Protocol::Hadamard { repetitions, .. } => *repetitions,
            Protocol::Interleaved { .. } => 1,
        }
    }

    /// Checks the protocol for `actuators` actuators and responses of `ir_len_s` seconds.
    ///
    /// Valid range: `1 <= actuators <= MAX_ACTUATORS`; a valid sweep; `repetitions >= 1`; for sequential and
    /// Hadamard protocols a response shorter than the sweep's period (`ir_len_s < duration_s`); for
    /// [`Protocol::Interleaved`] an exponential sweep and `slot_s >= ir_len_s + L ln 3` (`L` the sweep's rate), so
    /// that every actuator's response, and the second and third harmonics of the next one, stay out of each other's
    /// windows.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] naming what is out of range.
    pub fn validate(&self, actuators: usize, ir_len_s: f64) -> Result<(), DspError> {
        let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
        if actuators == 0 || actuators > MAX_ACTUATORS {
            return invalid("actuators", format!("{actuators}: must be 1 to {MAX_ACTUATORS}"));
        }
        self.sweep().validate()?;
        if self.repetitions() == 0 {
            return invalid("repetitions", "must be at least 1".into());
        }
        if let Protocol::Sequential { sweep, .. } | Protocol::Hadamard { sweep, .. } = self
            && (ir_len_s.is_nan() || ir_len_s >= sweep.duration_s)
        {
            // The periodic deconvolution wraps a response longer than the period onto its own start.
            return invalid(
                "ir_len_s",
                format!("a {ir_len_s} s response does not fit the sweep's {} s period", sweep.duration_s),
            );
        }
        if let Protocol::Interleaved { sweep, slot_s } = self {
            let Some(rate_s) = sweep.exp_rate_s() else {
                return invalid("sweep.kind", "the interleaved protocol needs an exponential sweep".into());
            };
            let needed_s = ir_len_s + rate_s * INTERLEAVED_MAX_ORDER.ln();
            if !(slot_s.is_finite() && *slot_s >= needed_s) {
                return invalid(
                    "slot_s",
                    format!(
                        "{slot_s} s is shorter than the response ({ir_len_s} s) plus the third harmonic's advance \
                         ({:.3} s): at least {needed_s:.3} s",
                        rate_s * INTERLEAVED_MAX_ORDER.ln()
                    ),
                );
            }
        }
        Ok(())
    }

    /// The shots, in playing order, for `actuators` actuators.
    ///
    /// # Errors
    /// As [`Protocol::validate`] (with a zero response length: the decoder checks the real one).
    pub fn shots(&self, actuators: usize) -> Result<Vec<Shot>, DspError> {
        self.validate(actuators, 0.0)?;
        let silent = vec![0.0; actuators];
        let undelayed = vec![0.0; actuators];
        Ok(match self {
            Protocol::Sequential { .. } => (0..actuators)
                .map(|k| {
                    let mut gains = silent.clone();
                    gains[k] = 1.0;
                    Shot { gains, delays_s: undelayed.clone() }
                })
                .collect(),
            Protocol::Hadamard { .. } => {
                let order = actuators.next_power_of_two();
                (0..order)
                    .map(|s| Shot {
                        gains: (0..actuators).map(|k| hadamard(s, k)).collect(),
                        delays_s: undelayed.clone(),
                    })
                    .collect()
            }
            Protocol::Interleaved { slot_s, .. } => {
                vec![Shot {
                    gains: vec![1.0; actuators],
                    delays_s: (0..actuators).map(|k| k as f64 * slot_s).collect(),
                }]
            }
        })
    }

    /// One period of the excitation at `sample_rate_hz` (the player's rate for playing, the recorder's for
    /// decoding).
    ///
    /// # Errors
    /// As [`SweepSpec::generate`] at that rate.
    pub fn excitation(&self, sample_rate_hz: f64) -> Result<Vec<f64>, DspError> {
        SweepSpec { sample_rate_hz, ..*self.sweep() }.generate()
    }

    /// Samples, at `sample_rate_hz`, from the start of a shot's playback to the end of the last actuator's last
    /// period (add the response length and the latency for a recording).
    pub fn shot_len_samples(&self, actuators: usize, sample_rate_hz: f64) -> usize {
        let period = (self.sweep().duration_s * sample_rate_hz).round() as usize;
        let delay = match self {
            Protocol::Interleaved { slot_s, .. } => {
                (actuators.saturating_sub(1) as f64 * slot_s * sample_rate_hz).round()
            }
            _ => 0.0,
        } as usize;
        self.repetitions() * period + delay
    }

    /// Playing time per grid point, s: every shot's playback plus `ir_len_s` of ring-out after each (beam moves
    /// and settling are the recipe's).
    pub fn time_per_point_s(&self, actuators: usize, ir_len_s: f64) -> f64 {
        let shots = match self {
            Protocol::Sequential { .. } => actuators,
            Protocol::Hadamard { .. } => actuators.next_power_of_two(),
            Protocol::Interleaved { .. } => 1,
        };
        let delay_s = match self {
            Protocol::Interleaved { slot_s, .. } => actuators.saturating_sub(1) as f64 * slot_s,
            _ => 0.0,
        };
        shots as f64 * (self.repetitions() as f64 * self.sweep().duration_s + delay_s + ir_len_s)
    }

    /// What actuator `actuator` plays in `shot`, at `sample_rate_hz`: its delay in silence, then `gain` times the
    /// excitation's periods; `None` when it is silent. The loopback plays [`Protocol::reference`].
    ///
    /// # Errors
    /// As [`Protocol::excitation`]; [`DspError::InvalidParameter`] for an actuator the shot does not have.
    pub fn drive(&self, shot: &Shot, actuator: usize, sample_rate_hz: f64) -> Result<Option<Vec<f64>>, DspError> {
        let (Some(&gain), Some(&delay_s)) = (shot.gains.get(actuator), shot.delays_s.get(actuator)) else {
            return Err(DspError::InvalidParameter {
                name: "actuator",
                reason: format!("{actuator} is beyond the shot's {} actuators", shot.gains.len()),
            });
        };
        if gain == 0.0 {
            return Ok(None);
        }
        let delay = (delay_s * sample_rate_hz).round() as usize;
        let mut out = vec![0.0; delay];
        let period = self.excitation(sample_rate_hz)?;
        for _ in 0..self.repetitions() {
            out.extend(period.iter().map(|x| gain * x));
        }
        Ok(Some(out))
    }

    /// What the loopback channel plays in every shot: the excitation's periods, undelayed.
    ///
    /// # Errors
    /// As [`Protocol::excitation`].
    pub fn reference(&self, sample_rate_hz: f64) -> Result<Vec<f64>, DspError> {
        Ok(self.excitation(sample_rate_hz)?.repeat(self.repetitions()))
    }

    /// Turns the recordings of every shot (velocity and loopback, on the recorder's clock at `cfg.sample_rate_hz`,
    /// in shot order) into one result per actuator: the impulse response from the loopback to the velocity
    /// (`cfg.ir_len` samples), its SNR, and the clock drift and latency seen.
    ///
    /// SNR: sequential shots give each actuator's own (from the spread of its repetitions; `None` with one).
    /// Hadamard responses are sums of `N` shots' responses with signs: their noise is the mean of the shots' noise
    /// energies divided by `N`, and the SNR is the response's energy over it. The interleaved protocol has no
    /// repetitions and gives `None`.
    ///
    /// Valid range: as [`Protocol::validate`] with `cfg.ir_len` samples of response; one recording pair per shot,
    /// each as [`PreparedLayout::process_channel`] requires.
    ///
    /// # Errors
    /// [`DspError::LengthMismatch`] for the wrong number of recordings; otherwise as
    /// [`PreparedLayout::process_channel`] and [`deconvolve_with_reference`].
    pub fn decode(
        &self,
        actuators: usize,
        recordings: &[(&[f64], &[f64])],
        cfg: &DeconvConfig,
    ) -> Result<Vec<ChannelResult>, DspError> {
        let fs = cfg.sample_rate_hz;
        self.validate(actuators, cfg.ir_len as f64 / fs)?;
        let shots = self.shots(actuators)?;
        if recordings.len() != shots.len() {
            return Err(DspError::LengthMismatch { what: "recordings and shots", a: recordings.len(), b: shots.len() });
        }
        match self {
            Protocol::Sequential { .. } => {
                let prepared = self.prepared(cfg)?;
                recordings.iter().map(|(velocity, loopback)| prepared.process_channel(velocity, loopback)).collect()
            }
            Protocol::Hadamard { .. } => {
                let prepared = self.prepared(cfg)?;
                let per_shot = recordings
                    .iter()
                    .map(|(velocity, loopback)| prepared.process_channel(velocity, loopback))
                    .collect::<Result<Vec<_>, _>>()?;
                hadamard_decode(&per_shot, actuators)
            }
            Protocol::Interleaved { slot_s, .. } => {
                let (velocity, loopback) = recordings[0];
                // The same rounding as `drive`, actuator by actuator.
                let starts: Vec<usize> = (0..actuators).map(|k| (k as f64 * slot_s * fs).round() as usize).collect();
                let last = starts.last().copied().unwrap_or(0);
                let span = DeconvConfig { ir_len: last + cfg.ir_len, ..*cfg };
                let total = deconvolve_with_reference(velocity, loopback, &span)?;
                starts
                    .iter()
                    .map(|&start| {
                        let ir = total[start..start + cfg.ir_len].to_vec();
                        Ok(ChannelResult { ir, snr_db: None, drift_ppm: 0.0, latency_samples: 0.0 })
                    })
                    .collect()
            }
        }
    }

    fn prepared(&self, cfg: &DeconvConfig) -> Result<PreparedLayout, DspError> {
        let layout =
            RepetitionLayout { excitation: self.excitation(cfg.sample_rate_hz)?, repetitions: self.repetitions() };
        PreparedLayout::new(&layout, cfg)
    }
}

/// Entry `(row, col)` of the Sylvester Hadamard matrix of any power-of-two order: `(-1)^popcount(row & col)`.
pub fn hadamard(row: usize, col: usize) -> f64 {
    if (row & col).count_ones().is_multiple_of(2) { 1.0 } else { -1.0 }
}

/// Responses of the actuators from the responses of the Hadamard shots: `g_k = (1/N) sum_s H[s][k] y_s`.
fn hadamard_decode(per_shot: &[ChannelResult], actuators: usize) -> Result<Vec<ChannelResult>, DspError> {
    let order = per_shot.len() as f64;
    let ir_len = per_shot.first().map_or(0, |r| r.ir.len());
    // A shot's noise energy from its SNR and energy; unknown when any shot has no SNR.
    let noise: Option<f64> = per_shot
        .iter()
        .map(|r| r.snr_db.map(|snr| energy(&r.ir) / 10f64.powf(snr / 10.0)))
        .sum::<Option<f64>>()
        .map(|total| total / order / order);
    let drift_ppm = per_shot.iter().map(|r| r.drift_ppm).sum::<f64>() / order;
    let latency_samples = per_shot.iter().map(|r| r.latency_samples).sum::<f64>() / order;
    (0..actuators)
        .map(|k| {
            let mut ir = vec![0.0; ir_len];
            for (s, shot) in per_shot.iter().enumerate() {
                let sign = hadamard(s, k) / order;
                ir.iter_mut().zip(&shot.ir).for_each(|(g, y)| *g += sign * y);
            }
            check_result("Hadamard-decoded response", &ir)?;
            let snr_db = noise.filter(|n| *n > 0.0).map(|n| 10.0 * (energy(&ir) / n).log10()).filter(|s| s.is_finite());
            Ok(ChannelResult { ir, snr_db, drift_ppm, latency_samples })
        })
        .collect()
}

fn energy(signal: &[f64]) -> f64 {
    signal.iter().map(|x| x * x).sum()
}

impl SweepSpec {
    /// The exponential sweep over the same band, duration and rate.
    pub fn as_exponential(&self) -> SweepSpec {
        SweepSpec { kind: SweepKind::Exponential, ..*self }
    }
}

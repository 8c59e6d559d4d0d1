//! Excitation protocols: how the actuators are played to measure every actuator's impulse response at one grid
//! point, and how the recordings are turned back into one response per actuator.
//!
//! A protocol is a list of [`Shot`]s. In a shot every actuator plays the same excitation (one sweep period,
//! repeated back to back), each with its own gain (+1, -1 or 0 for silent) and start delay; the loopback reference
//! plays the excitation undelayed with gain +1. The recipe plays each shot (applying the actuators' Kirkeby
//! compensation to their drives), records velocity and loopback, and hands the recordings to
//! [`ExcitationProtocol::decode`].
//!
//! | protocol | shots | assumptions |
//! |---|---|---|
//! | [`Scheme::Sequential`] (the paper's, with a linear sweep) | one per actuator, the others silent | none beyond the per-channel pipeline's: responses shorter than one period |
//! | [`Scheme::Hadamard`] | `N` (the power of two `>= actuators`), all actuators at once with the signs of row `s` of the Sylvester Hadamard matrix | linearity and superposition (the actuators' responses add at the plate); distortion of one actuator leaks into the others' responses as noise |
//! | [`Scheme::Staggered`] | one: all actuators play the same periodic linear sweep, actuator `k` circularly shifted by `k` slots of `period / actuators` | linearity and superposition; each response (and the band limit's precursor) within one slot, beyond which it lands in the next actuator's; odd- and even-order distortion of every actuator spreads over the whole period, so every actuator's window collects a share of all |
//! | [`Scheme::Interleaved`] (multiple exponential sweeps) | one: all actuators play one exponential sweep, actuator `k` delayed by `k * slot_s` | linearity; the response plus the harmonics' advance `L ln 3` fit in one slot; player and recorder on one clock (no drift estimate: a drift `d` moves actuator `k`'s response by `k slot_s d`) |
//!
//! Energy: with the same sweep and repetitions, each actuator gets as much excitation energy in a Hadamard scan as
//! in a sequential one, and every shot measures all of them: `N` shots of `N` actuators instead of `N` shots of
//! one. Decoding averages `N` shots, so the noise in each response falls by `N` in power, and the same accuracy
//! needs `N` times less playing time: the 8 x limit for 8 actuators.
//!
//! # The registry of names
//!
//! [`parse`] turns a name into a protocol; [`NAMES`] lists them with a line of help each (the CLI's help is
//! generated from it).
//!
//!
//! Syntax: `NAME` or `NAME:SETTINGS`, names in kebab-case. `D` is the sweep's duration in seconds (0.6 s at
//! least: the 0.5 s responses must fit one period), `R` the periods per shot (at least 1).
//!
//! | name | what is played | assumptions |
//! |---|---|---|
//! | `paper` | each actuator alone, a 3 s linear sweep 62..625 Hz, 5 periods (120 s of sweeps per point) | responses shorter than one period (0.5 s); nothing else |
//! | `quick` | each actuator alone, a 1 s linear sweep, 2 periods | as `paper` |
//! | `sequential:DxR` | each actuator alone, linear sweeps | as `paper` |
//! | `sequential-exp:DxR` | each actuator alone, exponential sweeps; the harmonics land before time 0 of the periodic response and are cut away (harmonic separation) | harmonic `k`'s advance `L ln k` (`L = D / ln(f2/f1)`) at least the response length beyond which the window stops, i.e. `D - 0.5 s >= L ln 2` for the second harmonic |
//! | `hadamard:DxR` | all actuators at once, 8 shots signed by the 8 x 8 Hadamard matrix, decoded by its transpose (8 x the energy per actuator per unit time) | linearity and superposition at the plate; odd-order distortion flips with the sign and stays with its actuator (as sequentially); even-order does not flip, so it can only land in actuator 0's (all-ones) column |
//! | `staggered:DxR` (R >= 2) | all 8 actuators in one shot, each playing the D s linear sweep circularly shifted by its slot, D / 8 s (at least 0.6 s: the 0.5 s response and its precursor in a slot), R periods: the periodic deconvolution gives all 8 responses side by side, every actuator getting R x D s of sweep; one ring-out per point | as `hadamard`, and every response shorter than a slot (its tail beyond lands in the next actuator's window); the drives start and stop mid-sweep (a click at each end, exact for a linear plate) |
//! | `interleaved:D` | all actuators in one shot, one exponential sweep each, staggered by a slot (the multiple exponential sweep method) | linearity; slot >= response (0.5 s) + the third harmonic's advance `L ln 3`, else refused; one period: no SNR estimate, no averaging; **no clock-drift correction**: actuator `k`'s response is cut at `k` slots on the recorder's clock, off by `k x slot x drift` (12 samples for actuator 7 at 50 ppm with 1.43 s slots), which costs it most of its accuracy at the top of the band (measured median error -10 dB on the mock lab, against -37 dB for the others) |
//! | `adaptive:DxR@SNR[/ROUNDS]` (R >= 2) | Hadamard rounds (`hadamard:DxR`) averaged until every actuator's SNR reaches `SNR` dB, at most `ROUNDS` (default 8) | as `hadamard`; the SNR estimate is the spread of the periods; when the target is not met in `ROUNDS` rounds the rows are committed with status `failed` and the reason |
//! | `sequential-adaptive:DxR@DB[/ROUNDS]` (R >= 2) | each actuator alone (as `sequential:DxR`): a first shot of R periods, then shots as long as its estimated error says are still missing (10 % over, at least 2 periods), averaged (weighted by their periods) until that actuator's own estimated error is `DB` dB or less, at most `ROUNDS x R` periods in all: each row gets the time its response needs, in few shots (each pays the ring-out) | as `sequential`; the estimate sees the noise only, and its noise falls as 1 / periods |
//! | `staggered-adaptive:DxR@DB[/ROUNDS]` (R >= 2) | staggered shots (`staggered:DxR`) averaged until every actuator's estimated error at the point is `DB` dB or less, at most `ROUNDS`: each point gets the time its darkest speckle and weakest actuator need | as `staggered`; the estimate sees the noise only |
//! | `adaptive-error:DxR@DB[/ROUNDS]` (R >= 2) | Hadamard rounds averaged until every actuator's estimated error over 80..600 Hz ([`crate::pipeline::ChannelResult::estimated_error_db`]) is `DB` dB or less, at most `ROUNDS` | as `adaptive`; the estimate sees the noise, not biases every period shares (distortion, drift) |
//!
//! Every protocol keeps the paper's deconvolution ([`DeconvConfig::paper`]: 0.5 s responses, band 62..625 Hz);
//! exponential sweeps use regularisation 1e-5 (their power falls 10 dB across the band, see
//! [`DeconvConfig::paper`]).

use crate::deconv::{DeconvConfig, deconvolve_with_reference};
use crate::error::{DspError, check_result};
use crate::pipeline::{ChannelResult, PreparedLayout, RepetitionLayout};
use crate::sweep::{SweepKind, SweepSpec};

mod names;
pub use names::{NAMES, ProtocolNameError, help_text, parse};

/// Largest actuator count a protocol accepts (a 64 x 64 Hadamard matrix at most).
pub const MAX_ACTUATORS: usize = 64;

/// Harmonic orders the interleaved protocol keeps out of the other actuators' windows (2 and 3: the voice coils'
/// quadratic and cubic distortion).
const INTERLEAVED_MAX_ORDER: f64 = 3.0;

/// How the actuators are played at a grid point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scheme {
    /// Each actuator alone, `repetitions` periods of the sweep (the paper's).
    Sequential,
    /// All actuators at once, `N` shots signed by a Sylvester Hadamard matrix, decoded by its transpose.
    Hadamard,
    /// All actuators in one shot, each playing the periodic sweep circularly shifted by its slot (`period /
    /// actuators`, rounded down to whole samples at the rate played and decoded), `repetitions` periods: the
    /// periodic deconvolution of the loopback holds every actuator's response in its own slot.
    Staggered,
    /// All actuators in one shot, playing one exponential sweep staggered by `slot_s` (the multiple exponential
    /// sweep method); one period, so no SNR estimate.
    Interleaved {
        /// Delay between consecutive actuators' starts, s. Delays are rounded to whole samples at each rate; a
        /// slot that is a whole number of samples at both the player's and the recorder's rate (a multiple of
        /// 1 ms for 48 and 24 kHz) keeps the two roundings equal.
        slot_s: f64,
    },
}

/// Averaging rounds until a target.
///
/// Valid range: a finite target; `max_rounds >= 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    /// What every actuator's response at a point must reach before the point is committed.
    pub target: AdaptiveTarget,
    /// Rounds (each one full set of shots) at most; then the point is committed, its short rows flagged.
    pub max_rounds: usize,
}

/// What an adaptive protocol's rounds aim for, per actuator at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AdaptiveTarget {
    /// The SNR of the averaged velocity (the spread of the periods, over the deconvolution's band) at least this,
    /// dB (`adaptive:DxR@SNR`).
    SnrDb(f64),
    /// The response's estimated error over [`crate::accuracy::ERROR_BAND_HZ`]
    /// ([`crate::pipeline::ChannelResult::estimated_error_db`]) at most this, dB (`adaptive-error:DxR@DB`): what a
    /// user of the Green's functions asks for, whatever the response's level at the point.
    ErrorDb(f64),
}

impl AdaptiveTarget {
    /// Whether an actuator with this SNR and estimated error (dB, `None` when unknown) has reached the target; an
    /// unknown value never has.
    pub fn reached(self, snr_db: Option<f64>, error_db: Option<f64>) -> bool {
        match self {
            Self::SnrDb(target) => snr_db.is_some_and(|s| s >= target),
            Self::ErrorDb(target) => error_db.is_some_and(|e| e <= target),
        }
    }

    /// By how much, dB, the noise of an actuator with this SNR and estimated error (dB, `None` when unknown) must
    /// still fall to reach the target: positive when short of it, 0 or less when reached; `None` when unknown.
    pub fn shortfall_db(self, snr_db: Option<f64>, error_db: Option<f64>) -> Option<f64> {
        match self {
            Self::SnrDb(target) => snr_db.map(|s| target - s),
            Self::ErrorDb(target) => error_db.map(|e| e - target),
        }
    }

    /// The target's value, dB.
    pub fn db(self) -> f64 {
        match self {
            Self::SnrDb(db) | Self::ErrorDb(db) => db,
        }
    }

    /// What it measures, in messages: `SNR` or `estimated error`.
    pub fn quantity(self) -> &'static str {
        match self {
            Self::SnrDb(_) => "SNR",
            Self::ErrorDb(_) => "estimated error",
        }
    }
}

/// An excitation protocol: how the actuators are played at one grid point and how the recordings are decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct ExcitationProtocol {
    /// Name recorded in the manifest (`paper`, `quick`, `hadamard:1x2`, ...).
    pub name: String,
    /// How the actuators are played (one at a time, or all at once).
    pub scheme: Scheme,
    /// One period of the excitation (its `sample_rate_hz` is replaced by the player's and the recorder's).
    pub sweep: SweepSpec,
    /// Periods played back to back per shot, at least 1 (the interleaved scheme plays 1 whatever this says).
    pub repetitions: usize,
    /// Deconvolution (its `sample_rate_hz` is replaced by the recorder's).
    pub deconv: DeconvConfig,
    /// Averaging until a target SNR (simultaneous schemes only); `None`: one round.
    pub adaptive: Option<Adaptive>,
}

/// One playback of a protocol: what every actuator and the loopback play.
#[derive(Debug, Clone, PartialEq)]
pub struct Shot {
    /// Per actuator: the excitation's gain (+1, -1, or 0 for silent).
    pub gains: Vec<f64>,
    /// Per actuator: start delay, s (a whole number of samples at the rates used).
    pub delays_s: Vec<f64>,
}

impl ExcitationProtocol {
    /// A protocol named `name` playing `sweep` by `scheme`, `repetitions` periods per shot, with the paper's
    /// deconvolution ([`DeconvConfig::paper`]: 0.5 s responses, band 62..625 Hz) made two-sided and nearly
    /// unbiased: [`PRE_SAMPLES`] of the 12000 samples before time 0, regularisation [`LINEAR_REGULARISATION`]
    /// ([`EXP_REGULARISATION`] for an exponential sweep); no adaptive averaging. Not validated: see
    /// [`ExcitationProtocol::validate`].
    pub fn new(name: &str, scheme: Scheme, sweep: SweepSpec, repetitions: usize) -> Self {
        let regularisation = if sweep.exp_rate_s().is_some() { EXP_REGULARISATION } else { LINEAR_REGULARISATION };
        let deconv = DeconvConfig { regularisation, pre_samples: PRE_SAMPLES, ..DeconvConfig::paper() };
        let repetitions = if matches!(scheme, Scheme::Interleaved { .. }) { 1 } else { repetitions };
        Self { name: name.to_string(), scheme, sweep, repetitions, deconv, adaptive: None }
    }

    /// The paper's: [`SweepSpec::default`] (a 3 s linear sweep 62..625 Hz), 5 repetitions, sequential,
    /// [`DeconvConfig::paper`] (0.5 s responses).
    pub fn paper() -> Self {
        Self::new("paper", Scheme::Sequential, SweepSpec::default(), 5)
    }

    /// For tests and quick looks: a 1 s sweep 62..625 Hz, 2 repetitions, the paper's deconvolution (0.5 s
    /// responses fit the 1 s period). 7.5 times less playing than the paper's; the SNR drops by about 10 dB (the
    /// sweep energy per period falls 3 times and 2 periods are averaged instead of 5).
    pub fn quick() -> Self {
        Self::new("quick", Scheme::Sequential, SweepSpec { duration_s: 1.0, ..SweepSpec::default() }, 2)
    }

    /// A protocol by name (see the module's table); the same as [`parse`].
    ///
    /// # Errors
    /// As [`parse`].
    pub fn by_name(name: &str) -> Result<Self, ProtocolNameError> {
        parse(name)
    }

    /// The sweep every shot plays.
    pub fn sweep(&self) -> &SweepSpec {
        &self.sweep
    }

    /// Periods per shot (1 for the interleaved scheme).
    pub fn repetitions(&self) -> usize {
        match self.scheme {
            Scheme::Sequential | Scheme::Hadamard | Scheme::Staggered => self.repetitions,
            Scheme::Interleaved { .. } => 1,
        }
    }

    /// Whether every actuator plays in every shot (shots are then measured and retried as a whole point).
    pub fn is_simultaneous(&self) -> bool {
        !matches!(self.scheme, Scheme::Sequential)
    }

    /// Nominal playing time per point and round for `actuators` actuators, s: every shot's playback and the
    /// response's ring-out of [`ExcitationProtocol::deconv`] (beam moves, settling and the recording margin are not
    /// included). Adaptive protocols take between one and `max_rounds` times this.
    pub fn nominal_time_per_point_s(&self, actuators: usize) -> f64 {
        self.time_per_point_s(actuators, self.deconv.ir_len as f64 / self.deconv.sample_rate_hz)
    }

    /// Checks the protocol for `actuators` actuators and responses of `ir_len_s` seconds.
    ///
    /// Valid range: `1 <= actuators <= MAX_ACTUATORS`; a valid sweep; `repetitions >= 1`; for sequential and
    /// Hadamard schemes a response shorter than the sweep's period (`ir_len_s < duration_s`); for
    /// [`Scheme::Interleaved`] an exponential sweep and `slot_s >= ir_len_s + L ln 3` (`L` the sweep's rate), so
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
        self.sweep.validate()?;
        if self.repetitions() == 0 {
            return invalid("repetitions", "must be at least 1".into());
        }
        let sweep = &self.sweep;
        if matches!(self.scheme, Scheme::Staggered) {
            // The SNR estimate and the drift correction need two periods; each response must fit its slot.
            if self.repetitions() < 2 {
                return invalid("repetitions", "a staggered protocol needs at least 2 periods".into());
            }
            let slot_s = sweep.duration_s / actuators as f64;
            if ir_len_s.is_nan() || slot_s < ir_len_s.max(MIN_SWEEP_S) {
                return invalid(
                    "ir_len_s",
                    format!(
                        "a {ir_len_s} s response does not fit the {slot_s:.3} s slot of {actuators} actuators in a {} \
                         s period: at least {MIN_SWEEP_S} s per actuator",
                        sweep.duration_s
                    ),
                );
            }
        }
        match self.scheme {
            Scheme::Sequential | Scheme::Hadamard if ir_len_s.is_nan() || ir_len_s >= sweep.duration_s => {
                // The periodic deconvolution wraps a response longer than the period onto its own start.
                return invalid(
                    "ir_len_s",
                    format!("a {ir_len_s} s response does not fit the sweep's {} s period", sweep.duration_s),
                );
            }
            Scheme::Sequential | Scheme::Hadamard | Scheme::Staggered => {}
            Scheme::Interleaved { slot_s } => {
                let Some(rate_s) = sweep.exp_rate_s() else {
                    return invalid("sweep.kind", "the interleaved protocol needs an exponential sweep".into());
                };
                let needed_s = ir_len_s + rate_s * INTERLEAVED_MAX_ORDER.ln();
                if !(slot_s.is_finite() && slot_s >= needed_s) {
                    return invalid(
                        "slot_s",
                        format!(
                            "{slot_s} s is shorter than the response ({ir_len_s} s) plus the third harmonic's \
                             advance ({:.3} s): at least {needed_s:.3} s",
                            rate_s * INTERLEAVED_MAX_ORDER.ln()
                        ),
                    );
                }
            }
        }
        Ok(())
    }

    /// The shots, in playing order, for `actuators` actuators.
    ///
    /// # Errors
    /// As [`ExcitationProtocol::validate`] (with a zero response length: the decoder checks the real one).
    pub fn shots(&self, actuators: usize) -> Result<Vec<Shot>, DspError> {
        self.validate(actuators, 0.0)?;
        let silent = vec![0.0; actuators];
        let undelayed = vec![0.0; actuators];
        Ok(match self.scheme {
            Scheme::Sequential => (0..actuators)
                .map(|k| {
                    let mut gains = silent.clone();
                    gains[k] = 1.0;
                    Shot { gains, delays_s: undelayed.clone() }
                })
                .collect(),
            Scheme::Hadamard => {
                let order = actuators.next_power_of_two();
                (0..order)
                    .map(|s| Shot {
                        gains: (0..actuators).map(|k| hadamard(s, k)).collect(),
                        delays_s: undelayed.clone(),
                    })
                    .collect()
            }
            Scheme::Interleaved { slot_s } => {
                vec![Shot {
                    gains: vec![1.0; actuators],
                    delays_s: (0..actuators).map(|k| k as f64 * slot_s).collect(),
                }]
            }
            // The shifts are circular, within each period: none delays the shot's start.
            Scheme::Staggered => vec![Shot { gains: vec![1.0; actuators], delays_s: undelayed }],
        })
    }

    /// One period of the excitation at `sample_rate_hz` (the player's rate for playing, the recorder's for
    /// decoding).
    ///
    /// # Errors
    /// As [`SweepSpec::generate`] at that rate.
    pub fn excitation(&self, sample_rate_hz: f64) -> Result<Vec<f64>, DspError> {
        SweepSpec { sample_rate_hz, ..self.sweep }.generate()
    }

    /// Samples, at `sample_rate_hz`, from the start of a shot's playback to the end of the last actuator's last
    /// period (add the response length and the latency for a recording).
    pub fn shot_len_samples(&self, actuators: usize, sample_rate_hz: f64) -> usize {
        let period = (self.sweep.duration_s * sample_rate_hz).round() as usize;
        let delay = match self.scheme {
            Scheme::Interleaved { slot_s } => (actuators.saturating_sub(1) as f64 * slot_s * sample_rate_hz).round(),
            _ => 0.0,
        } as usize;
        self.repetitions() * period + delay
    }

    /// Playing time per grid point, s: every shot's playback plus `ir_len_s` of ring-out after each (beam moves
    /// and settling are the recipe's).
    pub fn time_per_point_s(&self, actuators: usize, ir_len_s: f64) -> f64 {
        let (shots, delay_s) = match self.scheme {
            Scheme::Sequential => (actuators, 0.0),
            Scheme::Hadamard => (actuators.next_power_of_two(), 0.0),
            Scheme::Staggered => (1, 0.0),
            Scheme::Interleaved { slot_s } => (1, actuators.saturating_sub(1) as f64 * slot_s),
        };
        shots as f64 * (self.repetitions() as f64 * self.sweep.duration_s + delay_s + ir_len_s)
    }

    /// What actuator `actuator` plays in `shot`, at `sample_rate_hz`: its delay in silence, then `gain` times the
    /// excitation's periods; `None` when it is silent. The loopback plays [`ExcitationProtocol::reference`].
    ///
    /// # Errors
    /// As [`ExcitationProtocol::excitation`]; [`DspError::InvalidParameter`] for an actuator the shot does not have.
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
        let mut period = self.excitation(sample_rate_hz)?;
        if matches!(self.scheme, Scheme::Staggered) {
            let shift = staggered_shift(actuator, shot.gains.len(), period.len());
            period.rotate_right(shift);
        }
        for _ in 0..self.repetitions() {
            out.extend(period.iter().map(|x| gain * x));
        }
        Ok(Some(out))
    }

    /// What the loopback channel plays in every shot: the excitation's periods, undelayed.
    ///
    /// # Errors
    /// As [`ExcitationProtocol::excitation`].
    pub fn reference(&self, sample_rate_hz: f64) -> Result<Vec<f64>, DspError> {
        Ok(self.excitation(sample_rate_hz)?.repeat(self.repetitions()))
    }

    /// The decoder of this protocol for `actuators` actuators and the deconvolution `cfg` (on the recorder's clock
    /// at `cfg.sample_rate_hz`, responses of `cfg.ir_len` samples): the periodic deconvolution's set-up is built
    /// once here, for every shot and grid point.
    ///
    /// # Errors
    /// As [`ExcitationProtocol::validate`] with `cfg.ir_len` samples of response; as [`PreparedLayout::new`].
    pub fn decoder(&self, actuators: usize, cfg: &DeconvConfig) -> Result<Decoder, DspError> {
        self.validate(actuators, cfg.ir_len as f64 / cfg.sample_rate_hz)?;
        let prepared = match self.scheme {
            Scheme::Sequential | Scheme::Hadamard | Scheme::Staggered => {
                let layout = RepetitionLayout {
                    excitation: self.excitation(cfg.sample_rate_hz)?,
                    repetitions: self.repetitions(),
                };
                Some(PreparedLayout::new(&layout, cfg)?)
            }
            Scheme::Interleaved { .. } => None,
        };
        Ok(Decoder { protocol: self.clone(), actuators, cfg: *cfg, prepared })
    }

    /// Turns the recordings of every shot (velocity and loopback, on the recorder's clock at `cfg.sample_rate_hz`,
    /// in shot order) into one result per actuator; the same as [`ExcitationProtocol::decoder`] then
    /// [`Decoder::decode`].
    ///
    /// # Errors
    /// As [`ExcitationProtocol::decoder`] and [`Decoder::decode`].
    pub fn decode(
        &self,
        actuators: usize,
        recordings: &[(&[f64], &[f64])],
        cfg: &DeconvConfig,
    ) -> Result<Vec<ChannelResult>, DspError> {
        self.decoder(actuators, cfg)?.decode(recordings)
    }
}

/// A protocol ready to decode (see [`ExcitationProtocol::decoder`]).
#[derive(Debug, Clone)]
pub struct Decoder {
    protocol: ExcitationProtocol,
    actuators: usize,
    cfg: DeconvConfig,
    /// The periodic deconvolution (sequential and Hadamard schemes).
    prepared: Option<PreparedLayout>,
}

impl Decoder {
    /// The recorder's rate the responses come out at, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.cfg.sample_rate_hz
    }

    /// The response of one shot's recording by the periodic deconvolution: for a sequential protocol, the response
    /// of the shot's actuator (the scan decodes each actuator's acquisition as it comes).
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] for an interleaved protocol (its one shot decodes as a whole: see
    /// [`Decoder::decode`]); otherwise as [`PreparedLayout::process_channel`].
    pub fn decode_shot(&self, velocity: &[f64], loopback: &[f64]) -> Result<ChannelResult, DspError> {
        let (Some(prepared), Scheme::Sequential | Scheme::Hadamard) = (&self.prepared, self.protocol.scheme) else {
            return Err(DspError::InvalidParameter {
                name: "scheme",
                reason: "this protocol's one shot holds every actuator: decode it with `decode`".into(),
            });
        };
        prepared.process_channel(velocity, loopback)
    }

    /// Turns the recordings of every shot (velocity and loopback, in shot order) into one result per actuator: the
    /// impulse response from the loopback to the velocity (`cfg.ir_len` samples), its SNR, and the clock drift and
    /// latency seen.
    ///
    /// SNR: sequential shots give each actuator's own (from the spread of its repetitions; `None` with one).
    /// Hadamard responses are sums of `N` shots' responses with signs: their noise is the mean of the shots' noise
    /// energies divided by `N`, and the SNR is the response's energy over it. The interleaved protocol has no
    /// repetitions and gives `None`.
    ///
    /// Valid range: one recording pair per shot, each as [`PreparedLayout::process_channel`] requires.
    ///
    /// # Errors
    /// [`DspError::LengthMismatch`] for the wrong number of recordings; otherwise as
    /// [`PreparedLayout::process_channel`] and [`deconvolve_with_reference`].
    pub fn decode(&self, recordings: &[(&[f64], &[f64])]) -> Result<Vec<ChannelResult>, DspError> {
        let (actuators, cfg) = (self.actuators, &self.cfg);
        let shots = match self.protocol.scheme {
            Scheme::Sequential => actuators,
            Scheme::Hadamard => actuators.next_power_of_two(),
            Scheme::Staggered | Scheme::Interleaved { .. } => 1,
        };
        if recordings.len() != shots {
            return Err(DspError::LengthMismatch { what: "recordings and shots", a: recordings.len(), b: shots });
        }
        match self.protocol.scheme {
            Scheme::Sequential => {
                recordings.iter().map(|(velocity, loopback)| self.decode_shot(velocity, loopback)).collect()
            }
            Scheme::Hadamard => {
                let per_shot = recordings
                    .iter()
                    .map(|(velocity, loopback)| self.decode_shot(velocity, loopback))
                    .collect::<Result<Vec<_>, _>>()?;
                hadamard_decode(&per_shot, actuators)
            }
            Scheme::Staggered => {
                let (velocity, loopback) = recordings[0];
                let Some(prepared) = &self.prepared else {
                    return Err(DspError::InvalidParameter { name: "scheme", reason: "no layout prepared".into() });
                };
                let n = prepared.layout().excitation.len();
                let shifts: Vec<usize> = (0..actuators).map(|k| staggered_shift(k, actuators, n)).collect();
                prepared.process_shifted(velocity, loopback, &shifts)
            }
            Scheme::Interleaved { slot_s } => {
                let fs = cfg.sample_rate_hz;
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
                        Ok(ChannelResult { ir, snr_db: None, drift_ppm: 0.0, latency_samples: 0.0, noise_energy: None })
                    })
                    .collect()
            }
        }
    }
}

/// Samples of a scan's responses before time 0 (85 ms at 24 kHz), the rest of the 12000 after it: the band limit
/// smears a response's abrupt onset into negative time, and a response cut at time 0 misses that precursor, a bias
/// of -38 dB median over 80..600 Hz on 0.8's built-in plates with every imperfection of the mock lab off
/// (`metaplate budget --pre-samples 0`); kept, the processing floor is -89 dB. The response after time 0 (0.415 s) still holds
/// the plates' ring-down to below -100 dB.
pub const PRE_SAMPLES: usize = 2048;
/// Regularisation of a scan's linear sweeps: its bias `eps / (|D|^2 + eps)`, at most 6e-5 where the sweep's power
/// dips to a sixth of its peak, is below -84 dB; the paper's 1e-3 ([`DeconvConfig::paper`]) left a -57 dB floor.
/// Outside the band the raised-cosine skirts cut what the smaller regularisation lets through.
pub const LINEAR_REGULARISATION: f64 = 1e-5;
/// Regularisation of a scan's exponential sweeps, whose power falls by 10 dB across the band (see
/// [`DeconvConfig::paper`]).
pub const EXP_REGULARISATION: f64 = 1e-7;
/// Shortest sweep, s: one period must hold the 0.5 s responses plus the periodic pipeline's guard for the clock
/// drift (tens of samples).
const MIN_SWEEP_S: f64 = 0.6;
/// Longest sweep, s (a sanity bound: the paper's is 3 s).
const MAX_SWEEP_S: f64 = 60.0;
/// Most periods per shot (a sanity bound).
const MAX_REPETITIONS: usize = 100;
/// Default and largest number of adaptive rounds.
pub const DEFAULT_ROUNDS: usize = 8;
const MAX_ROUNDS: usize = 64;
/// Slot margin beyond the response and the third harmonic's advance, s: a few periods of the band's lowest
/// frequency, for the band-limit's ringing.
const SLOT_MARGIN_S: f64 = 0.05;

/// Circular shift, samples, of actuator `k` of `actuators` in a staggered protocol's period of `period_samples`:
/// `k` slots of `period_samples / actuators` (rounded down), the same for the drive and the decoder.
pub fn staggered_shift(k: usize, actuators: usize, period_samples: usize) -> usize {
    k * (period_samples / actuators.max(1))
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
    // Each shot's noise in band, independent across shots: the decoded sum of N signed shots over N carries their
    // total over N^2, whatever the signs.
    let band_noise: Option<f64> =
        per_shot.iter().map(|r| r.noise_energy).sum::<Option<f64>>().map(|total| total / order / order);
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
            Ok(ChannelResult { ir, snr_db, drift_ppm, latency_samples, noise_energy: band_noise })
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

//! Targets: what each pixel should do over time, and its spectrum at the band's bins.
//!
//! Every waveform is rendered on the model's circular time axis (period `fft_len / sample_rate_hz`), band-limited to
//! the operating band with raised-cosine skirts of [`TargetBand::skirt_hz`] inside the band (so the target is
//! reachable: `G` is known only in the band), and scaled to a peak of 1 in the band-limited signal (units of the
//! field, e.g. m/s, before the drive is peak-normalised). A [`Waveform::Null`] pixel asks for zero: suppression.

use std::str::FromStr;

use metaplate_core::rng::SplitMix64;
use num_complex::Complex64;

use metaplate_dsp::band::BandLimit;
use metaplate_dsp::fft;

use crate::error::ControlError;
use crate::propagation::PropagationMatrices;

/// Stream of a noise target's generator (see [`SplitMix64::new`]).
const NOISE_STREAM: u64 = 0x006e_6f69_7365; // "noise"

/// Default width of the raised-cosine skirts that taper a target inside the band edges, Hz.
pub const DEFAULT_SKIRT_HZ: f64 = 25.0;

/// A pixel's waveform over one period of the drive. Times in seconds from the start of the period.
#[derive(Debug, Clone, PartialEq)]
pub enum Waveform {
    /// One band-limited impulse at `time_s` (the paper's single-pixel target).
    Impulse {
        /// Focus time, s.
        time_s: f64,
    },
    /// Band-limited impulses at each of `times_s` (repeated impulses: refresh rate, sequences).
    Impulses {
        /// Impulse times, s.
        times_s: Vec<f64>,
    },
    /// A white-noise burst (seeded, reproducible), band-limited.
    Noise {
        /// Start, s.
        start_s: f64,
        /// Length, s.
        duration_s: f64,
        /// RNG seed.
        seed: u64,
    },
    /// White-noise bursts of `duration_s` starting at each of `starts_s` (a burst train: the paper's experiments 1
    /// and 3), drawn in order from one seeded generator, band-limited.
    NoiseBursts {
        /// Burst starts, s.
        starts_s: Vec<f64>,
        /// Length of each burst, s.
        duration_s: f64,
        /// RNG seed.
        seed: u64,
    },
    /// A sinusoid of `freq_hz` from `start_s` for `duration_s` (the whole period when `duration_s` is 0).
    Sine {
        /// Frequency, Hz.
        freq_hz: f64,
        /// Start, s.
        start_s: f64,
        /// Length, s (0: the whole period, continuous).
        duration_s: f64,
    },
    /// Hann-windowed sine bursts of `cycles` cycles at `freq_hz`, centred at each of `times_s`.
    WaveletTrain {
        /// Carrier frequency, Hz.
        freq_hz: f64,
        /// Cycles per wavelet (>= 1).
        cycles: f64,
        /// Wavelet centre times, s.
        times_s: Vec<f64>,
    },
    /// Zero: suppress vibration at the pixel.
    Null,
}

/// One pixel: a grid point and its waveform.
#[derive(Debug, Clone, PartialEq)]
pub struct PixelTarget {
    /// Grid point, flat index (must be among the propagation matrices' points).
    pub point_index: u32,
    /// What the pixel should do.
    pub waveform: Waveform,
    /// Peak of the band-limited target, units of the field (1 by default); relative sizes between pixels.
    pub amplitude: f64,
}

/// A moving source: one impulse per point of `points`, the `i`-th at `start_s + i * step_s` (sequences over time).
pub fn moving_source(points: &[u32], start_s: f64, step_s: f64) -> Vec<PixelTarget> {
    points
        .iter()
        .enumerate()
        .map(|(i, &point_index)| PixelTarget {
            point_index,
            waveform: Waveform::Impulse { time_s: start_s + i as f64 * step_s },
            amplitude: 1.0,
        })
        .collect()
}

/// The band a target is limited to: the propagation matrices' band, tapered by skirts inside its edges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetBand {
    /// Width of the raised-cosine skirts inside each band edge, Hz (>= 0; 0 is a brick wall).
    pub skirt_hz: f64,
}

impl Default for TargetBand {
    fn default() -> Self {
        Self { skirt_hz: DEFAULT_SKIRT_HZ }
    }
}

impl TargetBand {
    /// The target gain (0..=1) at each of `g`'s bins: 1 inside `[lo + skirt, hi - skirt]`, raised cosine to 0 at
    /// the band edges `lo`, `hi` (the first and last bin frequencies).
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for a negative or non-finite skirt, or skirts wider than half the band.
    pub fn gains(&self, g: &PropagationMatrices) -> Result<Vec<f64>, ControlError> {
        let freqs = g.freqs_hz();
        let (lo, hi) = (freqs[0], freqs[freqs.len() - 1]);
        let skirt = self.skirt_hz;
        if !(skirt.is_finite() && skirt >= 0.0 && (hi - lo == 0.0 && skirt == 0.0 || 2.0 * skirt < hi - lo)) {
            return Err(ControlError::InvalidParameter {
                name: "skirt_hz",
                reason: format!("must be finite, >= 0 and below half the band ({lo} .. {hi} Hz), got {skirt}"),
            });
        }
        if skirt == 0.0 {
            return Ok(vec![1.0; freqs.len()]);
        }
        // The dsp band puts its skirts outside [lo', hi']: move the edges in by one skirt, widened slightly so the
        // outermost bins keep a small non-zero gain (a zero there would waste a controlled bin).
        let band = BandLimit::new(lo + skirt, hi - skirt, skirt * 1.05, skirt * 1.05)?;
        Ok(freqs.iter().map(|&f| band.gain(f)).collect())
    }
}

impl Waveform {
    /// The waveform's raw samples over one period of `len` samples at `sample_rate_hz` (before band-limiting).
    pub fn samples(&self, len: usize, sample_rate_hz: f64) -> Result<Vec<f64>, ControlError> {
        let period_s = len as f64 / sample_rate_hz;
        let mut x = vec![0.0; len];
        let check_time = |name: &'static str, t: f64| -> Result<(), ControlError> {
            if t.is_finite() && (0.0..period_s).contains(&t) {
                Ok(())
            } else {
                Err(ControlError::InvalidParameter {
                    name,
                    reason: format!("{t} s is outside the period 0 .. {period_s} s"),
                })
            }
        };
        let positive = |name: &'static str, v: f64| -> Result<(), ControlError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ControlError::InvalidParameter { name, reason: format!("must be finite and positive, got {v}") })
            }
        };
        let span = |start_s: f64, duration_s: f64| {
            let first = (start_s * sample_rate_hz).round() as usize;
            let count = ((duration_s * sample_rate_hz).round() as usize).clamp(1, len);
            (0..count).map(move |i| (first + i) % len)
        };
        match self {
            Self::Null => {}
            // Impulses are added exactly in the frequency domain (fractional times); see `spectrum`.
            Self::Impulse { time_s } => check_time("time_s", *time_s)?,
            Self::Impulses { times_s } => {
                if times_s.is_empty() {
                    return Err(ControlError::Empty { input: "impulse times" });
                }
                for &t in times_s {
                    check_time("times_s", t)?;
                }
            }
            Self::Noise { start_s, duration_s, seed } => {
                check_time("start_s", *start_s)?;
                positive("duration_s", *duration_s)?;
                let mut rng = SplitMix64::new(*seed, NOISE_STREAM);
                for i in span(*start_s, *duration_s) {
                    x[i] = rng.uniform() * 2.0 - 1.0;
                }
            }
            Self::NoiseBursts { starts_s, duration_s, seed } => {
                if starts_s.is_empty() {
                    return Err(ControlError::Empty { input: "noise burst starts" });
                }
                positive("duration_s", *duration_s)?;
                let mut rng = SplitMix64::new(*seed, NOISE_STREAM);
                for &start_s in starts_s {
                    check_time("starts_s", start_s)?;
                    for i in span(start_s, *duration_s) {
                        x[i] = rng.uniform() * 2.0 - 1.0;
                    }
                }
            }
            Self::Sine { freq_hz, start_s, duration_s } => {
                positive("freq_hz", *freq_hz)?;
                check_time("start_s", *start_s)?;
                let duration_s = if *duration_s == 0.0 { period_s } else { *duration_s };
                positive("duration_s", duration_s)?;
                for (j, i) in span(*start_s, duration_s).enumerate() {
                    x[i] = (std::f64::consts::TAU * freq_hz * j as f64 / sample_rate_hz).sin();
                }
            }
            Self::WaveletTrain { freq_hz, cycles, times_s } => {
                positive("freq_hz", *freq_hz)?;
                if !(cycles.is_finite() && *cycles >= 1.0) {
                    return Err(ControlError::InvalidParameter {
                        name: "cycles",
                        reason: format!("must be >= 1, got {cycles}"),
                    });
                }
                if times_s.is_empty() {
                    return Err(ControlError::Empty { input: "wavelet times" });
                }
                let width_s = cycles / freq_hz;
                for &t in times_s {
                    check_time("times_s", t)?;
                    let n = ((width_s * sample_rate_hz).round() as usize).clamp(1, len);
                    let first = t - width_s / 2.0;
                    for j in 0..n {
                        let tau = j as f64 / sample_rate_hz;
                        let window = 0.5 - 0.5 * (std::f64::consts::TAU * tau / width_s).cos();
                        let i = ((first + tau) * sample_rate_hz).round().rem_euclid(len as f64) as usize % len;
                        x[i] += window * (std::f64::consts::TAU * freq_hz * tau).sin();
                    }
                }
            }
        }
        Ok(x)
    }

    /// The impulse times, when the waveform is made of impulses.
    fn impulse_times(&self) -> &[f64] {
        match self {
            Self::Impulse { time_s } => std::slice::from_ref(time_s),
            Self::Impulses { times_s } => times_s,
            _ => &[],
        }
    }

    /// The same waveform `delay_s` later (every time it holds moved by `delay_s`; [`Waveform::Null`] and a
    /// whole-period sine stay as they are): a pattern placed after the lead its drive needs to build it.
    pub fn delayed(&self, delay_s: f64) -> Self {
        let shift = |times: &[f64]| times.iter().map(|t| t + delay_s).collect();
        match self {
            Self::Impulse { time_s } => Self::Impulse { time_s: time_s + delay_s },
            Self::Impulses { times_s } => Self::Impulses { times_s: shift(times_s) },
            Self::Noise { start_s, duration_s, seed } => {
                Self::Noise { start_s: start_s + delay_s, duration_s: *duration_s, seed: *seed }
            }
            Self::NoiseBursts { starts_s, duration_s, seed } => {
                Self::NoiseBursts { starts_s: shift(starts_s), duration_s: *duration_s, seed: *seed }
            }
            Self::Sine { freq_hz, start_s, duration_s } if *duration_s != 0.0 => {
                Self::Sine { freq_hz: *freq_hz, start_s: start_s + delay_s, duration_s: *duration_s }
            }
            Self::WaveletTrain { freq_hz, cycles, times_s } => {
                Self::WaveletTrain { freq_hz: *freq_hz, cycles: *cycles, times_s: shift(times_s) }
            }
            Self::Sine { .. } | Self::Null => self.clone(),
        }
    }

    /// True for [`Waveform::Null`].
    pub fn is_null(&self) -> bool {
        matches!(self, Self::Null)
    }
}

/// The target spectrum (unnormalised DFT, as [`fft::forward`]) of `target` at `g`'s bins, band-limited by `gains`
/// (from [`TargetBand::gains`]) and scaled so that the band-limited time signal peaks at `target.amplitude`.
///
/// Valid range: times inside the period `[0, fft_len / sample_rate_hz)`, positive finite frequencies and durations,
/// finite `amplitude >= 0`.
///
/// # Errors
/// [`ControlError::InvalidParameter`] or [`ControlError::Empty`] for a waveform outside that range;
/// [`ControlError::NonFiniteResult`] when a non-null waveform has no energy in the band (a sine outside it).
pub fn spectrum(target: &PixelTarget, g: &PropagationMatrices, gains: &[f64]) -> Result<Vec<Complex64>, ControlError> {
    let (n, fs) = (g.fft_len(), g.sample_rate_hz());
    if !(target.amplitude.is_finite() && target.amplitude >= 0.0) {
        return Err(ControlError::InvalidParameter {
            name: "amplitude",
            reason: format!("must be finite and >= 0, got {}", target.amplitude),
        });
    }
    let x = target.waveform.samples(n, fs)?;
    let full = fft::forward(&x, n)?;
    let mut band: Vec<Complex64> = g.bins().zip(gains).map(|(k, &w)| full[k] * w).collect();
    for &t in target.waveform.impulse_times() {
        for ((k, &w), b) in g.bins().zip(gains).zip(band.iter_mut()) {
            let phase = -std::f64::consts::TAU * fft::bin_freq_hz(k, n, fs) * t;
            *b += Complex64::from_polar(w, phase);
        }
    }
    if target.waveform.is_null() || target.amplitude == 0.0 {
        return Ok(vec![Complex64::new(0.0, 0.0); band.len()]);
    }
    let peak = band_signal(&band, g)?.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(peak.is_finite() && peak > 0.0) {
        return Err(ControlError::NonFiniteResult { what: "target with no energy in the band" });
    }
    let scale = target.amplitude / peak;
    Ok(band.into_iter().map(|b| b * scale).collect())
}

/// The real time signal (`fft_len` samples) whose spectrum is `band` at `g`'s bins and zero elsewhere.
///
/// # Errors
/// [`ControlError::LengthMismatch`] when `band.len() != g.n_bins()`; a DSP error for non-finite bins.
pub fn band_signal(band: &[Complex64], g: &PropagationMatrices) -> Result<Vec<f64>, ControlError> {
    if band.len() != g.n_bins() {
        return Err(ControlError::LengthMismatch { what: "band spectrum against bins", a: band.len(), b: g.n_bins() });
    }
    let n = g.fft_len();
    let mut full = vec![Complex64::new(0.0, 0.0); fft::bin_count(n)];
    full[g.bins()].copy_from_slice(band);
    Ok(fft::inverse(&full, n)?)
}

impl FromStr for Waveform {
    type Err = ControlError;

    /// Parses `impulse[@T]`, `impulses@T1,T2,...`, `noise@START,DURATION[,SEED]`, `sine@FREQ[,START,DURATION]`,
    /// `wavelets@FREQ,CYCLES,T1,T2,...` or `null` (times and durations in s, frequencies in Hz). `impulse` alone
    /// means an impulse at time 0 here; callers substitute their default focus time with [`Waveform::Impulse`].
    fn from_str(text: &str) -> Result<Self, ControlError> {
        let (kind, args) = text.split_once('@').unwrap_or((text, ""));
        let bad = |reason: String| ControlError::InvalidParameter { name: "target", reason };
        let nums: Vec<f64> = if args.is_empty() {
            Vec::new()
        } else {
            args.split(',')
                .map(|a| a.trim().parse::<f64>().map_err(|_| bad(format!("`{a}` in `{text}` is not a number"))))
                .collect::<Result<_, _>>()?
        };
        let arity = |min: usize, max: usize| {
            if (min..=max).contains(&nums.len()) {
                Ok(())
            } else {
                Err(bad(format!("`{text}`: {kind} takes {min} to {max} numbers after @, got {}", nums.len())))
            }
        };
        match kind.trim() {
            "impulse" => {
                arity(0, 1)?;
                Ok(Self::Impulse { time_s: nums.first().copied().unwrap_or(0.0) })
            }
            "impulses" => {
                arity(1, usize::MAX)?;
                Ok(Self::Impulses { times_s: nums })
            }
            "noise" => {
                arity(2, 3)?;
                Ok(Self::Noise { start_s: nums[0], duration_s: nums[1], seed: nums.get(2).map_or(0, |&s| s as u64) })
            }
            "sine" => {
                if nums.len() != 1 && nums.len() != 3 {
                    return Err(bad(format!("`{text}`: sine takes FREQ or FREQ,START,DURATION")));
                }
                let (start_s, duration_s) = if nums.len() == 3 { (nums[1], nums[2]) } else { (0.0, 0.0) };
                Ok(Self::Sine { freq_hz: nums[0], start_s, duration_s })
            }
            "wavelets" => {
                arity(3, usize::MAX)?;
                Ok(Self::WaveletTrain { freq_hz: nums[0], cycles: nums[1], times_s: nums[2..].to_vec() })
            }
            "null" => {
                arity(0, 0)?;
                Ok(Self::Null)
            }
            other => Err(bad(format!(
                "unknown target `{other}` (expected impulse, impulses, noise, sine, wavelets or null)"
            ))),
        }
    }
}

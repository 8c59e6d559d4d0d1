//! Band-limited resampling: a Kaiser-windowed sinc interpolator that evaluates a signal at arbitrary (evenly
//! stepped) fractional positions, used to put a recording back on the player's clock ([`crate::drift`]).

use std::f64::consts::PI;
use std::sync::OnceLock;

use crate::error::{DspError, check_finite, check_result};

/// log2 of [`Interpolator::PHASES`].
const PHASE_BITS: u32 = 12;

/// Longest output of [`Interpolator::resample`]: 2^27 samples (about 93 minutes at 24 kHz).
pub const MAX_RESAMPLE_LEN: usize = 1 << 27;

/// Band-limited interpolation by a Kaiser-windowed sinc, tabulated at [`Interpolator::PHASES`] fractional positions.
///
/// Accuracy on a full-scale sinusoid (worst error over fractional positions, measured in the tests), including the
/// table's rounding of the position to 1 / 8192 sample (a phase error of `2 pi f / 8192`, 1e-5 at 0.01 fs):
/// half-width 4: 2e-4 up to 0.1 fs; half-width 8: 3e-4 up to 0.3 fs; half-width 16: 4e-4 up to 0.4 fs. Above that
/// the kernel attenuates towards Nyquist. [`Interpolator::for_band`] picks the shortest that suits a band.
#[derive(Debug, Clone, PartialEq)]
pub struct Interpolator {
    half_width: usize,
    /// Row `p` holds the `2 * half_width` taps for fractional position `p / PHASES`, normalised to unit sum.
    table: Vec<f64>,
}

impl Interpolator {
    /// Fractional positions tabulated per sample.
    pub const PHASES: usize = 1 << PHASE_BITS;
    /// Largest half-width accepted, samples.
    pub const MAX_HALF_WIDTH: usize = 64;
    /// Kaiser window shape: beta 9 puts the window's sidelobes near -90 dB.
    const KAISER_BETA: f64 = 9.0;

    /// Builds the table for a kernel reaching `half_width` samples either side.
    ///
    /// # Errors
    /// [`DspError::InvalidParameter`] unless `1 <= half_width <= MAX_HALF_WIDTH`.
    pub fn new(half_width: usize) -> Result<Self, DspError> {
        if !(1..=Self::MAX_HALF_WIDTH).contains(&half_width) {
            return Err(DspError::InvalidParameter {
                name: "half_width",
                reason: format!("must lie in 1..={}, got {half_width}", Self::MAX_HALF_WIDTH),
            });
        }
        let taps = 2 * half_width;
        let h = half_width as f64;
        let i0_beta = bessel_i0(Self::KAISER_BETA);
        let mut table = Vec::with_capacity((Self::PHASES + 1) * taps);
        for p in 0..=Self::PHASES {
            let mu = p as f64 / Self::PHASES as f64;
            let row: Vec<f64> = (0..taps)
                .map(|i| {
                    let t = mu + h - 1.0 - i as f64;
                    let u = t / h;
                    let window =
                        if u.abs() < 1.0 { bessel_i0(Self::KAISER_BETA * (1.0 - u * u).sqrt()) / i0_beta } else { 0.0 };
                    sinc(t) * window
                })
                .collect();
            let sum: f64 = row.iter().sum();
            table.extend(row.iter().map(|v| v / sum));
        }
        Ok(Self { half_width, table })
    }

    /// The shortest shared interpolator (half-width 4, 8 or 16, each built once per process) accurate for content
    /// up to `max_freq_hz` at `sample_rate_hz` (see the accuracy table on the type); above 0.4 of the sample rate,
    /// the longest.
    pub fn for_band(max_freq_hz: f64, sample_rate_hz: f64) -> &'static Self {
        static SHORT: OnceLock<Interpolator> = OnceLock::new();
        static MEDIUM: OnceLock<Interpolator> = OnceLock::new();
        static LONG: OnceLock<Interpolator> = OnceLock::new();
        let rel = max_freq_hz / sample_rate_hz;
        let (cell, half_width) = if rel <= 0.1 {
            (&SHORT, 4)
        } else if rel <= 0.3 {
            (&MEDIUM, 8)
        } else {
            (&LONG, 16)
        };
        cell.get_or_init(|| Self::build(half_width))
    }

    fn build(half_width: usize) -> Self {
        match Self::new(half_width) {
            Ok(i) => i,
            // Called with 4, 8 or 16 only, so `new` cannot fail; nearest-sample interpolation (one tap at unit
            // gain) is only a formal fallback.
            Err(_) => Self { half_width: 1, table: [1.0, 0.0].repeat(Self::PHASES + 1) },
        }
    }

    /// Kernel half-width, samples.
    pub fn half_width(&self) -> usize {
        self.half_width
    }

    /// Samples `x` at positions `start_samples + j * step_samples` for `j` in `0..out_len`, treating `x` as zero
    /// outside its samples.
    ///
    /// Valid range: finite `x` (only the samples within the kernel's reach of the positions are read and checked);
    /// finite `start_samples` within `±MAX_RESAMPLE_LEN`; `0.5 <= step_samples <= 2`; `out_len <= MAX_RESAMPLE_LEN`.
    /// A step above 1 lowers the rate: content above `0.5 / step_samples` of the input rate then aliases, so the
    /// input must not have any (true of drift correction, where the step is within 1e-3 of 1 and the content far
    /// below Nyquist).
    ///
    /// # Errors
    /// [`DspError::NonFinite`] in the samples of `x` read; [`DspError::InvalidParameter`] for a start or step out of
    /// range; [`DspError::TooLong`] for `out_len`; [`DspError::NonFiniteResult`] if the output overflows.
    pub fn resample(
        &self,
        x: &[f64],
        start_samples: f64,
        step_samples: f64,
        out_len: usize,
    ) -> Result<Vec<f64>, DspError> {
        if out_len > MAX_RESAMPLE_LEN {
            return Err(DspError::TooLong { what: "resampled signal", len: out_len, max: MAX_RESAMPLE_LEN });
        }
        let mut out = vec![0.0; out_len];
        self.resample_into(x, start_samples, step_samples, &mut out)?;
        Ok(out)
    }

    /// [`Interpolator::resample`] into a caller's buffer: `out.len()` samples from position `start_samples` on.
    /// Resampling a long recording piece by piece into a buffer that stays in cache saves passes over memory.
    ///
    /// # Errors
    /// As [`Interpolator::resample`], with `out.len()` for `out_len`.
    pub fn resample_into(
        &self,
        x: &[f64],
        start_samples: f64,
        step_samples: f64,
        out: &mut [f64],
    ) -> Result<(), DspError> {
        let limit = MAX_RESAMPLE_LEN as f64;
        if !(start_samples.is_finite() && start_samples.abs() <= limit) {
            return Err(DspError::InvalidParameter {
                name: "start_samples",
                reason: format!("must be finite and within ±{limit}, got {start_samples}"),
            });
        }
        if !(0.5..=2.0).contains(&step_samples) {
            return Err(DspError::InvalidParameter {
                name: "step_samples",
                reason: format!("must lie in [0.5, 2], got {step_samples}"),
            });
        }
        if out.len() > MAX_RESAMPLE_LEN {
            return Err(DspError::TooLong { what: "resampled signal", len: out.len(), max: MAX_RESAMPLE_LEN });
        }
        let Some(last) = out.len().checked_sub(1) else { return Ok(()) };
        // The samples the kernel reaches from the first to the last position, with a margin for the rounding of
        // the positions to the table.
        let reach = self.half_width as f64 + 2.0;
        let end_samples = start_samples + last as f64 * step_samples;
        let lo = (start_samples - reach).floor().clamp(0.0, x.len() as f64) as usize;
        let hi = (end_samples + reach).ceil().clamp(0.0, x.len() as f64) as usize;
        if lo < hi {
            check_finite("signal to resample", &x[lo..hi]).map_err(|e| match e {
                DspError::NonFinite { input, index, value } => DspError::NonFinite { input, index: index + lo, value },
                other => other,
            })?;
        }
        // Fixed tap counts let the compiler unroll the inner product: three times faster than the generic loop.
        match self.half_width {
            4 => self.fill::<8>(x, start_samples, step_samples, out),
            8 => self.fill::<16>(x, start_samples, step_samples, out),
            16 => self.fill::<32>(x, start_samples, step_samples, out),
            _ => self.fill_any(x, start_samples, step_samples, out),
        }
        check_result("resampled signal", out)
    }

    /// Kernel row and first input index for output position `t`.
    fn locate(&self, t: f64) -> (usize, i64) {
        // floor and round by integer conversion: the f64 methods are library calls on baseline x86-64.
        let mut base = t as i64;
        if (base as f64) > t {
            base -= 1;
        }
        let phase = ((t - base as f64) * Self::PHASES as f64 + 0.5) as usize;
        (phase, base - self.half_width as i64 + 1)
    }

    fn fill<const TAPS: usize>(&self, x: &[f64], start: f64, step: f64, out: &mut [f64]) {
        let (rows, _) = self.table.as_chunks::<TAPS>();
        // Positions in fixed point, re-anchored to the exact `start + j * step` every block so that the rounding
        // of the step (2^-32 sample) cannot accumulate: integer steps replace two float-to-integer conversions per
        // output, the costliest part of the loop after the taps.
        const FRAC_BITS: u32 = 32;
        const BLOCK: usize = 4096;
        let scale = (1u64 << FRAC_BITS) as f64;
        let step_fixed = (step * scale).round() as i64;
        let half_phase = 1i64 << (FRAC_BITS - PHASE_BITS - 1);
        // Position rounded to the table's resolution, then split into kernel row and first input sample.
        let split = |pos: i64| {
            let rounded = (pos + half_phase) >> (FRAC_BITS - PHASE_BITS);
            ((rounded & (Self::PHASES as i64 - 1)) as usize, (rounded >> PHASE_BITS) - self.half_width as i64 + 1)
        };
        for (b, block) in out.chunks_mut(BLOCK).enumerate() {
            let mut pos = ((start + (b * BLOCK) as f64 * step) * scale).round() as i64;
            let (pairs, rest) = block.as_chunks_mut::<2>();
            for pair in pairs {
                let (phase, first) = split(pos);
                let (next_phase, next_first) = split(pos + step_fixed);
                // With a step near one sample, neighbours mostly share a kernel row (at 30 ppm of drift the row
                // changes every 8 outputs): then one pass over TAPS + 1 inputs serves both, as the two lanes of a
                // vector, with the same arithmetic as one at a time.
                let shared = if next_phase == phase && next_first == first + 1 {
                    rows.get(phase).zip(usize::try_from(first).ok().and_then(|f| x.get(f..f + TAPS + 1)))
                } else {
                    None
                };
                *pair = match shared {
                    Some((row, input)) => dot_pair(row, input),
                    None => [self.sample(rows, x, phase, first), self.sample(rows, x, next_phase, next_first)],
                };
                pos += 2 * step_fixed;
            }
            for y in rest {
                let (phase, first) = split(pos);
                *y = self.sample(rows, x, phase, first);
                pos += step_fixed;
            }
        }
    }

    /// One output from kernel row `phase` and inputs from `first` on.
    fn sample<const TAPS: usize>(&self, rows: &[[f64; TAPS]], x: &[f64], phase: usize, first: i64) -> f64 {
        let window = usize::try_from(first).ok().and_then(|f| x.get(f..)).and_then(|s| s.first_chunk::<TAPS>());
        match (rows.get(phase), window) {
            (Some(row), Some(input)) => dot_fixed(row, input),
            _ => self.edge_sample(x, phase, first),
        }
    }

    fn fill_any(&self, x: &[f64], start: f64, step: f64, out: &mut [f64]) {
        let taps = 2 * self.half_width;
        for (j, y) in out.iter_mut().enumerate() {
            let (phase, first) = self.locate(start + j as f64 * step);
            let row = &self.table[phase * taps..(phase + 1) * taps];
            *y = match usize::try_from(first).ok().and_then(|f| x.get(f..f + taps)) {
                Some(input) => row.iter().zip(input).map(|(w, v)| w * v).sum(),
                None => self.edge_sample(x, phase, first),
            };
        }
    }

    /// One output whose kernel overlaps the ends of `x` (zero beyond them).
    fn edge_sample(&self, x: &[f64], phase: usize, first: i64) -> f64 {
        let taps = 2 * self.half_width;
        let row = &self.table[phase * taps..(phase + 1) * taps];
        row.iter()
            .enumerate()
            .map(|(i, w)| {
                let idx = first + i as i64;
                if idx >= 0 && (idx as usize) < x.len() { w * x[idx as usize] } else { 0.0 }
            })
            .sum()
    }
}

/// Inner product of fixed length with four partial sums, which the compiler keeps in vector registers.
fn dot_fixed<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut acc = [0.0; 4];
    for i in 0..N {
        acc[i % 4] += a[i] * b[i];
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// [`dot_fixed`] of `a` with `x[..N]` and with `x[1..N + 1]` (`x` holds at least `N + 1` samples), term for term
/// the same sums, computed side by side.
fn dot_pair<const N: usize>(a: &[f64; N], x: &[f64]) -> [f64; 2] {
    let x = &x[..N + 1];
    let mut acc = [[0.0; 2]; 4];
    for i in 0..N {
        acc[i % 4][0] += a[i] * x[i];
        acc[i % 4][1] += a[i] * x[i + 1];
    }
    [(acc[0][0] + acc[1][0]) + (acc[2][0] + acc[3][0]), (acc[0][1] + acc[1][1]) + (acc[2][1] + acc[3][1])]
}

fn sinc(t: f64) -> f64 {
    if t == 0.0 { 1.0 } else { (PI * t).sin() / (PI * t) }
}

/// Modified Bessel function of the first kind, order 0, by its power series (converges for all real x; the
/// arguments here are at most 9, where 40 terms reach full f64 precision).
fn bessel_i0(x: f64) -> f64 {
    let q = x * x / 4.0;
    let mut term = 1.0;
    let mut sum = 1.0;
    for k in 1..60 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < sum * 1e-17 {
            break;
        }
    }
    sum
}

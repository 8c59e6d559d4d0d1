//! Fractional-octave smoothing of a response's power spectrum, the levels it gives over a band, and the
//! minimum-phase response of a magnitude.
//!
//! Why: an actuator measured on its own magnet also shows the plate's driving-point modes, peaks and notches of
//! +/-25 dB a few hertz wide. They belong to the plate at that one point, not to the actuator: an inverse filter
//! that inverted them would boost narrow notches by tens of dB, spend the amplifier's headroom there and lower the
//! signal-to-noise ratio of every other frequency at every other point. So the calibration flattens the actuator's
//! broadband response, the power averaged over a fraction of an octave, as loudspeakers are equalised, and states
//! its flatness on the same smoothing.

use num_complex::Complex64;

use crate::error::{DspError, check_result, check_signal};
use crate::{fft, impulse};

/// Power spectrum `power` (bins `0..=n/2` of an `n`-point DFT at `sample_rate_hz`) averaged over `1/fraction` of
/// an octave around each bin: bin `k` at `f` takes the mean of the bins from `f / 2^(1/fraction)` to
/// `f * 2^(1/fraction)` weighted by a triangle that peaks at `f`, whose equivalent width (area over peak) is
/// `1/fraction` of an octave; bin 0 is kept.
///
/// Why a triangle and not the plain mean over `f * 2^(+-1/(2 fraction))`: with a rectangular window, a narrow mode
/// steps the smoothed level up as it enters a bin's window and down as it leaves, by a dB or two for a strong one;
/// no smooth filter can flatten a step. A triangle's weights go to zero at its ends, so the smoothed level is
/// continuous.
///
/// Valid range: `power.len() == n / 2 + 1`, finite non-negative powers, `fraction` finite and >= 1 (1 is a whole
/// octave; 3 the usual third-octave), finite positive sample rate. Linear time (prefix sums): a bin whose window
/// holds power some 1e14 times below the total power under it comes back with a large relative error (rounding of
/// the sums), never below 0.
///
/// # Errors
/// [`DspError::LengthMismatch`], [`DspError::NonFinite`], [`DspError::InvalidParameter`] naming the bad argument.
pub fn fractional_octave_power(
    power: &[f64],
    n: usize,
    sample_rate_hz: f64,
    fraction: f64,
) -> Result<Vec<f64>, DspError> {
    smooth_power(power, n, sample_rate_hz, fraction, None)
}

/// As [`fractional_octave_power`], except that a bin inside `band_hz` (`lo..=hi`) averages only the bins inside
/// the band: a window reaching past the band's edge is cut there, so a response rolled off outside the band does not
/// pull its smoothed level down near the edge. Bins outside the band are smoothed as by [`fractional_octave_power`].
///
/// Valid range: as [`fractional_octave_power`], and `0 <= lo_hz < hi_hz`.
///
/// # Errors
/// As [`fractional_octave_power`]; [`DspError::InvalidParameter`] naming `band_hz` for a bad band.
pub fn fractional_octave_power_in_band(
    power: &[f64],
    n: usize,
    sample_rate_hz: f64,
    fraction: f64,
    band_hz: (f64, f64),
) -> Result<Vec<f64>, DspError> {
    let (lo_hz, hi_hz) = band_hz;
    if !(lo_hz.is_finite() && hi_hz.is_finite() && lo_hz >= 0.0 && lo_hz < hi_hz) {
        return Err(DspError::InvalidParameter {
            name: "band_hz",
            reason: format!("must satisfy 0 <= lo < hi, got {lo_hz} .. {hi_hz} Hz"),
        });
    }
    let bin = |f: f64| f * n as f64 / sample_rate_hz;
    // The bins whose frequencies lie in the band: ceil(lo) ..= floor(hi), empty when the band holds none.
    let first = bin(lo_hz).ceil().max(0.0) as usize;
    let last = bin(hi_hz).floor().max(0.0) as usize;
    smooth_power(power, n, sample_rate_hz, fraction, Some((first, last)))
}

/// The smoothing behind [`fractional_octave_power`] and [`fractional_octave_power_in_band`]: `limits`, when given,
/// are the first and last bins of a band whose bins average only among themselves.
fn smooth_power(
    power: &[f64],
    n: usize,
    sample_rate_hz: f64,
    fraction: f64,
    limits: Option<(usize, usize)>,
) -> Result<Vec<f64>, DspError> {
    if power.len() != fft::bin_count(n) {
        return Err(DspError::LengthMismatch {
            what: "power bins against n / 2 + 1",
            a: power.len(),
            b: fft::bin_count(n),
        });
    }
    check_signal("power", power)?;
    if power.iter().any(|p| *p < 0.0) {
        return Err(DspError::InvalidParameter { name: "power", reason: "must be >= 0 at every bin".into() });
    }
    if !(fraction.is_finite() && fraction >= 1.0) {
        return Err(DspError::InvalidParameter { name: "fraction", reason: format!("must be >= 1, got {fraction}") });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(DspError::InvalidParameter {
            name: "sample_rate_hz",
            reason: format!("must be finite and positive, got {sample_rate_hz}"),
        });
    }
    // Prefix sums of P_j and j P_j: a triangle's weighted sum over any range is a combination of the two.
    let mut sum_p = Vec::with_capacity(power.len() + 1);
    let mut sum_jp = Vec::with_capacity(power.len() + 1);
    sum_p.push(0.0);
    sum_jp.push(0.0);
    for (j, p) in power.iter().enumerate() {
        sum_p.push(sum_p[j] + p);
        sum_jp.push(sum_jp[j] + j as f64 * p);
    }
    let range = |v: &[f64], lo: usize, hi: usize| v[hi + 1] - v[lo];
    let span = 2f64.powf(1.0 / fraction);
    let top = power.len() - 1;
    let smoothed: Vec<f64> = (0..power.len())
        .map(|k| {
            if k == 0 {
                return power[0];
            }
            // The triangle rises from k / span to 1 at k and falls to 0 at k span (bin numbers scale with
            // frequency): its weights are (j - left) / (k - left) below k and (right - j) / (right - k) above.
            let (kf, left, right) = (k as f64, k as f64 / span, k as f64 * span);
            let mut lo = (left.ceil() as usize).clamp(1, k);
            let mut hi = (right.floor() as usize).clamp(k, top);
            if let Some((first, last)) = limits.filter(|(first, last)| (*first..=*last).contains(&k)) {
                lo = lo.max(first);
                hi = hi.min(last);
            }
            let ones = |a: usize, b: usize| ((b + 1 - a) as f64, (a + b) as f64 * (b + 1 - a) as f64 / 2.0);
            let (below_n, below_j) = ones(lo, k);
            let mut numerator = (range(&sum_jp, lo, k) - left * range(&sum_p, lo, k)) / (kf - left);
            let mut denominator = (below_j - left * below_n) / (kf - left);
            if hi > k {
                let (above_n, above_j) = ones(k + 1, hi);
                numerator += (right * range(&sum_p, k + 1, hi) - range(&sum_jp, k + 1, hi)) / (right - kf);
                denominator += (right * above_n - above_j) / (right - kf);
            }
            // Differences of prefix sums can round below zero where the power is far below what lies under it.
            (numerator / denominator).max(0.0)
        })
        .collect();
    check_result("smoothed power", &smoothed)?;
    Ok(smoothed)
}

/// Levels of `ir`'s power spectrum smoothed over `1/fraction` of an octave within `band_hz`
/// ([`fractional_octave_power_in_band`]), dB re 1 (units of `ir`), as `(freq_hz, level_db)` at every bin of a
/// zero-padded FFT (at least twice `ir`'s length) inside the band.
///
/// Valid range: a finite, non-empty `ir`; `fraction` and `sample_rate_hz` as [`fractional_octave_power`]; a band
/// holding at least one bin.
///
/// # Errors
/// As [`fractional_octave_power_in_band`]; [`DspError::InvalidParameter`] for a band with no bin, or a response
/// with no power somewhere in the band (its level would be -infinity).
pub fn smoothed_levels_db(
    ir: &[f64],
    sample_rate_hz: f64,
    fraction: f64,
    band_hz: (f64, f64),
) -> Result<Vec<(f64, f64)>, DspError> {
    check_signal("response", ir)?;
    let n = fft::fast_len(2 * ir.len())?;
    let power: Vec<f64> = fft::forward(ir, n)?.iter().map(Complex64::norm_sqr).collect();
    let smoothed = fractional_octave_power_in_band(&power, n, sample_rate_hz, fraction, band_hz)?;
    band_levels_db(&smoothed, n, sample_rate_hz, band_hz)
}

/// Levels of `ir`'s magnitude spectrum (an FFT of `ir`'s own length, no padding) smoothed by pyfar's standard
/// fractional-octave smoothing ([`fractional_octave_standard`]), dB re 1 (units of `ir`), as `(freq_hz, level_db)`
/// at every bin inside `band_hz`: the flatness others would report. Its window reaches half of `1/fraction` of an
/// octave beyond the band's edges and is not cut there.
///
/// Valid range: a finite `ir` of at least 6 samples; `fraction` as [`fractional_octave_standard`]; a band holding at
/// least one bin.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for `ir`; [`DspError::InvalidParameter`] for a band holding no bin,
/// a bad `fraction`, or a smoothed level of zero in the band.
pub fn standard_levels_db(
    ir: &[f64],
    sample_rate_hz: f64,
    fraction: f64,
    band_hz: (f64, f64),
) -> Result<Vec<(f64, f64)>, DspError> {
    let n = ir.len();
    if n < 6 {
        return Err(DspError::Empty { input: "response (at least 6 samples)" });
    }
    let magnitude: Vec<f64> = fft::forward(ir, n)?.iter().map(|c| c.norm()).collect();
    let (smoothed, _) = fractional_octave_standard(&magnitude, fraction)?;
    // A spline can overshoot below zero next to a deep notch: that is no level (refused below), not its square.
    let power: Vec<f64> = smoothed.iter().map(|m| if *m > 0.0 { m * m } else { 0.0 }).collect();
    band_levels_db(&power, n, sample_rate_hz, band_hz)
}

/// `(freq_hz, 10 log10(power))` at the bins of an `n`-point DFT inside `band_hz`.
pub(crate) fn band_levels_db(
    power: &[f64],
    n: usize,
    sample_rate_hz: f64,
    band_hz: (f64, f64),
) -> Result<Vec<(f64, f64)>, DspError> {
    let mut levels = Vec::new();
    for (k, p) in power.iter().enumerate() {
        let f = fft::bin_freq_hz(k, n, sample_rate_hz);
        if (band_hz.0..=band_hz.1).contains(&f) {
            if *p <= 0.0 {
                return Err(DspError::InvalidParameter {
                    name: "response",
                    reason: format!("has no power at {f:.1} Hz, inside the band"),
                });
            }
            levels.push((f, 10.0 * p.log10()));
        }
    }
    if levels.is_empty() {
        return Err(DspError::InvalidParameter {
            name: "band_hz",
            reason: format!("{} to {} Hz holds no bin of a {n}-point FFT at {sample_rate_hz} Hz", band_hz.0, band_hz.1),
        });
    }
    Ok(levels)
}

/// The minimum-phase response with magnitude `magnitude` (bins `0..=n/2` of an `n`-point DFT): `len` samples, zero
/// before time 0 at sample `pre_samples`, then the first `len - pre_samples` samples of the response.
///
/// Valid range: as [`impulse::minimum_phase_spectrum`]; `pre_samples < len <= n + pre_samples`. Pad the cepstrum
/// (a larger `n`) for a magnitude with sharp features, whose minimum-phase response is long.
///
/// # Errors
/// As [`impulse::minimum_phase_spectrum`]; [`DspError::InvalidParameter`] for `len` or `pre_samples`.
pub fn minimum_phase_response(
    magnitude: &[f64],
    n: usize,
    len: usize,
    pre_samples: usize,
) -> Result<Vec<f64>, DspError> {
    if pre_samples >= len || len - pre_samples > n {
        return Err(DspError::InvalidParameter {
            name: "len",
            reason: format!("need pre_samples ({pre_samples}) < len ({len}) <= n ({n}) + pre_samples"),
        });
    }
    let spectrum = impulse::minimum_phase_spectrum(magnitude, n)?;
    let min_phase = fft::inverse(&spectrum, n)?;
    let mut out = vec![0.0; pre_samples];
    out.extend_from_slice(&min_phase[..len - pre_samples]);
    check_result("minimum-phase response", &out)?;
    Ok(out)
}

/// Fractional-octave smoothing of a magnitude response as pyfar's `smooth_fractional_octave` does it (its default,
/// `mode="magnitude_zerophase"`, `window="boxcar"`; Tylka et al. 2017, method 2), the smoothing others report
/// flatness with: `magnitude` (bins `0..N` of a real DFT, `|H|`) is interpolated by a not-a-knot cubic spline onto
/// `N` logarithmically spaced points (bin `k` at `N^(k / (N - 1)) - 1`), averaged by a moving mean of
/// `n_window = 2 floor(1 / (2 fraction dn)) + 1` of them (`dn = log2(N^(1/(N-1)))` octaves apart; the edges
/// repeat the end values), and interpolated back. Returns the smoothed magnitude and `n_window`.
///
/// How it differs from [`fractional_octave_power`]: it averages the magnitude, not the power (a narrow peak counts
/// less, a narrow notch more), with a rectangular window (a mode entering or leaving the window steps the level),
/// over the whole spectrum (a roll-off outside a band pulls the level inside it near the edge), and through two
/// interpolations, the first of which samples the high octaves sparsely (points about `ln N` bins apart at the top).
///
/// Valid range: `magnitude` of at least 4 finite values; `fraction` finite and > 0, small enough that the window
/// holds more than one point (`n_window > 1`). Agrees with pyfar 0.8.1 to 3e-15 of the peak
/// (`tests/pyfar_crosscheck.rs`).
///
/// # Errors
/// [`DspError::Empty`] for fewer than 4 values, [`DspError::NonFinite`] for a non-finite one,
/// [`DspError::InvalidParameter`] naming `fraction` when it is out of range or too narrow for the resolution.
pub fn fractional_octave_standard(magnitude: &[f64], fraction: f64) -> Result<(Vec<f64>, usize), DspError> {
    let n = magnitude.len();
    if n < 4 {
        return Err(DspError::Empty { input: "magnitude (at least 4 bins)" });
    }
    check_signal("magnitude", magnitude)?;
    if !(fraction.is_finite() && fraction > 0.0) {
        return Err(DspError::InvalidParameter {
            name: "fraction",
            reason: format!("must be finite and > 0, got {fraction}"),
        });
    }
    let nf = n as f64;
    let lin: Vec<f64> = (1..=n).map(|k| k as f64).collect();
    let log: Vec<f64> = (0..n).map(|k| nf.powf(k as f64 / (nf - 1.0))).collect();
    let dn = log[1].log2();
    let n_window = 2 * (1.0 / (fraction * dn * 2.0)).floor() as usize + 1;
    if n_window <= 1 {
        return Err(DspError::InvalidParameter {
            name: "fraction",
            reason: format!(
                "1/{fraction} octave is below the resolution of {n} bins: use a longer response or a smaller fraction"
            ),
        });
    }
    let on_log = NotAKnotSpline::new(&lin, magnitude).eval_sorted(&log);
    let half = n_window / 2;
    // Moving mean with the end values repeated (scipy's `mode="nearest"`), by a running sum.
    let at = |i: isize| on_log[i.clamp(0, n as isize - 1) as usize];
    let mut sum: f64 = (-(half as isize)..=half as isize).map(at).sum();
    let mut averaged = Vec::with_capacity(n);
    for i in 0..n as isize {
        averaged.push(sum / n_window as f64);
        sum += at(i + half as isize + 1) - at(i - half as isize);
    }
    let back = NotAKnotSpline::new(&log, &averaged).eval_sorted(&lin);
    check_result("smoothed magnitude", &back)?;
    Ok((back, n_window))
}

/// The cubic spline through `(x, y)` with not-a-knot ends (the third derivative continuous at the second and the
/// last-but-one knot), as scipy's `interp1d(kind="cubic")` builds it. Needs at least 4 knots, `x` strictly
/// increasing.
struct NotAKnotSpline<'a> {
    x: &'a [f64],
    y: &'a [f64],
    /// Second derivatives at the knots.
    m: Vec<f64>,
}

impl<'a> NotAKnotSpline<'a> {
    fn new(x: &'a [f64], y: &'a [f64]) -> Self {
        let n = x.len();
        let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        // Equations for M_1 ..= M_{n-2}: h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = r_i, with M_0 and
        // M_{n-1} eliminated by the not-a-knot conditions: a tridiagonal system, solved by Thomas' algorithm.
        let k = n - 2;
        let (mut sub, mut diag, mut sup, mut rhs) = (vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]);
        for j in 0..k {
            let i = j + 1;
            sub[j] = h[i - 1];
            diag[j] = 2.0 * (h[i - 1] + h[i]);
            sup[j] = h[i];
            rhs[j] = 6.0 * ((y[i + 1] - y[i]) / h[i] - (y[i] - y[i - 1]) / h[i - 1]);
        }
        let (h0, h1) = (h[0], h[1]);
        let (ha, hb) = (h[n - 3], h[n - 2]);
        // At least 4 knots: k >= 2, so the first and last rows are distinct.
        diag[0] = (h0 + h1) * (h0 + 2.0 * h1) / h1;
        sup[0] = (h1 * h1 - h0 * h0) / h1;
        sub[k - 1] = (ha * ha - hb * hb) / ha;
        diag[k - 1] = (ha + hb) * (2.0 * ha + hb) / ha;
        for j in 1..k {
            let w = sub[j] / diag[j - 1];
            diag[j] -= w * sup[j - 1];
            rhs[j] -= w * rhs[j - 1];
        }
        let mut inner = vec![0.0; k];
        inner[k - 1] = rhs[k - 1] / diag[k - 1];
        for j in (0..k - 1).rev() {
            inner[j] = (rhs[j] - sup[j] * inner[j + 1]) / diag[j];
        }
        let mut m = Vec::with_capacity(n);
        m.push(((h0 + h1) * inner[0] - h0 * inner[1]) / h1);
        m.extend_from_slice(&inner);
        m.push(((ha + hb) * inner[k - 1] - hb * inner[k - 2]) / ha);
        Self { x, y, m }
    }

    /// The spline at `xs` (ascending, within the knots' range; outside it the end pieces are extended).
    fn eval_sorted(&self, xs: &[f64]) -> Vec<f64> {
        let (x, y, m) = (self.x, self.y, &self.m);
        let last = x.len() - 2;
        let mut i = 0;
        xs.iter()
            .map(|&t| {
                while i < last && t > x[i + 1] {
                    i += 1;
                }
                let h = x[i + 1] - x[i];
                let (a, b) = (x[i + 1] - t, t - x[i]);
                m[i] * a * a * a / (6.0 * h)
                    + m[i + 1] * b * b * b / (6.0 * h)
                    + (y[i] / h - m[i] * h / 6.0) * a
                    + (y[i + 1] / h - m[i + 1] * h / 6.0) * b
            })
            .collect()
    }
}

//! An actuator equaliser: the Kirkeby inverse of a response's fractional-octave-smoothed magnitude, refined until
//! the response through it, smoothed the same way (and, if asked, on pyfar's standard smoothing too), is flat over a
//! band.
//!
//! Why smoothed: see [`crate::smooth`] (the plate's narrow driving-point modes are left alone). Why refined:
//! inverting the smoothed power `S` of a response `R` does not make the smoothed `|R H|^2` flat. Where the response
//! falls steeply, or has a strong mode within a window, the average of the product is not the product of the
//! averages; on the mock lab's magnets one design left -3.3 .. +1.3 dB. The compensated response is known from the
//! measured response and the taps alone, so each pass predicts the verification a measurement through the taps
//! would give (the response through the taps, cut to the response's own length and time 0), fits a smooth gain that
//! flattens that prediction and designs again; a verification measurement then confirms it.
//!
//! Two smoothings: the project's (power, triangular window cut at the band's edges: [`crate::smooth::
//! fractional_octave_power_in_band`]) and pyfar's standard one (magnitude, rectangular window over the whole
//! spectrum: [`crate::smooth::fractional_octave_standard`]), as others report flatness. Over the plate's narrow
//! driving-point modes they differ by as much as the response is peaky within a window (0 to -2.2 dB on the mock
//! lab's metamaterial magnets), so a gain flattening one leaves that difference on the other; with
//! [`EqualiserConfig::standard`] the fit aims between them, weighing both in dB. The standard window also reaches
//! half a window past the band ([`EqualiserConfig::fit_band_hz`]), where the response must have been measured and the
//! filter be allowed to invert: the Kirkeby band must cover that reach, else the design is refused.
//!
//! The gain is piecewise linear in log-frequency, on the magnitude, with nodes half a smoothing window apart (an
//! eighth with the standard smoothing, whose rectangular window steps within a few hertz as strong modes enter and
//! leave it): the standard smoothing is linear in its node values, the project's (of power) quadratic and linearised
//! about the current design (one Gauss-Newton step a pass). The node values make the largest deviation in dB of
//! either smoothing from its own level smallest (Lawson's reweighted least squares over [`crate::lstsq`]), with a
//! small ridge towards 1 and at most +/-3 dB a pass, so the fit stays where the Kirkeby design can follow it.

use num_complex::Complex64;

use crate::error::{DspError, check_signal};
use crate::fft;
use crate::kirkeby::{KirkebyConfig, KirkebyFilter, design};
use crate::lstsq::least_squares;
use crate::smooth::{
    fractional_octave_power_in_band, fractional_octave_standard, minimum_phase_response, smoothed_levels_db,
    standard_levels_db,
};

/// The band the calibration measures and lets its filter invert, Hz: its sweep, its deconvolution's band limit and
/// its Kirkeby band ([`EqualiserConfig::calibration`]). It reaches past the scan's band, 62 to 625 Hz, by more than
/// half a third of an octave (55.2 to 701.5 Hz), so that pyfar's standard third-octave window at the scan band's
/// edges averages measured, equalised response and not the sweep's roll-off.
pub const CALIBRATION_MEASURED_BAND_HZ: (f64, f64) = (50.0, 710.0);

/// What [`design_equaliser`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct EqualiserConfig {
    /// The inverse filter design; its `response_delay_samples` is where the response's time 0 lies.
    pub kirkeby: KirkebyConfig,
    /// Octave fraction of the smoothing (3: a third of an octave); >= 1.
    pub fraction: f64,
    /// Band over which the compensated response is made flat, Hz (`0 <= lo < hi <= sample_rate / 2`). The smoothing
    /// windows of bins inside it are cut at its edges ([`fractional_octave_power_in_band`]).
    pub band_hz: (f64, f64),
    /// Stop refining once the predicted smoothed response (on each smoothing judged) is within this many dB of its
    /// median over the band; > 0.
    pub tolerance_db: f64,
    /// Designs at most, 1 to 64 (1: no refinement).
    pub max_designs: usize,
    /// Also flatten the compensated response on pyfar's standard smoothing (same `fraction`) over `band_hz`, as
    /// [`standard_levels_db`] reads the response through the taps cut to the response's own length. Needs the
    /// Kirkeby band to cover [`EqualiserConfig::fit_band_hz`].
    pub standard: bool,
}

impl EqualiserConfig {
    /// The paper's calibration settings around `kirkeby`: third-octave smoothing, flat over 62..625 Hz (the scan's
    /// band) on both the project's and pyfar's standard smoothing, refined until within 0.25 dB predicted, at most
    /// 16 designs; the Kirkeby band (`kirkeby.profile.band`, its skirts kept) set to
    /// [`CALIBRATION_MEASURED_BAND_HZ`], which the standard window at 62 and 625 Hz reaches into. The one home of
    /// these numbers: the calibrate recipe and the ground truth both design with them.
    pub fn calibration(kirkeby: KirkebyConfig) -> Self {
        let mut kirkeby = kirkeby;
        (kirkeby.profile.band.lo_hz, kirkeby.profile.band.hi_hz) = CALIBRATION_MEASURED_BAND_HZ;
        Self { kirkeby, fraction: 3.0, band_hz: (62.0, 625.0), tolerance_db: 0.25, max_designs: 16, standard: true }
    }

    /// The band the gain is fitted over, Hz: `band_hz`, widened with [`EqualiserConfig::standard`] by half a
    /// smoothing window (`2^(1/(2 fraction))`) at each end, where the standard smoothing's window at the band's edges
    /// reaches (55.2 to 701.5 Hz for the calibration's third octave over 62 to 625 Hz).
    pub fn fit_band_hz(&self) -> (f64, f64) {
        let (lo, hi) = self.band_hz;
        if self.standard {
            let half = 2f64.powf(1.0 / (2.0 * self.fraction));
            (lo / half, hi * half)
        } else {
            (lo, hi)
        }
    }
}

/// A designed equaliser.
#[derive(Debug, Clone, PartialEq)]
pub struct Equaliser {
    /// The inverse filter (the best design made: the smallest predicted deviation, the larger of the two smoothings'
    /// when both are judged).
    pub filter: KirkebyFilter,
    /// Predicted smoothed compensated response over the band, on the project's smoothing: its lowest and highest
    /// level relative to its median, dB (`min <= 0 <= max`).
    pub predicted_range_db: (f64, f64),
    /// The same on pyfar's standard smoothing, with [`EqualiserConfig::standard`] (else `None`).
    pub predicted_standard_range_db: Option<(f64, f64)>,
    /// Designs made (the best may be an earlier one).
    pub designs: usize,
}

impl Equaliser {
    /// The predicted larger excursion from the median on the project's smoothing, dB.
    pub fn predicted_deviation_db(&self) -> f64 {
        deviation(self.predicted_range_db)
    }

    /// The predicted larger excursion from the median on pyfar's standard smoothing, dB, when it was judged.
    pub fn predicted_standard_deviation_db(&self) -> Option<f64> {
        self.predicted_standard_range_db.map(deviation)
    }

    /// The larger of the predicted deviations on every smoothing judged, dB.
    pub fn predicted_worst_deviation_db(&self) -> f64 {
        self.predicted_deviation_db().max(self.predicted_standard_deviation_db().unwrap_or(0.0))
    }
}

/// The larger excursion of a `(lowest, highest)` range about the median ([`range_about_median`]), dB.
pub fn deviation((lo, hi): (f64, f64)) -> f64 {
    hi.max(-lo)
}

/// Designs the equaliser of `response` (sampled at `cfg.kirkeby.sample_rate_hz`, time 0 at
/// `cfg.kirkeby.response_delay_samples`).
///
/// Valid range: a finite response with power at every bin of the band (and, with [`EqualiserConfig::standard`], of
/// at least 6 samples, long enough for the standard smoothing's resolution); `cfg` as its fields state, the Kirkeby
/// configuration as [`KirkebyConfig::validate`]. What the design cannot reach it reports: the predicted ranges of
/// the best design.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for the response; [`DspError::InvalidParameter`] for a
/// configuration outside its range, a response without power in the band, or (with the standard smoothing) a
/// Kirkeby band that does not cover [`EqualiserConfig::fit_band_hz`]: the filter may not invert where the standard
/// window reaches, so it could not flatten it; the errors of [`design`].
pub fn design_equaliser(response: &[f64], cfg: &EqualiserConfig) -> Result<Equaliser, DspError> {
    check_signal("actuator response", response)?;
    let invalid = |name: &'static str, reason: String| Err(DspError::InvalidParameter { name, reason });
    if !(cfg.tolerance_db.is_finite() && cfg.tolerance_db > 0.0) {
        return invalid("tolerance_db", format!("must be finite and positive, got {}", cfg.tolerance_db));
    }
    if !(1..=64).contains(&cfg.max_designs) {
        return invalid("max_designs", format!("must be 1 to 64, got {}", cfg.max_designs));
    }
    let pre_samples = cfg.kirkeby.response_delay_samples;
    if pre_samples >= response.len() {
        return invalid("kirkeby.response_delay_samples", format!("must be below {}", response.len()));
    }
    if cfg.standard {
        let (lo, hi) = cfg.fit_band_hz();
        let band = &cfg.kirkeby.profile.band;
        if lo < band.lo_hz || hi > band.hi_hz {
            return invalid(
                "kirkeby.profile.band",
                format!(
                    "{:.1} to {:.1} Hz does not cover {lo:.1} to {hi:.1} Hz, where the standard smoothing's window at \
                     the band's edges {:?} Hz reaches: the filter may not invert there, so it cannot flatten it \
                     (measure and invert a wider band, or judge a narrower one)",
                    band.lo_hz, band.hi_hz, cfg.band_hz
                ),
            );
        }
    }
    let fs = cfg.kirkeby.sample_rate_hz;
    let len = response.len();
    let delay = cfg.kirkeby.modelling_delay_samples;
    // Long enough for the compensated response (response * taps) without wrap-around, and twice that so the
    // minimum-phase model's cepstrum is not time-aliased.
    let n = fft::fast_len(2 * (len + cfg.kirkeby.fir_len))?;
    let spectrum = fft::forward(response, n)?;
    let power: Vec<f64> = spectrum.iter().map(Complex64::norm_sqr).collect();
    let mut target = fractional_octave_power_in_band(&power, n, fs, cfg.fraction, cfg.band_hz)?;
    let mut best: Option<Equaliser> = None;
    let mut made = 0;
    for designs in 1..=cfg.max_designs {
        made = designs;
        let magnitude: Vec<f64> = target.iter().map(|p| p.sqrt()).collect();
        let model = minimum_phase_response(&magnitude, n, len, pre_samples)?;
        let filter = design(&model, &cfg.kirkeby)?;
        // The verification a measurement through the taps would give: the response through them, advanced by the
        // modelling delay (the verification's loopback carries it) and cut to the response's length.
        let taps_spectrum = fft::forward(&filter.taps, n)?;
        let through: Vec<Complex64> = spectrum.iter().zip(&taps_spectrum).map(|(r, h)| r * h).collect();
        let verification = fft::inverse(&through, n)?[delay..delay + len].to_vec();
        let own = smoothed_levels_db(&verification, fs, cfg.fraction, cfg.band_hz)?;
        let standard =
            if cfg.standard { Some(standard_levels_db(&verification, fs, cfg.fraction, cfg.band_hz)?) } else { None };
        let candidate = Equaliser {
            filter,
            predicted_range_db: range_about_median(&own),
            predicted_standard_range_db: standard.as_deref().map(range_about_median),
            designs,
        };
        let worst = candidate.predicted_worst_deviation_db();
        if best.as_ref().is_none_or(|b| worst < b.predicted_worst_deviation_db()) {
            best = Some(candidate);
        }
        if worst <= cfg.tolerance_db || designs == cfg.max_designs {
            break;
        }
        // The correction: the compensated magnitude times a smooth gain a(f) = sum_i g_i phi_i(f) (hat functions on
        // log-frequency nodes), with the g_i chosen so that the smoothed predictions are flat. A bin's smoothed
        // level is mostly the modes' in its window, not its own, so a per-bin correction would chase them and not
        // converge.
        let gain = flattening_gain(&verification, cfg)?;
        for (k, t) in target.iter_mut().enumerate() {
            *t /= gain.at(fft::bin_freq_hz(k, n, fs)).powi(2);
        }
    }
    let mut best =
        best.ok_or_else(|| DspError::InvalidParameter { name: "max_designs", reason: "no design was made".into() })?;
    best.designs = made;
    Ok(best)
}

/// The lowest and highest of `levels` relative to their median, dB; `levels` is non-empty and finite (the
/// smoothing functions' guarantee), else 0.
pub fn range_about_median(levels: &[(f64, f64)]) -> (f64, f64) {
    let mut values: Vec<f64> = levels.iter().map(|(_, l)| *l).collect();
    let median_db = crate::stats::median(&mut values).unwrap_or(0.0);
    values.iter().fold((0.0, 0.0), |(lo, hi): (f64, f64), l| (lo.min(l - median_db), hi.max(l - median_db)))
}

/// A piecewise-linear gain on log-frequency: `values[i]` at node `i`, nodes `step` octaves apart from `log2_lo`, the
/// end values held beyond the ends.
struct NodeGain {
    log2_lo: f64,
    step: f64,
    values: Vec<f64>,
}

impl NodeGain {
    /// Position of `f_hz` in node units, clamped to the nodes.
    fn position(&self, f_hz: f64) -> f64 {
        ((f_hz.max(1e-9).log2() - self.log2_lo) / self.step).clamp(0.0, (self.values.len() - 1) as f64)
    }

    /// The hat function of node `i` at `f_hz` (the hats sum to 1 everywhere).
    fn hat(&self, i: usize, f_hz: f64) -> f64 {
        (1.0 - (self.position(f_hz) - i as f64).abs()).max(0.0)
    }

    /// The gain at `f_hz`.
    fn at(&self, f_hz: f64) -> f64 {
        let x = self.position(f_hz);
        let i = (x.floor() as usize).min(self.values.len() - 1);
        let frac = x - i as f64;
        let next = self.values.get(i + 1).copied().unwrap_or(self.values[i]);
        self.values[i] * (1.0 - frac) + next * frac
    }
}

/// dB per relative change of a power (10 / ln 10) and of a magnitude (20 / ln 10): the fit's rows are in dB.
const DB_PER_POWER: f64 = 4.342_944_819_032_518;
const DB_PER_MAGNITUDE: f64 = 2.0 * DB_PER_POWER;

/// The smooth magnitude gain `a(f)` that, multiplying `verification`'s spectrum, makes its smoothed levels (on the
/// project's smoothing, and with `cfg.standard` on the standard one) as flat as it can over the band: the largest
/// deviation in dB of either from its own level (a free constant each) made smallest, by Lawson's iteratively
/// reweighted least squares.
fn flattening_gain(verification: &[f64], cfg: &EqualiserConfig) -> Result<NodeGain, DspError> {
    let fs = cfg.kirkeby.sample_rate_hz;
    let (lo_hz, hi_hz) = cfg.band_hz;
    let (fit_lo_hz, fit_hi_hz) = cfg.fit_band_hz();
    let len = verification.len();
    // The project's smoothing on the grid smoothed_levels_db uses (twice the length), the standard one on the
    // response's own (standard_levels_db).
    let own_n = fft::fast_len(2 * len)?;
    let own_power: Vec<f64> = fft::forward(verification, own_n)?.iter().map(Complex64::norm_sqr).collect();
    let octaves = (fit_hi_hz / fit_lo_hz.max(fs / own_n as f64)).log2();
    // With the standard smoothing the nodes lie an eighth of a window apart (a 24th of an octave for a third):
    // its rectangular window steps by up to 1.7 dB within a few hertz as strong modes enter and leave it (measured
    // on the mock lab's magnets), and only a gain that fine can balance the two smoothings there (nodes a sixth of an
    // octave apart left 1.3 to 1.7 dB, a 12th 0.4 to 0.6 dB, a 24th 0.13 to 0.21 dB, predicted on three of them).
    // Alone, the project's smoothing needs no more than half a window.
    let per_window = if cfg.standard { 8.0 } else { 2.0 };
    let nodes = ((octaves * per_window * cfg.fraction).ceil() as usize + 1).max(2);
    let mut gain =
        NodeGain { log2_lo: fit_hi_hz.log2() - octaves, step: octaves / (nodes - 1) as f64, values: vec![1.0; nodes] };
    let in_band = |n: usize| -> Vec<usize> {
        (0..fft::bin_count(n)).filter(|k| (lo_hz..=hi_hz).contains(&fft::bin_freq_hz(*k, n, fs))).collect()
    };
    // The rows, in dB. Own (power, linearised about the current design, a = 1): S[P a^2] ~ S[P (2 a - 1)] =
    // sum_i g_i 2 S[P phi_i] - S[P] (the hats sum to 1), so its level moves by DB_PER_POWER (sum_i g_i 2 S[P phi_i]
    // / S[P] - 2) dB; standard (magnitude, exactly linear): DB_PER_MAGNITUDE (sum_i g_i S[|V| phi_i] / S[|V|] - 1).
    // Each row asks the level (now `now_db`, relative to the median) plus that move to equal its smoothing's
    // constant, a further unknown.
    let own_rows = in_band(own_n);
    let own_now = fractional_octave_power_in_band(&own_power, own_n, fs, cfg.fraction, cfg.band_hz)?;
    let own_level = median_of(own_rows.iter().map(|k| own_now[*k]));
    let std_magnitude: Option<Vec<f64>> =
        if cfg.standard { Some(fft::forward(verification, len)?.iter().map(|c| c.norm()).collect()) } else { None };
    let std_rows = if cfg.standard { in_band(len) } else { Vec::new() };
    let std_now = match &std_magnitude {
        Some(m) => fractional_octave_standard(m, cfg.fraction)?.0,
        None => Vec::new(),
    };
    let std_level = median_of(std_rows.iter().map(|k| std_now[*k]));
    let offsets = if cfg.standard { 2 } else { 1 };
    let cols = nodes + offsets;
    let fit_rows = own_rows.len() + std_rows.len();
    let mut a = vec![0.0; fit_rows * cols];
    let mut b = vec![0.0; fit_rows];
    // Each bin's starting weight is the octaves it spans (k bins per octave at bin k), so every octave counts alike
    // (bins are spaced linearly; the band's low octave holds few).
    let mut weight = vec![0.0; fit_rows];
    for (r, k) in own_rows.iter().enumerate() {
        b[r] = 2.0 * DB_PER_POWER - DB_PER_POWER * (own_now[*k] / own_level).ln();
        a[r * cols + nodes] = -1.0;
        weight[r] = 1.0 / *k.max(&1) as f64;
    }
    let std_row0 = own_rows.len();
    for (r, k) in std_rows.iter().enumerate() {
        b[std_row0 + r] = DB_PER_MAGNITUDE - DB_PER_MAGNITUDE * (std_now[*k] / std_level).ln();
        a[(std_row0 + r) * cols + nodes + 1] = -1.0;
        weight[std_row0 + r] = 1.0 / *k.max(&1) as f64;
    }
    for i in 0..nodes {
        let weighted: Vec<f64> =
            own_power.iter().enumerate().map(|(k, p)| p * gain.hat(i, fft::bin_freq_hz(k, own_n, fs))).collect();
        let smoothed = fractional_octave_power_in_band(&weighted, own_n, fs, cfg.fraction, cfg.band_hz)?;
        for (r, k) in own_rows.iter().enumerate() {
            a[r * cols + i] = DB_PER_POWER * 2.0 * smoothed[*k] / own_now[*k].max(f64::MIN_POSITIVE);
        }
        if let Some(m) = &std_magnitude {
            let weighted: Vec<f64> =
                m.iter().enumerate().map(|(k, v)| v * gain.hat(i, fft::bin_freq_hz(k, len, fs))).collect();
            let smoothed = fractional_octave_standard(&weighted, cfg.fraction)?.0;
            for (r, k) in std_rows.iter().enumerate() {
                a[(std_row0 + r) * cols + i] = DB_PER_MAGNITUDE * smoothed[*k] / std_now[*k].max(f64::MIN_POSITIVE);
            }
        }
    }
    // Lawson's algorithm: least squares with weights u_k, then u_k <- u_k |r_k| (normalised), converges to the
    // smallest largest |r_k|. Each smoothing's weights sum to 1, and one row per node pulls its gain towards 1 with
    // weight RIDGE (dB per dB), so a node the band barely constrains does not swing and the fit stays near a filter
    // the Kirkeby design can follow.
    const RIDGE: f64 = 0.01;
    const LAWSON_ITERATIONS: usize = 30;
    let normalise = |w: &mut [f64]| {
        for part in [0..std_row0, std_row0..fit_rows] {
            let total: f64 = w[part.clone()].iter().sum();
            if total > 0.0 {
                w[part].iter_mut().for_each(|v| *v /= total);
            }
        }
    };
    normalise(&mut weight);
    let total = fit_rows + nodes;
    let mut g = vec![1.0; cols];
    for _ in 0..LAWSON_ITERATIONS {
        let mut aw = vec![0.0; total * cols];
        let mut bw = vec![0.0; total];
        for r in 0..fit_rows {
            let s = weight[r].sqrt();
            for c in 0..cols {
                aw[r * cols + c] = s * a[r * cols + c];
            }
            bw[r] = s * b[r];
        }
        for i in 0..nodes {
            aw[(fit_rows + i) * cols + i] = RIDGE * DB_PER_MAGNITUDE;
            bw[fit_rows + i] = RIDGE * DB_PER_MAGNITUDE;
        }
        g = least_squares(&aw, total, cols, &bw)?;
        for r in 0..fit_rows {
            let residual: f64 = (0..cols).map(|c| a[r * cols + c] * g[c]).sum::<f64>() - b[r];
            weight[r] *= residual.abs();
        }
        normalise(&mut weight);
        if weight.iter().any(|w| !w.is_finite()) {
            break;
        }
    }
    // At most +/-3 dB a step: the Kirkeby design realises a small change faithfully, a large one only as far as its
    // regularisation allows, and the next step corrects what remains.
    let limit = 10f64.powf(3.0 / 20.0);
    gain.values = g[..nodes].iter().map(|v| v.clamp(1.0 / limit, limit)).collect();
    Ok(gain)
}

/// Median of positive values (0 for none).
fn median_of(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.collect();
    crate::stats::median(&mut v).unwrap_or(0.0)
}

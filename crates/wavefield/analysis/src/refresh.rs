//! Temporal refresh: the shortest spacing at which two band-limited impulses focused on one pixel are told apart
//! (paper, Fig. 4D: 5 ms on the metamaterial plate).
//!
//! Definition (paper, Wave Field Analysis): the target at pixel `x0` is a band-limited impulse at `T` and another
//! at `T + dt`; the two are resolvable when, in the intensity profile at `x0`, the valley between the two peaks falls
//! to at most half the peak height (the 50 % peak-to-valley rule). Here:
//! - the intensity is the squared envelope `|z(t)|^2` of the focused velocity (`z` its analytic signal): the raw
//!   `v(t)^2` of a band-pass pulse crosses zero every half carrier period, so its "valley" would be zero as soon as
//!   the carrier changes sign between the pulses, whatever their overlap;
//! - the two peaks are the intensity maxima within `dt / 2` of `T` and of `T + dt`, the valley the minimum between
//!   them, and the rule compares it with the *smaller* peak;
//! - the spacing is searched on a grid of `step_s` up to `max_spacing_s`; a pixel's refresh is the smallest spacing
//!   from which every larger spacing on the grid is resolvable (interference can make resolvability flicker near
//!   the limit; this takes the conservative side); the result is the median over a sample of pixels.
//!
//! The focused signal at the pixel is the target through the focal transfer `F(omega)` of [`crate::focus`], so only
//! `F` at the pixel is needed, never the whole field.

use metaplate_control::PropagationMatrices;
use metaplate_dsp::band::BandLimit;
use num_complex::Complex64;

use crate::error::AnalysisError;
use crate::focus::{FocusMethod, focal_scale, target_bins};
use crate::wavelength::stats::weighted_quantiles;

/// Options of [`refresh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefreshOptions {
    /// The target pulse: a zero-phase band-limited impulse with this band (default 75 to 400 Hz with 25 Hz
    /// raised-cosine skirts). The propagation matrices must cover its skirts.
    pub band: BandLimit,
    /// Focusing law (default: the regularised inverse filter).
    pub method: FocusMethod,
    /// Valley-to-peak ratio at or below which two pulses are resolved, in (0, 1) (default 0.5).
    pub valley_ratio: f64,
    /// Spacing grid step, s (default 0.1 ms). Valid: 1 us to `max_spacing_s`.
    pub step_s: f64,
    /// Largest spacing tried, s (default 30 ms). Valid: finite, up to 1 s.
    pub max_spacing_s: f64,
    /// Pixels sampled, evenly spread over the points of `g` (default 32; all points when there are fewer).
    pub focus_points: usize,
}

impl Default for RefreshOptions {
    fn default() -> Self {
        Self {
            band: BandLimit { lo_hz: 75.0, hi_hz: 400.0, lo_transition_hz: 25.0, hi_transition_hz: 25.0 },
            method: FocusMethod::default(),
            valley_ratio: 0.5,
            step_s: 1e-4,
            max_spacing_s: 0.03,
            focus_points: 32,
        }
    }
}

/// Refresh over a sample of pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Refresh {
    /// Median over the pixels that resolve two pulses within the search, s.
    pub refresh_s: f64,
    /// Per pixel sampled: its grid point and its refresh, s (`None`: not resolvable up to `max_spacing_s`).
    pub per_point: Vec<(u32, Option<f64>)>,
}

/// Whether two peaks are resolved in `intensity` (non-negative samples) by the peak-to-valley rule, for pulses
/// centred at samples `first` and `second` (`first < second`, both inside): the peaks are the maxima within half
/// the spacing of each centre, the valley the minimum between the two peaks, and the pulses are resolved when
/// `valley <= valley_ratio * min(peak_1, peak_2)`. False when either index is out of range or they are not in order.
pub fn resolvable(intensity: &[f64], first: usize, second: usize, valley_ratio: f64) -> bool {
    if first >= second || second >= intensity.len() {
        return false;
    }
    let half = (second - first) / 2;
    let argmax =
        |lo: usize, hi: usize| (lo..=hi).fold(lo, |best, i| if intensity[i] > intensity[best] { i } else { best });
    let p1 = argmax(first.saturating_sub(half), first + half);
    let p2 = argmax(second - half, (second + half).min(intensity.len() - 1));
    if p1 >= p2 {
        return false;
    }
    let valley = intensity[p1..=p2].iter().copied().fold(f64::INFINITY, f64::min);
    valley <= valley_ratio * intensity[p1].min(intensity[p2])
}

/// The temporal refresh of `g` (see the module documentation).
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for an option outside its range, a band whose skirts reach beyond `g`'s bins,
/// or when no sampled pixel resolves two pulses up to `max_spacing_s`; [`AnalysisError::NoEnergy`] when a sampled
/// pixel's response is zero.
pub fn refresh(g: &PropagationMatrices, opts: &RefreshOptions) -> Result<Refresh, AnalysisError> {
    check_options(opts)?;
    let target = target_bins(g, &opts.band)?;
    let bins: Vec<usize> = target.iter().map(|&(k, _)| k).collect();
    let m = g.n_points();
    let n = opts.focus_points.clamp(1, m.max(1));
    let mut rows: Vec<usize> = (0..n).map(|i| i * m / n + m / (2 * n)).filter(|&r| r < m).collect();
    rows.dedup();
    let mut per_point = Vec::with_capacity(rows.len());
    for row in rows {
        let scales = focal_scale(g, row, &bins, opts.method)?;
        let weights: Vec<(f64, f64)> =
            target.iter().zip(&scales).map(|(&(k, w), &(_, f))| (g.freqs_hz()[k], w * f)).collect();
        per_point.push((g.points()[row], pixel_refresh(&weights, opts)));
    }
    let found: Vec<f64> = per_point.iter().filter_map(|p| p.1).collect();
    let refresh_s = weighted_quantiles(&found, &vec![1.0; found.len()], &[0.5]).map(|q| q[0]).ok_or_else(|| {
        AnalysisError::InvalidParameter {
            name: "max_spacing_s",
            reason: format!("no sampled pixel resolves two pulses {} s apart or less", opts.max_spacing_s),
        }
    })?;
    Ok(Refresh { refresh_s, per_point })
}

/// One pixel's refresh from its focused pulse spectrum `(freq_hz, amplitude)`, or `None` if not resolvable.
fn pixel_refresh(spectrum: &[(f64, f64)], opts: &RefreshOptions) -> Option<f64> {
    // Envelope samples every half step, so that a spacing of `s` steps is `2 s` samples; one pulse is evaluated once
    // over +-1.5 max spacing and the pair is its sum with a shifted copy.
    let h_s = opts.step_s / 2.0;
    let steps = (opts.max_spacing_s / opts.step_s).floor() as usize;
    let half_len = 3 * steps + 2;
    let pulse: Vec<Complex64> = (0..2 * half_len + 1)
        .map(|j| {
            let t = (j as f64 - half_len as f64) * h_s;
            spectrum.iter().map(|&(f, a)| Complex64::from_polar(a, 2.0 * std::f64::consts::PI * f * t)).sum()
        })
        .collect();
    let mut best = None;
    for s in (1..=steps).rev() {
        let shift = 2 * s;
        // Intensity of pulse(t) + pulse(t - dt) at samples where both are defined.
        let intensity: Vec<f64> = (shift..pulse.len()).map(|j| (pulse[j] + pulse[j - shift]).norm_sqr()).collect();
        // Pulse centres: t = 0 at sample half_len of `pulse`, i.e. half_len - shift here; t = dt at half_len.
        if resolvable(&intensity, half_len - shift, half_len, opts.valley_ratio) {
            best = Some(s as f64 * opts.step_s);
        } else {
            break;
        }
    }
    best
}

fn check_options(opts: &RefreshOptions) -> Result<(), AnalysisError> {
    let bad = |name: &'static str, reason: String| Err(AnalysisError::InvalidParameter { name, reason });
    if !(opts.valley_ratio > 0.0 && opts.valley_ratio < 1.0) {
        return bad("valley_ratio", format!("must lie in (0, 1), got {}", opts.valley_ratio));
    }
    if !(opts.max_spacing_s.is_finite() && opts.max_spacing_s > 0.0 && opts.max_spacing_s <= 1.0) {
        return bad("max_spacing_s", format!("must lie in (0, 1] s, got {}", opts.max_spacing_s));
    }
    if !(opts.step_s.is_finite() && opts.step_s >= 1e-6 && opts.step_s <= opts.max_spacing_s) {
        return bad("step_s", format!("must lie in [1e-6, max_spacing_s] s, got {}", opts.step_s));
    }
    if opts.max_spacing_s / opts.step_s > 100_000.0 {
        return bad("step_s", "more than 100000 spacings to try: use a larger step".to_owned());
    }
    if opts.focus_points == 0 {
        return bad("focus_points", "must be at least 1".to_owned());
    }
    Ok(())
}

//! The radial refinement: the angular average of |G(k)|^2 as a function of |k|, its peak, and the half-maximum
//! annulus around that peak.
//!
//! Why: at long wavelengths the 2-D half-maximum region of the paper's method is as wide as its distance from the
//! origin (the aperture's resolution is comparable to |k|), and which bins it takes depends on where speckle happens
//! to put the peak. Averaging over angle first pools the whole ring of a reverberant field into one profile with a
//! single, stable peak; the half-maximum annulus is then taken on that profile.

use super::region::{Region, parabolic_offset};
use super::spectrum::PowerMap;

/// Angular average of `map` in annuli one bin wide, up to `max_k_rad_m` (the inscribed Nyquist circle: beyond it
/// annuli are incomplete); its peak outside `|k| < min_k_rad_m`; the half-maximum interval of |k| around that peak
/// (linearly interpolated between annuli); and the 2-D bins whose |k| falls in that interval.
/// `None` when no annulus outside the disc carries energy.
pub(crate) fn radial_half_max(map: &PowerMap, min_k_rad_m: f64, max_k_rad_m: f64) -> Option<Region> {
    let dk = map.dk_rad_m;
    let annuli = (max_k_rad_m / dk).floor() as usize + 1;
    let mut sum = vec![0.0; annuli];
    let mut count = vec![0usize; annuli];
    for sy in 0..map.my {
        for sx in 0..map.mx {
            let (kx, ky) = map.k_of(sx, sy);
            let j = (kx.hypot(ky) / dk).round() as usize;
            if j < annuli {
                sum[j] += map.power[sy * map.mx + sx];
                count[j] += 1;
            }
        }
    }
    let profile: Vec<f64> = sum.iter().zip(&count).map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 }).collect();
    let first = (min_k_rad_m / dk).ceil() as usize;
    let mut peak: Option<(usize, f64)> = None;
    for (j, &e) in profile.iter().enumerate().skip(first) {
        if e > 0.0 && peak.is_none_or(|(_, best)| e > best) {
            peak = Some((j, e));
        }
    }
    let (peak_j, peak_e) = peak?;
    let half = 0.5 * peak_e;

    let offset = if peak_j > 0 && peak_j + 1 < annuli {
        let (l, r) = (profile[peak_j - 1], profile[peak_j + 1]);
        if l > 0.0 && r > 0.0 { parabolic_offset(l.ln(), peak_e.ln(), r.ln()) } else { parabolic_offset(l, peak_e, r) }
    } else {
        0.0
    };
    let peak_k_rad_m = (peak_j as f64 + offset) * dk;

    // Walk down each side to the first annulus below half the peak; the crossing is interpolated linearly.
    let crossing = |below: usize, above: usize| {
        let (eb, ea) = (profile[below], profile[above]);
        let t = if ea > eb { (half - eb) / (ea - eb) } else { 0.0 };
        (below as f64 + t * (above as f64 - below as f64)) * dk
    };
    let mut lo = peak_j;
    while lo > first && profile[lo - 1] >= half {
        lo -= 1;
    }
    // Stopping at the excluded disc with the profile still above half means the annulus was cut there, not closed.
    let touches_dc = lo == first && (first == 0 || profile[first - 1] >= half);
    let k_lo = if touches_dc { min_k_rad_m } else { crossing(lo - 1, lo).max(min_k_rad_m) };
    let mut hi = peak_j;
    while hi + 1 < annuli && profile[hi + 1] >= half {
        hi += 1;
    }
    let touches_nyquist = hi + 1 == annuli;
    let k_hi = if touches_nyquist { max_k_rad_m } else { crossing(hi + 1, hi) };

    let mut samples = Vec::new();
    for sy in 0..map.my {
        for sx in 0..map.mx {
            let (kx, ky) = map.k_of(sx, sy);
            let k = kx.hypot(ky);
            if k >= k_lo && k <= k_hi && k > 0.0 {
                samples.push((2.0 * std::f64::consts::PI / k, map.power[sy * map.mx + sx]));
            }
        }
    }
    Some(Region { peak_k_rad_m, samples, touches_dc, touches_nyquist })
}

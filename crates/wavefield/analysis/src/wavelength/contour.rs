//! The paper's method: the peak bin of |G(k)|^2 and the connected region around it above half the peak.

use super::region::{Region, parabolic_offset};
use super::spectrum::PowerMap;

/// Finds the peak of `map` outside the disc `|k| < min_k_rad_m`, flood-fills the 8-connected region of bins at or
/// above half the peak (the half-maximum contour; it never enters the excluded disc), and returns the region.
/// `None` when no bin outside the disc carries energy.
pub(crate) fn half_max_contour(map: &PowerMap, min_k_rad_m: f64) -> Option<Region> {
    let (mx, my) = (map.mx, map.my);
    let excluded = |sx: usize, sy: usize| {
        let (kx, ky) = map.k_of(sx, sy);
        kx.hypot(ky) < min_k_rad_m
    };
    let mut peak: Option<(usize, f64)> = None;
    for (i, &p) in map.power.iter().enumerate() {
        if p > 0.0 && peak.is_none_or(|(_, best)| p > best) && !excluded(i % mx, i / mx) {
            peak = Some((i, p));
        }
    }
    let (peak_index, peak_power) = peak?;
    let half = 0.5 * peak_power;

    let mut in_region = vec![false; map.power.len()];
    let mut stack = vec![peak_index];
    in_region[peak_index] = true;
    let mut samples = Vec::new();
    let (mut touches_dc, mut touches_nyquist) = (false, false);
    while let Some(i) = stack.pop() {
        let (sx, sy) = (i % mx, i / mx);
        let (kx, ky) = map.k_of(sx, sy);
        samples.push((2.0 * std::f64::consts::PI / kx.hypot(ky), map.power[i]));
        touches_nyquist |= map.on_edge(sx, sy);
        for (nx, ny) in neighbours(sx, sy, mx, my) {
            let j = ny * mx + nx;
            if in_region[j] || map.power[j] < half {
                continue;
            }
            if excluded(nx, ny) {
                touches_dc = true;
                continue;
            }
            in_region[j] = true;
            stack.push(j);
        }
    }

    let (sx, sy) = (peak_index % mx, peak_index / mx);
    let (kx, ky) = map.k_of(sx, sy);
    let at = |x: usize, y: usize| map.power[y * mx + x];
    let offset_x = if sx > 0 && sx + 1 < mx { log_parabola(at(sx - 1, sy), peak_power, at(sx + 1, sy)) } else { 0.0 };
    let offset_y = if sy > 0 && sy + 1 < my { log_parabola(at(sx, sy - 1), peak_power, at(sx, sy + 1)) } else { 0.0 };
    let peak_k_rad_m = (kx + offset_x * map.dk_rad_m).hypot(ky + offset_y * map.dk_rad_m);
    Some(Region { peak_k_rad_m, samples, touches_dc, touches_nyquist })
}

/// Parabolic vertex on the logarithm of power (exact for a Gaussian peak, close for the main lobe of the aperture's
/// transform), falling back to the power itself when a neighbour is zero.
fn log_parabola(left: f64, centre: f64, right: f64) -> f64 {
    if left > 0.0 && right > 0.0 {
        parabolic_offset(left.ln(), centre.ln(), right.ln())
    } else {
        parabolic_offset(left, centre, right)
    }
}

/// The up-to-8 neighbours of `(sx, sy)` inside an `mx` x `my` grid (no wrap-around: the grid edge is the Nyquist
/// limit, and the flood fill reports reaching it rather than continuing into aliased bins).
fn neighbours(sx: usize, sy: usize, mx: usize, my: usize) -> impl Iterator<Item = (usize, usize)> {
    (-1isize..=1).flat_map(move |dy| (-1isize..=1).map(move |dx| (dx, dy))).filter_map(move |(dx, dy)| {
        let (x, y) = (sx as isize + dx, sy as isize + dy);
        let inside = (dx, dy) != (0, 0) && x >= 0 && y >= 0 && (x as usize) < mx && (y as usize) < my;
        inside.then_some((x as usize, y as usize))
    })
}

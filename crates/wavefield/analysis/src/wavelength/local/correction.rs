//! From the discrete bilaplacian's eigenvalue back to the wavenumber: inverting the stencil's dispersion.
//!
//! On a plane wave `e^{i k (x cos t + y sin t)}` the 13-point stencil returns `S(kh, t) u / h^4` with
//! `S(kh, t) = [4 sin^2(kh cos t / 2) + 4 sin^2(kh sin t / 2)]^2 = (kh)^4 [1 - (kh)^2 c(t) / 6 + O((kh)^4)]`,
//! `c(t) = cos^4 t + sin^4 t` between 1/2 (diagonals) and 1 (axes). Taking `S^{1/4}` as `kh` would read the
//! wavenumber short, hence the wavelength long, by `(kh)^2 c(t) / 24` (0.4 to 0.8 % at 10 points per wavelength).
//! The inversion below solves `S_bar(kh) = s` for a chosen `S_bar`: along the axis (`c = 1`, exact for waves along x
//! or y) or averaged over all directions (`c = 3/4` at leading order, exact for a diffuse field).

use super::StencilCorrection;

/// Largest `kh` the inversion accepts: `pi`, the Nyquist limit along an axis. Beyond it `S` is not monotonic.
pub(crate) const MAX_KH: f64 = std::f64::consts::PI;

/// Directions averaged over one period of `S` in t (pi / 2); the trapezoid rule on a smooth periodic function is
/// exact to rounding well before 32 samples for `kh <= pi` (the Fourier coefficients in t fall like J_n(kh)).
const DIRECTIONS: usize = 32;

/// The stencil's symbol `S(kh, t)` for a wave travelling at angle `t` (rad) from the x axis.
pub(crate) fn symbol(kh: f64, angle_rad: f64) -> f64 {
    let half = |c: f64| 4.0 * (0.5 * kh * c).sin().powi(2);
    (half(angle_rad.cos()) + half(angle_rad.sin())).powi(2)
}

/// The symbol the inversion assumes: along an axis, or averaged over directions.
fn assumed_symbol(kh: f64, correction: StencilCorrection) -> f64 {
    match correction {
        StencilCorrection::None => kh.powi(4),
        StencilCorrection::Axis => symbol(kh, 0.0),
        StencilCorrection::Isotropic => {
            let step = std::f64::consts::FRAC_PI_2 / DIRECTIONS as f64;
            (0..DIRECTIONS).map(|j| symbol(kh, j as f64 * step)).sum::<f64>() / DIRECTIONS as f64
        }
    }
}

/// The `kh` whose assumed symbol is `s` (`s = k^4 h^4` as the stencil measured it), or `None` when `s` lies beyond
/// the assumed symbol at [`MAX_KH`] (the field varies faster than the grid can follow). `s` must be finite and
/// `>= 0`; 0 gives 0.
pub(crate) fn invert(s: f64, correction: StencilCorrection) -> Option<f64> {
    if s == 0.0 {
        return Some(0.0);
    }
    if correction == StencilCorrection::None {
        let kh = s.powf(0.25);
        return (kh <= MAX_KH).then_some(kh);
    }
    if s > assumed_symbol(MAX_KH, correction) {
        return None;
    }
    // The assumed symbol increases strictly on [0, pi] (each direction's does); bisection to rounding. Starting from
    // the uncorrected root keeps the bracket tight: the corrected kh is larger (the stencil reads short).
    let (mut lo, mut hi) = (s.powf(0.25).min(MAX_KH), MAX_KH);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if assumed_symbol(mid, correction) < s {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn inversion_undoes_the_symbol() {
        for kh in [1e-6, 0.01, 0.3, 1.0, 2.0, 3.0, MAX_KH] {
            // Along an axis the axis correction is exact.
            let kh_axis = invert(symbol(kh, 0.0), StencilCorrection::Axis).unwrap();
            // At pi the axis symbol is flat (sin^4 at its maximum): rounding in S moves the root by its square
            // root, ~1e-8; everywhere else the root is as exact as S.
            let tolerance = if kh == MAX_KH { 1e-7 } else { 1e-12 };
            assert!((kh_axis / kh - 1.0).abs() < tolerance, "{kh}: {kh_axis}");
            let kh_iso =
                invert(assumed_symbol(kh, StencilCorrection::Isotropic), StencilCorrection::Isotropic).unwrap();
            assert!((kh_iso / kh - 1.0).abs() < 1e-12, "{kh}: {kh_iso}");
        }
        assert_eq!(invert(0.0, StencilCorrection::Isotropic), Some(0.0));
        assert!(invert(1e6, StencilCorrection::Isotropic).is_none());
        assert!(invert(1e6, StencilCorrection::None).is_none());
    }

    #[test]
    fn leading_order_matches_the_expansion() {
        // S = (kh)^4 (1 - (kh)^2 c / 6): check c = 1 on the axis, 1/2 on the diagonal, 3/4 on average, at a kh small
        // enough that the next order ((kh)^4 ~ 1e-4) is below the 1e-3 tolerance on c.
        let kh: f64 = 0.01;
        let c = |s: f64| (1.0 - s / kh.powi(4)) * 6.0 / (kh * kh);
        assert!((c(symbol(kh, 0.0)) - 1.0).abs() < 1e-3);
        assert!((c(symbol(kh, std::f64::consts::FRAC_PI_4)) - 0.5).abs() < 1e-3);
        assert!((c(assumed_symbol(kh, StencilCorrection::Isotropic)) - 0.75).abs() < 1e-3);
    }
}

//! What both k-space methods hand back: the peak and the bins of the half-maximum region around it.

/// The half-maximum region found around the k-space peak.
pub(crate) struct Region {
    /// |k| of the peak in rad/m, refined below the bin spacing.
    pub peak_k_rad_m: f64,
    /// Wavelength 2 pi / |k| (m) of each k-bin in the region, with that bin's |G|^2.
    pub samples: Vec<(f64, f64)>,
    /// The region borders the excluded neighbourhood of k = 0.
    pub touches_dc: bool,
    /// The region reaches the edge of the k-grid (the spatial Nyquist limit).
    pub touches_nyquist: bool,
}

/// Sub-bin offset of a peak from three equally spaced samples (left, centre, right) by a parabola through them, in
/// bins within [-0.5, 0.5]; 0 when the centre is not a strict local maximum of a concave parabola.
pub(crate) fn parabolic_offset(left: f64, centre: f64, right: f64) -> f64 {
    let curvature = left - 2.0 * centre + right;
    if curvature < 0.0 { (0.5 * (left - right) / curvature).clamp(-0.5, 0.5) } else { 0.0 }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn parabola_vertex_is_found() {
        // y = -(x - 0.3)^2 sampled at -1, 0, 1.
        let f = |x: f64| -(x - 0.3) * (x - 0.3);
        assert!((parabolic_offset(f(-1.0), f(0.0), f(1.0)) - 0.3).abs() < 1e-12);
        assert_eq!(parabolic_offset(1.0, 1.0, 1.0), 0.0);
    }
}

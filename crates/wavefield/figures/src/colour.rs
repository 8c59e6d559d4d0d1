//! Perceptually ordered colour maps (viridis for magnitudes, a red-blue diverging map for signed fields, both by
//! their anchor colours, interpolated linearly: continuous, no steps) and the figure palette.

use plotters::style::RGBColor;

/// Viridis (matplotlib's) at 0, 1/8, ..., 1.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 45, 123),
    (59, 82, 139),
    (44, 114, 142),
    (33, 145, 140),
    (40, 174, 128),
    (94, 201, 98),
    (173, 220, 48),
    (253, 231, 37),
];

/// ColorBrewer's RdBu (reversed: blue for negative) at -1, -0.8, ..., 1: white at 0, equal lightness steps either
/// side, so that the sign reads from the hue and the magnitude from the lightness.
const RED_BLUE: [(u8, u8, u8); 11] = [
    (5, 48, 97),
    (33, 102, 172),
    (67, 147, 195),
    (146, 197, 222),
    (209, 229, 240),
    (247, 247, 247),
    (253, 219, 199),
    (244, 165, 130),
    (214, 96, 77),
    (178, 24, 43),
    (103, 0, 31),
];

/// Linear interpolation through `anchors` at `t` in [0, 1] (clamped; NaN maps to 0).
fn through(anchors: &[(u8, u8, u8)], t: f64) -> RGBColor {
    let last = anchors.len().saturating_sub(1);
    if last == 0 {
        let (r, g, b) = anchors.first().copied().unwrap_or((0, 0, 0));
        return RGBColor(r, g, b);
    }
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * last as f64;
    let i = (t.floor() as usize).min(last - 1);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (anchors[i], anchors[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Viridis at `t` in [0, 1] (clamped; NaN maps to 0).
pub(crate) fn viridis(t: f64) -> RGBColor {
    through(&VIRIDIS, t)
}

/// The diverging map at `t` in [-1, 1]: dark blue (-1), white (0), dark red (+1) (clamped; NaN maps to 0).
pub(crate) fn diverging(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t };
    through(&RED_BLUE, 0.5 * (t + 1.0))
}

/// Series colours (one per plate or domain).
pub(crate) const PALETTE: [RGBColor; 6] = [
    RGBColor(200, 30, 30),
    RGBColor(30, 60, 200),
    RGBColor(30, 150, 60),
    RGBColor(150, 80, 0),
    RGBColor(120, 40, 160),
    RGBColor(90, 90, 90),
];

/// Unmeasured parts of a map (on the plate where its outline is known).
pub(crate) const MASKED: RGBColor = RGBColor(225, 225, 225);

/// Measured points without a value (for example no closed half-maximum contour): a dark grey, apart from both
/// colour maps and from [`MASKED`].
pub(crate) const NO_VALUE: RGBColor = RGBColor(110, 110, 110);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_are_continuous_and_hit_their_anchors() {
        assert_eq!(diverging(0.0), RGBColor(247, 247, 247));
        assert_eq!(diverging(-1.0), RGBColor(5, 48, 97));
        assert_eq!(diverging(2.0), RGBColor(103, 0, 31));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        // No step larger than one anchor interval's share: 1000 samples move at most a few levels each.
        for map in [viridis as fn(f64) -> RGBColor, |t| diverging(2.0 * t - 1.0)] {
            for i in 0..1000 {
                let (a, b) = (map(i as f64 / 1000.0), map((i + 1) as f64 / 1000.0));
                let step = a.0.abs_diff(b.0).max(a.1.abs_diff(b.1)).max(a.2.abs_diff(b.2));
                assert!(step <= 2, "step {step} at {i}");
            }
        }
    }
}

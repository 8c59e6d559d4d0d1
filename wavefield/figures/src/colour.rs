//! A perceptually ordered colour map (viridis, by its anchor colours) and the figure palette.

use plotters::style::RGBColor;

/// Viridis at 0, 0.25, 0.5, 0.75 and 1.
const VIRIDIS: [(u8, u8, u8); 5] = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)];

/// Colour of `t` in [0, 1] (clamped; NaN maps to 0).
pub(crate) fn viridis(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * (VIRIDIS.len() - 1) as f64;
    let i = (t.floor() as usize).min(VIRIDIS.len() - 2);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A diverging map for signed fields: blue (-1), white (0), red (+1).
pub(crate) fn diverging(t: f64) -> RGBColor {
    let t = if t.is_nan() { 0.0 } else { t.clamp(-1.0, 1.0) };
    let fade = |c: u8| (255.0 - t.abs() * (255.0 - c as f64)).round() as u8;
    if t >= 0.0 { RGBColor(fade(200), fade(30), fade(30)) } else { RGBColor(fade(30), fade(60), fade(200)) }
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

/// Unmeasured grid points.
pub(crate) const MASKED: RGBColor = RGBColor(225, 225, 225);

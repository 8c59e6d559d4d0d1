//! The lattice a set of measured points lies on, and what it can resolve.
//!
//! A scan of every `s`-th point (`scan --grid 25x13` on the paper's 49 x 25 grid: `s = 2`) keeps the full grid's
//! indices. Analysed on the full grid, the unmeasured points between read as zeros: the field is multiplied by a
//! comb of period `s`, and its spectrum is repeated at multiples of `2 pi / (s h)` (spectral images), well inside the
//! full grid's Nyquist limit `pi / h`. The k-space wavelength then locks onto an image (5.7 cm for a 25.5 cm wave on
//! the 1 cm subset), and the contours of the pixel area run into the holes. Every lattice-dependent analysis
//! therefore works on [`Lattice::of_points`]: the coarsest regular lattice through the points, spacing `s h`.

use metaplate_core::grid::GridSpec;

/// Measured points that fill less than this fraction of their lattice's nodes leave holes inside the aperture
/// (an irregular subset whose strides have no common divisor above 1): the holes' spectral images can pass for
/// waves, so estimates on such a lattice are flagged. A regular subset of the stadium plate fills about 85 % (the
/// corners are off the plate); an irregular 17 x 9 subset of the 49 x 25 grid, 14 %.
pub const MIN_LATTICE_FILL: f64 = 0.5;

/// The regular lattice a set of points lies on (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// The lattice as a grid: spacing `stride` times the original's, origin at the lowest measured column and row;
    /// the original grid itself for stride 1.
    pub grid: GridSpec,
    /// Each point's flat index on [`Lattice::grid`], in the order given.
    pub indices: Vec<u32>,
    /// Lattice step in steps of the original grid (1: the points use the original's full resolution).
    pub stride: usize,
}

impl Lattice {
    /// The coarsest regular lattice through `points` (flat indices of `grid`): stride `s`, the greatest common
    /// divisor of every point's offset from the lowest `ix` and `iy` present, or 1 when that is 0 (a single point)
    /// or the points already use the full resolution. `None` for no points or a point beyond the grid.
    pub fn of_points(grid: &GridSpec, points: &[u32]) -> Option<Self> {
        if points.iter().any(|&p| p as usize >= grid.len()) {
            return None;
        }
        let cells: Vec<(usize, usize)> = points.iter().map(|&p| grid.indices(p as usize)).collect();
        let ix0 = cells.iter().map(|c| c.0).min()?;
        let iy0 = cells.iter().map(|c| c.1).min()?;
        let stride = cells.iter().fold(0, |g, &(ix, iy)| gcd(gcd(g, ix - ix0), iy - iy0)).max(1);
        if stride == 1 {
            // The grid's own resolution: the grid itself, so that a full scan is analysed exactly as before.
            return Some(Self { grid: *grid, indices: points.to_vec(), stride });
        }
        let nx = cells.iter().map(|c| (c.0 - ix0) / stride).max()? + 1;
        let ny = cells.iter().map(|c| (c.1 - iy0) / stride).max()? + 1;
        let (origin_x_m, origin_y_m) = grid.position_m(grid.index(ix0, iy0));
        let lattice = GridSpec { nx, ny, spacing_m: grid.spacing_m * stride as f64, origin_x_m, origin_y_m };
        let indices =
            cells.iter().map(|&(ix, iy)| lattice.index((ix - ix0) / stride, (iy - iy0) / stride) as u32).collect();
        Some(Self { grid: lattice, indices, stride })
    }

    /// Per lattice node: measured.
    pub fn mask(&self) -> Vec<bool> {
        let mut mask = vec![false; self.grid.len()];
        for &i in &self.indices {
            if let Some(m) = mask.get_mut(i as usize) {
                *m = true;
            }
        }
        mask
    }

    /// Fraction of the lattice's nodes that are measured (0 to 1).
    pub fn fill(&self) -> f64 {
        self.mask().iter().filter(|&&m| m).count() as f64 / self.grid.len().max(1) as f64
    }

    /// The range a wavenumber estimate on this lattice can resolve.
    pub fn resolvable(&self) -> ResolvableRange {
        let spacing_m = self.grid.spacing_m;
        let aperture_m = self.grid.nx.max(self.grid.ny) as f64 * spacing_m;
        ResolvableRange {
            spacing_m,
            nyquist_k_rad_m: std::f64::consts::PI / spacing_m,
            shortest_wavelength_m: 2.0 * spacing_m,
            aperture_m,
            longest_wavelength_m: 0.5 * aperture_m,
            fill: self.fill(),
        }
    }
}

/// What a k-space estimate on a lattice can resolve: wavelengths between `2 h` (Nyquist, along an axis) and half
/// the aperture's longer side (below that the aperture's own resolution `2 pi / L` blurs the peak; see
/// [`crate::wavelength`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolvableRange {
    /// Lattice spacing `h`, m.
    pub spacing_m: f64,
    /// The lattice's Nyquist wavenumber `pi / h`, rad/m.
    pub nyquist_k_rad_m: f64,
    /// Shortest resolvable wavelength `2 h`, m.
    pub shortest_wavelength_m: f64,
    /// The aperture's longer side `L = max(nx, ny) h`, m.
    pub aperture_m: f64,
    /// Longest wavelength resolved without the aperture's bias, `L / 2`, m.
    pub longest_wavelength_m: f64,
    /// Fraction of the lattice's nodes measured; below [`MIN_LATTICE_FILL`] the holes' images are a risk.
    pub fill: f64,
}

impl ResolvableRange {
    /// Whether `wavelength_m` lies inside the range on a lattice filled well enough.
    pub fn contains(&self, wavelength_m: f64) -> bool {
        self.fill >= MIN_LATTICE_FILL
            && wavelength_m >= self.shortest_wavelength_m
            && wavelength_m <= self.longest_wavelength_m
    }
}

/// Greatest common divisor (`gcd(0, n) = n`).
fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn a_regular_subset_lies_on_its_own_coarser_lattice() {
        // 49 x 25 grid at 1 cm; every other point from (2, 1): a 24 x 12 lattice at 2 cm with its origin at (2, 1).
        let grid = GridSpec::centred(49, 25, 0.01);
        let points: Vec<u32> =
            (1..25).step_by(2).flat_map(|iy| (2..49).step_by(2).map(move |ix| grid.index(ix, iy) as u32)).collect();
        let lattice = Lattice::of_points(&grid, &points).unwrap();
        assert_eq!((lattice.grid.nx, lattice.grid.ny, lattice.stride), (24, 12, 2));
        assert!((lattice.grid.spacing_m - 0.02).abs() < 1e-15);
        for (&p, &c) in points.iter().zip(&lattice.indices) {
            let (a, b) = (grid.position_m(p as usize), lattice.grid.position_m(c as usize));
            assert!((a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12, "point {p} moved");
        }
        assert_eq!(lattice.fill(), 1.0);
        let range = lattice.resolvable();
        assert!((range.shortest_wavelength_m - 0.04).abs() < 1e-12);
        assert!((range.longest_wavelength_m - 0.24).abs() < 1e-12);
        // Strides 1 (a neighbour pair) and a single point: the grid's own resolution.
        assert_eq!(Lattice::of_points(&grid, &[0, 1]).unwrap().stride, 1);
        assert_eq!(Lattice::of_points(&grid, &[7]).unwrap().stride, 1);
        assert!(Lattice::of_points(&grid, &[]).is_none());
        assert!(Lattice::of_points(&grid, &[grid.len() as u32]).is_none());
        // Stride 3 along x only, 6 along y: the common stride is 3; three of the 3 x 3 nodes measured.
        let mixed = [grid.index(0, 0), grid.index(3, 0), grid.index(0, 6)].map(|i| i as u32);
        let lattice = Lattice::of_points(&grid, &mixed).unwrap();
        assert!((lattice.grid.spacing_m - 0.03).abs() < 1e-15);
        assert!((lattice.fill() - 3.0 / 6.0).abs() < 1e-12);
    }
}

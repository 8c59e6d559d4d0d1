//! The 13-point discrete bilaplacian and the grid points where it may be applied.

use metaplate_core::grid::GridSpec;
use num_complex::Complex64;

use super::Exclusion;

/// The 5-point Laplacian applied twice, in grid units (multiply by `1 / h^4` for m^-4): offsets `(dx, dy)` and
/// weights. Its symbol for `e^{i (kx x + ky y)}` is `[4 sin^2(kx h / 2) + 4 sin^2(ky h / 2)]^2`.
pub(crate) const BILAPLACIAN: [(isize, isize, f64); 13] = [
    (0, 0, 20.0),
    (1, 0, -8.0),
    (-1, 0, -8.0),
    (0, 1, -8.0),
    (0, -1, -8.0),
    (1, 1, 2.0),
    (1, -1, 2.0),
    (-1, 1, 2.0),
    (-1, -1, 2.0),
    (2, 0, 1.0),
    (-2, 0, 1.0),
    (0, 2, 1.0),
    (0, -2, 1.0),
];

/// Flat indices of the points whose whole stencil lies on the grid, is measured, and keeps clear of every
/// exclusion (no stencil point strictly closer than `radius_m` to an exclusion's centre).
pub(crate) fn usable_points(grid: &GridSpec, mask: &[bool], exclusions: &[Exclusion]) -> Vec<usize> {
    let (nx, ny) = (grid.nx as isize, grid.ny as isize);
    // Per point: measured and outside every exclusion disc. Checked once per point, then per stencil.
    let clear: Vec<bool> = (0..grid.len())
        .map(|i| {
            let (x, y) = grid.position_m(i);
            mask[i] && exclusions.iter().all(|e| (x - e.x_m).hypot(y - e.y_m) >= e.radius_m)
        })
        .collect();
    (0..grid.len())
        .filter(|&i| {
            let (ix, iy) = grid.indices(i);
            BILAPLACIAN.iter().all(|&(dx, dy, _)| {
                let (x, y) = (ix as isize + dx, iy as isize + dy);
                x >= 0 && y >= 0 && x < nx && y < ny && clear[(y * nx + x) as usize]
            })
        })
        .collect()
}

/// The bilaplacian of `field` at flat index `i` in grid units. `i` must be a usable point (whole stencil on the
/// grid), as [`usable_points`] returns.
pub(crate) fn bilaplacian_at(field: &[Complex64], nx: usize, i: usize) -> Complex64 {
    let (ix, iy) = ((i % nx) as isize, (i / nx) as isize);
    BILAPLACIAN.iter().map(|&(dx, dy, w)| field[((iy + dy) * nx as isize + ix + dx) as usize] * w).sum()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests may unwrap
mod tests {
    use super::*;

    #[test]
    fn stencil_is_the_laplacian_squared() {
        // Apply the 5-point Laplacian twice to a unit impulse on a 9 x 9 grid and compare with the table.
        let n = 9;
        let lap = |f: &[f64]| -> Vec<f64> {
            let mut out = vec![0.0; n * n];
            for y in 1..n - 1 {
                for x in 1..n - 1 {
                    let i = y * n + x;
                    out[i] = f[i - 1] + f[i + 1] + f[i - n] + f[i + n] - 4.0 * f[i];
                }
            }
            out
        };
        let mut impulse = vec![0.0; n * n];
        impulse[4 * n + 4] = 1.0;
        let twice = lap(&lap(&impulse));
        let mut expected = vec![0.0; n * n];
        for &(dx, dy, w) in &BILAPLACIAN {
            expected[((4 + dy) * n as isize + 4 + dx) as usize] = w;
        }
        assert_eq!(twice, expected);
    }

    #[test]
    fn usable_points_keep_the_stencil_inside_and_clear() {
        let grid = GridSpec::centred(9, 9, 1.0);
        let mask = vec![true; 81];
        // Full grid: the 5 x 5 centre block (2 points from each side).
        assert_eq!(usable_points(&grid, &mask, &[]).len(), 25);
        // An exclusion of radius 1 at the centre removes every point whose stencil reaches within 1 of it:
        // stencil points closer than 1 means the centre itself, so all 13 stencil-neighbours of the centre.
        let centre = Exclusion { x_m: 0.0, y_m: 0.0, radius_m: 0.5 };
        let used = usable_points(&grid, &mask, &[centre]);
        assert_eq!(used.len(), 25 - 13);
        assert!(!used.contains(&(4 * 9 + 4)));
    }
}

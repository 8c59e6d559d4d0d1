//! Grid subsets and scan order.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests may unwrap

use metaplate_core::grid::{GridError, GridSpec};
use proptest::prelude::*;

#[test]
fn subset_7x5_of_the_paper_grid() {
    let g = GridSpec::centred(49, 25, 0.005);
    let s = g.subset(7, 5).unwrap();
    assert_eq!(s.len(), 35);
    // Bin centres by hand: 49 / 7 = 7 points per bin, centres at 3, 10, ..., 45; 25 / 5 = 5, centres 2, 7, ..., 22.
    let xs: Vec<usize> = s[..7].iter().map(|&i| g.indices(i).0).collect();
    let ys: Vec<usize> = s.iter().step_by(7).map(|&i| g.indices(i).1).collect();
    assert_eq!(xs, [3, 10, 17, 24, 31, 38, 45]);
    assert_eq!(ys, [2, 7, 12, 17, 22]);
    // Centred: the middle point is the plate's centre (1e-15 m: a few ulps of 0.12 m).
    let (x, y) = g.position_m(s[17]);
    assert!(x.abs() < 1e-15 && y.abs() < 1e-15, "({x}, {y})");
    assert_eq!(g.subset(49, 25).unwrap(), (0..1225).collect::<Vec<_>>());
    assert_eq!(g.subset(1, 1).unwrap(), [g.index(24, 12)]);
    for (nx, ny) in [(50, 5), (7, 26), (0, 5), (7, 0)] {
        assert!(matches!(g.subset(nx, ny), Err(GridError::BadSubset { .. })), "{nx} x {ny}");
    }
}

#[test]
fn serpentine_order_of_a_subset() {
    let g = GridSpec::centred(49, 25, 0.005);
    let mut s = g.subset(7, 5).unwrap();
    s.reverse(); // the input order must not matter
    s.push(s[0]); // nor duplicates
    let path = g.serpentine_order(&s);
    assert_eq!(path.len(), 35);
    let cells: Vec<(usize, usize)> = path.iter().map(|&i| g.indices(i)).collect();
    assert_eq!(&cells[..7], &[(3, 2), (10, 2), (17, 2), (24, 2), (31, 2), (38, 2), (45, 2)]);
    assert_eq!(cells[7], (45, 7), "the second row starts where the first ended");
    assert_eq!(cells[13], (3, 7));
    assert_eq!(cells[14], (3, 12));
    assert_eq!(cells[34], (45, 22), "five rows: the last runs towards +x");
}

#[test]
fn grid_validation_extremes() {
    assert!(GridSpec::centred(1, 1, 1e-9).validate().is_ok());
    assert!(GridSpec::centred(1000, 1000, 0.001).validate().is_ok(), "exactly the 10^6 limit");
    assert!(GridSpec::centred(1001, 1000, 0.001).validate().is_err());
    assert!(GridSpec::centred(usize::MAX, 2, 0.001).validate().is_err(), "overflowing product");
    assert!(GridSpec::centred(0, 5, 0.001).validate().is_err());
    for spacing in [0.0, -0.005, f64::NAN, f64::INFINITY] {
        assert!(GridSpec::centred(3, 3, spacing).validate().is_err(), "{spacing}");
    }
    let g = GridSpec { nx: 0, ny: 3, spacing_m: 0.01, origin_x_m: 0.0, origin_y_m: 0.0 };
    assert_eq!(g.indices(5), (0, 5), "no division by zero on an invalid grid");
    assert!(g.is_empty());
}

proptest! {
    #[test]
    fn subsets_are_spread_and_serpentine_keeps_them(
        (nx, nx_sub) in (1usize..200).prop_flat_map(|n| (Just(n), 1..=n)),
        (ny, ny_sub) in (1usize..200).prop_flat_map(|n| (Just(n), 1..=n)),
    ) {
        let g = GridSpec::centred(nx, ny, 0.005);
        let s = g.subset(nx_sub, ny_sub).unwrap();
        prop_assert_eq!(s.len(), nx_sub * ny_sub);
        prop_assert!(s.windows(2).all(|w| w[0] < w[1]), "distinct and ascending");
        prop_assert!(s.iter().all(|&i| i < g.len()));
        // Mirror-symmetric within one index: (n - 1 - i) of the first is within 1 of the last, and so on.
        let xs: Vec<usize> = s[..nx_sub].iter().map(|&i| g.indices(i).0).collect();
        for k in 0..nx_sub {
            prop_assert!(((nx - 1 - xs[k]) as i64 - xs[nx_sub - 1 - k] as i64).abs() <= 1);
        }
        let path = g.serpentine_order(&s);
        let mut sorted = path.clone();
        sorted.sort_unstable();
        prop_assert_eq!(sorted, s);
        // Consecutive points are in the same row or adjacent rows of the subset, and a row change keeps x.
        for w in path.windows(2) {
            let (a, b) = (g.indices(w[0]), g.indices(w[1]));
            prop_assert!(a.1 == b.1 || a.0 == b.0, "{:?} -> {:?}", a, b);
        }
    }
}

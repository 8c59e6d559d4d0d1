use metaplate_core::grid::*;

#[test]
fn grid_subset_reads_nx_by_ny() {
    assert_eq!("7x5".parse(), Ok(GridSubset { nx: 7, ny: 5 }));
    assert_eq!(" 7 X 5 ".parse(), Ok(GridSubset { nx: 7, ny: 5 }));
    assert_eq!("1x1".parse(), Ok(GridSubset { nx: 1, ny: 1 }));
    assert_eq!(GridSubset { nx: 7, ny: 5 }.to_string(), "7x5");
    assert_eq!(<(usize, usize)>::from(GridSubset { nx: 7, ny: 5 }), (7, 5));
}

#[test]
fn grid_subset_refuses_bad_text_with_the_reason() {
    let reason = |text: &str| match text.parse::<GridSubset>() {
        Err(GridError::BadSubsetText { text: t, reason }) if t == text => reason,
        other => panic!("`{text}`: {other:?}"),
    };
    assert!(reason("0x5").contains("along x must be at least 1"));
    assert!(reason("5x0").contains("along y must be at least 1"));
    assert!(reason("5x").contains("along y is missing"));
    assert!(reason("x5").contains("along x is missing"));
    assert!(reason("axb").contains("`a` (points along x) is not a whole number"));
    assert!(reason("7x5x3").contains("`5x3`"));
    assert!(reason("-1x5").contains("not a whole number"));
    assert!(reason("75").contains("expected NXxNY"));
    assert!(reason("").contains("expected NXxNY"));
    assert!(reason("99999999999999999999999x1").contains("not a whole number"));
}

#[test]
fn grid_subset_checks_its_use_and_the_grid() {
    let one: GridSubset = "1x1".parse().unwrap();
    assert!(matches!(one.at_least(2), Err(GridError::BadSubsetText { .. })));
    let two: GridSubset = "2x3".parse().unwrap();
    assert_eq!(two.at_least(2), Ok(two));
    let g = GridSpec::centred(7, 5, 0.01);
    assert_eq!("7x5".parse::<GridSubset>().unwrap().indices(&g).unwrap().len(), 35);
    assert_eq!(one.indices(&g).unwrap(), vec![g.index(3, 2)]);
    assert!(matches!(
        "8x5".parse::<GridSubset>().unwrap().indices(&g),
        Err(GridError::BadSubset { nx_sub: 8, ny_sub: 5, nx: 7, ny: 5 })
    ));
}

#[test]
fn centred_paper_grid() {
    let g = GridSpec::centred(49, 25, 0.005);
    // Exact multiples of 5 mm up to rounding of the products: 1e-15 m is far below any physical length.
    assert!((g.origin_x_m + 0.12).abs() < 1e-15 && (g.origin_y_m + 0.06).abs() < 1e-15);
    assert_eq!(g.len(), 1225);
    let (x, y) = g.position_m(g.index(48, 24));
    assert!((x - 0.12).abs() < 1e-15 && (y - 0.06).abs() < 1e-15);
    assert_eq!(g.indices(g.index(17, 9)), (17, 9));
}

mod snap_tests {
    use proptest::prelude::*;

    use metaplate_core::grid::*;

    #[test]
    fn a_subset_of_a_grid_snaps_to_its_common_step() {
        let grid = GridSpec::centred(49, 25, 0.005);
        let subset = grid.subset(7, 5).unwrap();
        let positions: Vec<_> = subset.iter().map(|&i| grid.position_m(i)).collect();
        let (snapped, indices) = snap_to_grid(&positions).unwrap();
        assert!((snapped.spacing_m - 0.005).abs() < 1e-12, "{snapped:?}");
        for (&i, &p) in indices.iter().zip(&positions) {
            let q = snapped.position_m(i);
            assert!((q.0 - p.0).abs() < 1e-9 && (q.1 - p.1).abs() < 1e-9);
        }
    }

    #[test]
    fn refuses_what_is_not_a_grid_with_the_reason() {
        let reason = |p: &[(f64, f64)]| match snap_to_grid(p) {
            Err(GridError::NotRegular { reason }) => reason,
            other => panic!("{p:?}: {other:?}"),
        };
        assert!(reason(&[]).contains("no position"));
        assert!(reason(&[(0.0, 0.0), (0.0, 0.0)]).contains("one point"));
        assert!(reason(&[(0.0, 0.0), (f64::NAN, 0.0)]).contains("not finite"));
        assert!(reason(&[(0.0, 0.0), (0.01, 0.0), (0.0173, 0.0)]).contains("sixteenth"));
        assert!(reason(&[(0.0, 0.0), (1e-3, 0.0), (1e3, 1e3)]).contains("limit"));
    }

    proptest! {
        /// Any positions: a grid with every position on its own node, or a typed refusal; never a panic.
        #[test]
        fn snapping_never_panics_and_places_every_position(
            positions in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..40),
        ) {
            if let Ok((grid, indices)) = snap_to_grid(&positions) {
                prop_assert!(grid.validate().is_ok());
                prop_assert_eq!(indices.len(), positions.len());
                for (&i, &(x, y)) in indices.iter().zip(&positions) {
                    let (gx, gy) = grid.position_m(i);
                    prop_assert!((gx - x).abs() < 1e-5 && (gy - y).abs() < 1e-5);
                }
            }
        }

        /// Points of a regular grid, shuffled and thinned: snapped back onto nodes at the grid's spacing or a
        /// multiple of it.
        #[test]
        fn grid_points_snap_back(
            nx in 2usize..20, ny in 1usize..10, spacing_mm in 1u32..50, keep in prop::collection::vec(any::<bool>(), 200),
        ) {
            let grid = GridSpec::centred(nx, ny, f64::from(spacing_mm) * 1e-3);
            let positions: Vec<_> =
                (0..grid.len()).filter(|&i| keep[i % keep.len()] || i == 0 || i == 1).map(|i| grid.position_m(i)).collect();
            let (snapped, _) = snap_to_grid(&positions).unwrap();
            let ratio = snapped.spacing_m / grid.spacing_m;
            prop_assert!((ratio - ratio.round()).abs() < 1e-6 && ratio >= 0.999, "{snapped:?}");
        }
    }
}

//! POD, authority and the refresh rule on synthetic propagation matrices whose answers are known exactly.

#![allow(clippy::unwrap_used)] // helpers outside #[test] functions unwrap too: a failure is a failed test

use metaplate_analysis::AnalysisError;
use metaplate_analysis::authority::{AuthorityOptions, domain_authority};
use metaplate_analysis::pod::{PodOptions, pod};
use metaplate_analysis::refresh::resolvable;
use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSpec;
use num_complex::Complex64;

/// `G` on a 9 x 9 grid at 5 mm (81 points), 8 actuators, bins 150..=800 of a 2000-point DFT at 2 kHz (75 to 400 Hz).
fn matrices(entry: impl Fn(usize, usize, usize) -> Complex64) -> (PropagationMatrices, GridSpec) {
    let grid = GridSpec::centred(9, 9, 0.005);
    let (m, n, bins) = (81, 8, 150..401);
    let mut data = Vec::new();
    for k in bins.clone() {
        for a in 0..n {
            for p in 0..m {
                data.push(entry(k, p, a));
            }
        }
    }
    let g = PropagationMatrices::from_parts(bins, 1000, 1000.0, (0..81).collect(), (0..8).collect(), data).unwrap();
    (g, grid)
}

#[test]
fn pod_of_one_spatial_pattern_is_one_component() {
    // h(x, f) = s(x) c(f): rank one whatever the spectra.
    let (g, _) = matrices(|k, p, a| Complex64::from_polar((p as f64 + 1.0).sin() * (a + 1) as f64, 0.1 * k as f64));
    let p = pod(&g, &PodOptions::default()).unwrap();
    assert_eq!(p.components, 1);
    // Sums to 1 up to rounding of a few hundred terms (1e-12).
    assert!((p.energy.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert_eq!(p.components_for(0.0), 0);
}

#[test]
fn pod_refuses_zero_response_and_bad_fractions() {
    let (zero, _) = matrices(|_, _, _| Complex64::new(0.0, 0.0));
    assert!(matches!(pod(&zero, &PodOptions::default()), Err(AnalysisError::NoEnergy { .. })));
    let (g, _) = matrices(|_, p, _| Complex64::new(p as f64, 0.0));
    for f in [0.0, 1.5, f64::NAN] {
        let opts = PodOptions { energy_fraction: f, ..PodOptions::default() };
        assert!(matches!(pod(&g, &opts), Err(AnalysisError::InvalidParameter { .. })), "{f}");
    }
    // The whole energy (fraction 1) is reached by the one non-zero component.
    assert_eq!(pod(&g, &PodOptions { energy_fraction: 1.0, ..PodOptions::default() }).unwrap().components, 1);
}

#[test]
fn orthogonal_actuators_have_full_rank_and_unit_condition() {
    // Column a is the a-th DFT pattern over the points: orthogonal columns of equal norm, so all sigma are equal.
    let (g, grid) = matrices(|_, p, a| Complex64::from_polar(1.0, 2.0 * std::f64::consts::PI * (p * a) as f64 / 81.0));
    let a = domain_authority(&g, &grid, 0.1, &AuthorityOptions::default()).unwrap();
    assert_eq!(a.points.len(), 81);
    assert_eq!(a.mean_effective_rank(), 8.0);
    // Equal singular values up to the SVD's rounding (1e-9 relative).
    assert!((a.mean_condition_number() - 1.0).abs() < 1e-9);
}

#[test]
fn weak_directions_below_minus_30_db_do_not_count() {
    // Actuator a drives pattern a with amplitude 10^(-a/2): energies 0, -10, -20, ... dB; four lie within -30 dB.
    let (g, grid) = matrices(|_, p, a| {
        Complex64::from_polar(10f64.powf(-(a as f64) / 2.0), 2.0 * std::f64::consts::PI * (p * a) as f64 / 81.0)
    });
    let a = domain_authority(&g, &grid, 0.1, &AuthorityOptions::default()).unwrap();
    assert_eq!(a.mean_effective_rank(), 4.0);
    // sigma_1 / sigma_8 = 10^(7/2), to SVD rounding (1e-6 relative).
    assert!((a.mean_condition_number() / 10f64.powf(3.5) - 1.0).abs() < 1e-6);
}

#[test]
fn authority_refuses_small_domains_bad_edges_and_singular_matrices() {
    let (g, grid) = matrices(|_, p, a| Complex64::new((p * a) as f64, 1.0));
    // 1 cm holds 3 x 3 = 9 points: enough; 0.5 cm holds 1.
    assert_eq!(domain_authority(&g, &grid, 0.01, &AuthorityOptions::default()).map(|a| a.points.len()), Ok(9));
    assert!(matches!(
        domain_authority(&g, &grid, 0.005, &AuthorityOptions::default()),
        Err(AnalysisError::TooFewPoints { measured: 1, required: 8 })
    ));
    for edge in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let r = domain_authority(&g, &grid, edge, &AuthorityOptions::default());
        assert!(matches!(r, Err(AnalysisError::InvalidParameter { .. })), "{edge}");
    }
    // Two identical actuators: sigma_8 = 0 up to rounding, kappa huge or infinite, never NaN.
    let (twin, grid) =
        matrices(|_, p, a| Complex64::new(((p + 1) * (a.min(6) + 1)) as f64, (p % (a.min(6) + 2)) as f64));
    match domain_authority(&twin, &grid, 0.1, &AuthorityOptions::default()) {
        Ok(a) => assert!(a.mean_condition_number() > 1e10 && a.mean_condition_number().is_finite()),
        Err(e) => assert!(matches!(e, AnalysisError::NonFiniteResult { .. })),
    }
}

#[test]
fn peak_to_valley_rule() {
    // Two unit peaks at 10 and 20 with a valley of v between them.
    let profile = |v: f64| -> Vec<f64> {
        (0..31)
            .map(|i| {
                if i == 10 || i == 20 {
                    1.0
                } else if (11..20).contains(&i) {
                    v
                } else {
                    0.0
                }
            })
            .collect()
    };
    assert!(resolvable(&profile(0.5), 10, 20, 0.5), "a valley at exactly half is resolved");
    assert!(!resolvable(&profile(0.51), 10, 20, 0.5));
    // One merged peak between the centres: not resolved.
    let merged: Vec<f64> = (0..31).map(|i| 1.0 / (1.0 + ((i as f64 - 15.0) / 8.0).powi(2))).collect();
    assert!(!resolvable(&merged, 10, 20, 0.5));
    // Out of range or out of order: false, never a panic.
    assert!(!resolvable(&profile(0.0), 20, 10, 0.5));
    assert!(!resolvable(&profile(0.0), 10, 31, 0.5));
    assert!(!resolvable(&[], 0, 1, 0.5));
}

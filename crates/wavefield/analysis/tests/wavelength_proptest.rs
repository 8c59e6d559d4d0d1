//! Random fields, masks, shapes and options never make the wavelength estimator panic, and whatever it returns is
//! finite and ordered.
#![allow(clippy::unwrap_used)] // tests may unwrap

use metaplate_analysis::wavelength::{BinWeighting, KSpaceMethod, KSpaceOptions, estimate_wavelength};
use num_complex::Complex64;
use proptest::prelude::*;

fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3f64..1e3,
        1 => Just(0.0),
        1 => prop::num::f64::ANY,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn random_fields_never_panic(
        (nx, ny, values, mask) in (1usize..12, 1usize..12).prop_flat_map(|(nx, ny)| {
            let n = nx * ny;
            (Just(nx), Just(ny), prop::collection::vec((value(), value()), n), prop::collection::vec(any::<bool>(), n))
        }),
        spacing_m in prop_oneof![Just(0.005), 1e-6f64..10.0, prop::num::f64::ANY],
        zero_pad_factor in 0usize..10,
        taper_width_m in prop_oneof![Just(0.0), 0.0f64..0.05],
        remove_mean in any::<bool>(),
        radial in any::<bool>(),
        energy in any::<bool>(),
    ) {
        let field: Vec<Complex64> = values.iter().map(|&(re, im)| Complex64::new(re, im)).collect();
        let opts = KSpaceOptions {
            zero_pad_factor,
            taper_width_m,
            remove_mean,
            min_k_rad_m: None,
            method: if radial { KSpaceMethod::RadialProfile } else { KSpaceMethod::HalfMaxContour },
            weighting: if energy { BinWeighting::Energy } else { BinWeighting::Uniform },
        };
        if let Ok(e) = estimate_wavelength(&field, &mask, nx, ny, spacing_m, &opts) {
            for v in [e.peak_m, e.median_m, e.iqr_m.0, e.iqr_m.1] {
                prop_assert!(v.is_finite() && v > 0.0, "{e:?}");
            }
            prop_assert!(e.iqr_m.0 <= e.median_m && e.median_m <= e.iqr_m.1, "{e:?}");
            prop_assert!(e.bins_in_contour >= 1);
            // Nothing beyond the spatial Nyquist limit |kx|, |ky| <= pi / d can come out: lambda >= sqrt(2) d on the
            // diagonal (rounding aside).
            prop_assert!(e.iqr_m.0 >= std::f64::consts::SQRT_2 * spacing_m * (1.0 - 1e-9), "{e:?}");
        }
    }
}

//! The coupling validated: a thin plate with a lattice of spring-mass resonators against the plane-wave expansion
//! (tests/pwe.rs), within 2 % (the figure).

use metaplate_core::design::{CellPlate, CellResonator, Design, SpringMassSpec};
use metaplate_design::{CellModel, MeshOptions, Reduction, Sides, gamma_x_m_path};

use crate::pwe::PointResonatorPlate;

/// A 20 mm cell of 0.83 mm acrylic (a / 24: k h <= 0.19 on the path, so Mindlin's waves are at most 0.7 % below
/// Kirchhoff's, and the 5 mm elements are 6 thicknesses long, short enough not to lock) with a
/// resonator of half the cell's plate mass tuned to 400 Hz, on a footprint of a/100 (rigid and point-like alike
/// within 0.1 %). Both branches of the hybridisation (below and above the resonance) at wave vectors on every leg
/// of the path.
#[test]
fn spring_mass_lattice_matches_plane_wave_expansion_within_2_percent() {
    let a = 0.02;
    let plate = CellPlate { thickness_m: a / 24.0, ..metaplate_core::design::PAPER_PLATE };
    let mass_kg = 0.5 * plate.areal_density_kg_m2() * a * a;
    let stiffness_n_per_m = mass_kg * (2.0 * std::f64::consts::PI * 400.0_f64).powi(2);
    let design = Design {
        name: "spring-mass".into(),
        lattice_constant_m: a,
        plate,
        resonator: CellResonator::SpringMass(SpringMassSpec {
            mass_kg,
            stiffness_n_per_m,
            footprint_radius_m: a / 100.0,
        }),
    };
    let reference = PointResonatorPlate {
        d_n_m: plate.flexural_rigidity_n_m(),
        rho_h_kg_m2: plate.areal_density_kg_m2(),
        a_m: a,
        mass_kg,
        stiffness_n_per_m,
    };
    let model = CellModel::new(&design, MeshOptions { per_side: 4, radial: 4, rod_elements: 1 });
    let reduction = Reduction::new(&model, Sides::Periodic).unwrap();
    let path = gamma_x_m_path(a, 13);
    let mut worst: f64 = 0.0;
    for p in path.iter().filter(|p| p.k_rad_m() > 0.0) {
        let fe = reduction.solve(&model, p.kx_rad_m, p.ky_rad_m, 4).unwrap();
        let pwe = reference.frequencies_hz(p.kx_rad_m, p.ky_rad_m, 2, 5000.0);
        assert_eq!(pwe.len(), 2, "the reference finds both branches at {p:?}");
        // The lowest branch is the lowest mode; each branch of the reference is a mode of the cell. (The cell also
        // has plate waves with a node at every resonator, w(0) = 0, which the reference's relation leaves out:
        // near X the antisymmetric one of the two folded A0 waves.)
        assert!((fe[0].freq_hz / pwe[0] - 1.0).abs() < 0.02, "at {p:?}: FE {fe:?} against PWE {pwe:?}");
        for r in &pwe {
            let nearest = fe.iter().map(|f| f.freq_hz / r - 1.0).min_by(|x, y| x.abs().total_cmp(&y.abs())).unwrap();
            worst = worst.max(nearest.abs());
            assert!(nearest.abs() < 0.02, "at {p:?}: PWE {r} Hz, FE {fe:?}");
        }
    }
    eprintln!("spring-mass lattice: worst relative difference from the PWE {:.3} %", 100.0 * worst);
}

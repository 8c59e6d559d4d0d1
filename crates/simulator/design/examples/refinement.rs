//! The mesh refinement study of docs/design.md: the first three branches of the paper's cell at 16 wave vectors
//! along Gamma-X-M-Gamma, for the default mesh and refinements of its plate and rod, against the mesh twice as fine
//! in every direction; and that reference against a finer one still (4/3 as fine again) at two wave vectors.
//!
//! `cargo run --release -p metaplate-design --example refinement`

#![allow(clippy::expect_used)] // An example: a failure is reported by the panic.

use metaplate_core::design::Design;
use metaplate_design::{CellModel, MeshOptions, Reduction, Sides, clamped_resonator_mode, gamma_x_m_path};

fn branches(design: &Design, mesh: MeshOptions, ks: &[(f64, f64)]) -> (usize, Vec<[f64; 3]>) {
    let model = CellModel::new(design, mesh);
    let reduction = Reduction::new(&model, Sides::Periodic).expect("periodic reduction");
    let f = ks
        .iter()
        .map(|&(kx, ky)| {
            let m = reduction.solve(&model, kx, ky, 3).expect("eigenproblem");
            [m[0].freq_hz, m[1].freq_hz, m[2].freq_hz]
        })
        .collect();
    (reduction.len(), f)
}

fn worst(a: &[[f64; 3]], b: &[[f64; 3]]) -> [f64; 3] {
    let mut w = [0.0f64; 3];
    for (x, y) in a.iter().zip(b) {
        for m in 0..3 {
            if y[m] > 1.0 {
                w[m] = w[m].max((x[m] / y[m] - 1.0).abs());
            }
        }
    }
    w
}

fn main() {
    let design = Design::paper();
    let ks: Vec<(f64, f64)> =
        gamma_x_m_path(design.lattice_constant_m, 16).iter().map(|p| (p.kx_rad_m, p.ky_rad_m)).collect();
    let d = MeshOptions::default();
    let reference_mesh = MeshOptions::refined(2);
    let (ref_dofs, reference) = branches(&design, reference_mesh, &ks);
    let fn_ref = clamped_resonator_mode(&design, reference_mesh).expect("clamped").map_or(0.0, |m| m.freq_hz);
    println!("reference: {reference_mesh:?}, {ref_dofs} DOFs, f_n {fn_ref:.2} Hz");
    println!("{:<44} {:>6} {:>9} {:>9} {:>9} {:>9}", "mesh", "DOFs", "m=1 %", "m=2 %", "m=3 %", "f_n %");
    let cases = [
        ("default", d),
        ("plate x2 tangential", MeshOptions { per_side: 2 * d.per_side, ..d }),
        ("plate x2 radial", MeshOptions { radial: 2 * d.radial, ..d }),
        ("rod x2", MeshOptions { rod_elements: 2 * d.rod_elements, ..d }),
        ("previous default: 2 per side", MeshOptions { per_side: 2, ..d }),
        ("coarser: 1 per side, 2 radial, 3 rod", MeshOptions { per_side: 1, radial: 2, rod_elements: 3 }),
    ];
    for (name, mesh) in cases {
        let (dofs, f) = branches(&design, mesh, &ks);
        let fn_hz = clamped_resonator_mode(&design, mesh).expect("clamped").map_or(0.0, |m| m.freq_hz);
        let w = worst(&f, &reference);
        println!(
            "{:<44} {:>6} {:>9.3} {:>9.3} {:>9.3} {:>9.3}",
            format!("{name} {mesh:?}").chars().take(44).collect::<String>(),
            dofs,
            100.0 * w[0],
            100.0 * w[1],
            100.0 * w[2],
            100.0 * (fn_hz / fn_ref - 1.0).abs()
        );
    }
    // The reference's own error: against a finer mesh, at one wave vector on Gamma-X and at M.
    let xm = [
        (ks[5].0, ks[5].1),
        (std::f64::consts::PI / design.lattice_constant_m, std::f64::consts::PI / design.lattice_constant_m),
    ];
    let finer = MeshOptions { per_side: 8, radial: 8, rod_elements: 16 };
    let (_, fine) = branches(&design, finer, &xm);
    let (_, coarse) = branches(&design, reference_mesh, &xm);
    let w = worst(&coarse, &fine);
    println!(
        "reference against {finer:?} at two wave vectors: {:.3} % {:.3} % {:.3} %",
        100.0 * w[0],
        100.0 * w[1],
        100.0 * w[2]
    );
}

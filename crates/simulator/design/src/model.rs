//! The cell's finite-element model: the plate's elements on the O-grid, the rigid footprint (three master degrees
//! of freedom: deflection `w0` and rotations `bx`, `by` at the centre), and the resonator attached to it.
//!
//! The rod is a beam in each of the two bending planes, from the plate's face to its tip; its base moves with the
//! footprint (lateral displacement `z0 bx`, section rotation `bx`, with `z0` the face's height above the mid-plane),
//! so its bending couples to the plate's rotation: the rod rocks. Axially the rod is rigid (its first axial mode is
//! tens of kHz), so its mass rides on `w0`. The plate's in-plane (membrane) motion is left out: it is stiffer than
//! the slow flexural waves' inertia by three orders of magnitude (docs/design.md), so the footprint's mid-plane
//! does not translate sideways.

use crate::elements::{BeamSection, PLATE_DOFS, beam, mindlin_q9};
use crate::mesh::{Mesh, MeshOptions};
use metaplate_core::design::{CellResonator, Design, RodSide};

/// Which part of the cell an element belongs to (for the kinetic-energy shares).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The plate and the footprint.
    Plate,
    /// The resonator.
    Resonator,
}

/// One element's (or lumped item's) matrices on its degrees of freedom.
#[derive(Debug, Clone)]
pub struct Block {
    /// Global (full) degrees of freedom.
    pub dofs: Vec<usize>,
    /// Stiffness, row-major.
    pub k: Vec<f64>,
    /// Mass, row-major.
    pub m: Vec<f64>,
    /// Where it belongs.
    pub part: Part,
}

/// The cell's model before boundary conditions.
#[derive(Debug, Clone)]
pub struct CellModel {
    /// The plate mesh.
    pub mesh: Mesh,
    /// Lattice constant, m.
    pub lattice_constant_m: f64,
    /// Number of full degrees of freedom (plate nodes, footprint masters, resonator, rod base).
    pub n_full: usize,
    /// Element and lumped matrices.
    pub blocks: Vec<Block>,
    /// Real constraints: a full DOF that is a combination of others (footprint nodes and the rod's base on the
    /// footprint's masters), as `(dof, [(master dof, coefficient)])`.
    pub constraints: Vec<(usize, Vec<(usize, f64)>)>,
}

/// Full DOF of a plate node's component (0: w, 1: bx, 2: by).
pub fn plate_dof(node: usize, component: usize) -> usize {
    3 * node + component
}

impl CellModel {
    /// Builds the cell's model.
    pub fn new(design: &Design, options: MeshOptions) -> Self {
        let a = design.lattice_constant_m;
        let r = design.footprint_radius_m();
        let mesh = Mesh::o_grid(a, r, options);
        let mut blocks = Vec::with_capacity(mesh.elements.len() + 8);
        for element in &mesh.elements {
            let xy = element.map(|n| mesh.nodes[n]);
            let (k, m) = mindlin_q9(&design.plate, &xy);
            let dofs = element.iter().flat_map(|&n| (0..3).map(move |c| plate_dof(n, c))).collect::<Vec<_>>();
            debug_assert_eq!(dofs.len(), PLATE_DOFS);
            blocks.push(Block { dofs, k, m, part: Part::Plate });
        }
        // The footprint's masters: w0, bx, by.
        let master = 3 * mesh.nodes.len();
        let (w0, bx, by) = (master, master + 1, master + 2);
        let mut constraints = Vec::new();
        for &n in &mesh.footprint_nodes {
            let [x, y] = mesh.nodes[n];
            // Rigid motion: w = w0 - x bx - y by (so that u = z bx is a rotation), rotations equal the footprint's.
            constraints.push((plate_dof(n, 0), vec![(w0, 1.0), (bx, -x), (by, -y)]));
            constraints.push((plate_dof(n, 1), vec![(bx, 1.0)]));
            constraints.push((plate_dof(n, 2), vec![(by, 1.0)]));
        }
        let m_f = design.footprint_mass_kg();
        let h = design.plate.thickness_m;
        let i_f = m_f * (h * h / 12.0 + r * r / 4.0);
        blocks.push(Block {
            dofs: vec![w0, bx, by],
            k: vec![0.0; 9],
            m: vec![m_f, 0.0, 0.0, 0.0, i_f, 0.0, 0.0, 0.0, i_f],
            part: Part::Plate,
        });
        let mut n_full = master + 3;
        match &design.resonator {
            CellResonator::None => {}
            CellResonator::SpringMass(s) => {
                let u = n_full;
                n_full += 1;
                let ks = s.stiffness_n_per_m;
                blocks.push(Block { dofs: vec![w0, u], k: vec![ks, -ks, -ks, ks], m: vec![0.0; 4], part: Part::Plate });
                blocks.push(Block { dofs: vec![u], k: vec![0.0], m: vec![s.mass_kg], part: Part::Resonator });
            }
            CellResonator::Rod(rod) => {
                let section =
                    BeamSection::circular(rod.diameter_m, rod.youngs_modulus_pa, rod.poisson_ratio, rod.density_kg_m3);
                let z0 = match rod.side {
                    RodSide::Top => h / 2.0,
                    RodSide::Bottom => -h / 2.0,
                };
                let elements = options.rod_elements.max(1);
                let l = rod.free_length_m() / elements as f64;
                let (ke, me) = beam(&section, l);
                // Two planes: x-z (driven by bx) and y-z (by). A bottom rod points down: its axis coordinate runs
                // along -z, which flips the sign of its lateral displacement's slope; mirror images, same bands.
                let sign = if rod.side == RodSide::Top { 1.0 } else { -1.0 };
                for rotation in [bx, by] {
                    let base = n_full;
                    n_full += 2 * (elements + 1);
                    constraints.push((base, vec![(rotation, z0)]));
                    constraints.push((base + 1, vec![(rotation, sign)]));
                    for e in 0..elements {
                        let dofs = (0..4).map(|i| base + 2 * e + i).collect();
                        blocks.push(Block { dofs, k: ke.to_vec(), m: me.to_vec(), part: Part::Resonator });
                    }
                }
                blocks.push(Block { dofs: vec![w0], k: vec![0.0], m: vec![rod.free_mass_kg()], part: Part::Resonator });
            }
        }
        Self { mesh, lattice_constant_m: a, n_full, blocks, constraints }
    }
}

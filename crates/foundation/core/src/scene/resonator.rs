//! The resonator lattice: brass rods standing on the plate (the metamaterial), or none.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::error::SceneError;
use super::outline::Outline;

/// The most resonators a lattice may hold (the paper's plate has about 400).
pub const MAX_RESONATORS: usize = 1_000_000;

/// How the plate model treats the resonators. TOML: `model = "none" | "added_mass" | "rocking_rod"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResonatorModel {
    /// A plain plate: no resonators.
    None,
    /// Each rod is a mass on a spring at its site: a single resonance per rod.
    AddedMass,
    /// Each rod is a rigid rod on a compliant joint, coupling plate slope as well as displacement.
    RockingRod,
}

/// A square lattice of rod resonators, with the rod geometry and material.
///
/// With `model = "none"` every other field may be omitted from the TOML and takes its zero default. Otherwise the
/// valid range (checked by [`crate::scene::Scene::validate`]) is: finite `pitch_m`, `rod_height_m`,
/// `rod_diameter_m`, `rod_youngs_modulus_pa`, `rod_density_kg_m3` all `> 0`; `rod_diameter_m < pitch_m`;
/// `loss_factor >= 0`; `region_inset_m >= 0` and leaving some plate; `0 <= height_spread < 0.5`; overrides,
/// when present, `> 0`, and `gyration_radius_m <= rod_height_m`; at most [`MAX_RESONATORS`] rods.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ResonatorFile")]
pub struct ResonatorSpec {
    /// How the plate model treats the rods.
    pub model: ResonatorModel,
    /// Lattice constant a, m.
    pub pitch_m: f64,
    /// Mean rod height, m.
    pub rod_height_m: f64,
    /// Rod diameter, m.
    pub rod_diameter_m: f64,
    /// Rod Young's modulus, Pa.
    pub rod_youngs_modulus_pa: f64,
    /// Rod density, kg/m^3.
    pub rod_density_kg_m3: f64,
    /// Loss factor of the rod and its joint (dimensionless).
    pub loss_factor: f64,
    /// The lattice covers the outline shrunk by this margin, m.
    pub region_inset_m: f64,
    /// Relative standard deviation of the rod heights (hand-cut rods differ), dimensionless.
    pub height_spread: f64,
    /// Effective-model override: resonator mass / plate mass per unit cell. When absent, derived from the rod
    /// ([`ResonatorSpec::cell_mass_ratio`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_ratio: Option<f64>,
    /// Effective-model override: resonance frequency of one resonator on the plate, Hz. When absent, derived from
    /// the rod by the plate model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resonance_hz: Option<f64>,
    /// Effective-model override (`rocking_rod` only): the rod's radius of gyration about its base, m, so that its
    /// rotary inertia is `m r^2`. When absent, a rigid rod pivoting at its base: `rod_height_m / sqrt(3)`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gyration_radius_m: Option<f64>,
}

impl ResonatorSpec {
    /// No resonators: `model = "none"`, every other field zero or absent.
    pub fn none() -> Self {
        Self {
            model: ResonatorModel::None,
            pitch_m: 0.0,
            rod_height_m: 0.0,
            rod_diameter_m: 0.0,
            rod_youngs_modulus_pa: 0.0,
            rod_density_kg_m3: 0.0,
            loss_factor: 0.0,
            region_inset_m: 0.0,
            height_spread: 0.0,
            mass_ratio: None,
            resonance_hz: None,
            gyration_radius_m: None,
        }
    }

    /// Radius of gyration of a rod of the mean height about its base, m: the override, or a rigid rod's
    /// `rod_height_m / sqrt(3)`.
    pub fn gyration_radius_m(&self) -> f64 {
        self.gyration_radius_m.unwrap_or(self.rod_height_m / 3f64.sqrt())
    }

    /// Mass of one rod of the mean height, `rho pi d^2 / 4 h`, kg.
    pub fn rod_mass_kg(&self) -> f64 {
        self.rod_density_kg_m3 * PI * self.rod_diameter_m.powi(2) / 4.0 * self.rod_height_m
    }

    /// Rod mass over the plate mass of one unit cell (`rho_plate h a^2`, holes ignored), dimensionless.
    ///
    /// # Errors
    /// [`SceneError::InvalidArgument`] when the ratio is not finite (no lattice, or an unvalidated plate).
    pub fn cell_mass_ratio(&self, plate_mass_per_area_kg_m2: f64) -> Result<f64, SceneError> {
        let ratio = self.rod_mass_kg() / (plate_mass_per_area_kg_m2 * self.pitch_m.powi(2));
        if ratio.is_finite() {
            Ok(ratio)
        } else {
            Err(SceneError::invalid_argument("pitch_m", format!("gives a non-finite mass ratio ({ratio})")))
        }
    }

    /// Centres `(x_m, y_m)` of the rods, m: the square lattice with a site at the plate's centre, kept where a
    /// site is at least `region_inset_m` inside `outline`. Empty for `model = "none"`. Sorted row by row.
    ///
    /// # Errors
    /// [`SceneError::InvalidArgument`] when the pitch is not finite and positive, or the lattice would hold more
    /// than [`MAX_RESONATORS`] rods.
    pub fn lattice_sites_m(&self, outline: &Outline) -> Result<Vec<(f64, f64)>, SceneError> {
        if self.model == ResonatorModel::None {
            return Ok(Vec::new());
        }
        let a = self.pitch_m;
        let (x_min, x_max, y_min, y_max) = outline.bounding_box_m();
        let (nx_half, ny_half) = ((x_max.max(-x_min) / a).floor(), (y_max.max(-y_min) / a).floor());
        let sites_bound = (2.0 * nx_half + 1.0) * (2.0 * ny_half + 1.0);
        if !(a.is_finite() && a > 0.0 && sites_bound.is_finite() && sites_bound <= MAX_RESONATORS as f64) {
            return Err(SceneError::invalid_argument(
                "pitch_m",
                format!("{a} m gives too many rods (more than {MAX_RESONATORS}) or is not positive"),
            ));
        }
        let (nx_half, ny_half) = (nx_half as i64, ny_half as i64);
        let sites = (-ny_half..=ny_half)
            .flat_map(|j| (-nx_half..=nx_half).map(move |i| (i as f64 * a, j as f64 * a)))
            .filter(|&(x, y)| outline.distance_inside_m(x, y) >= self.region_inset_m)
            .collect();
        Ok(sites)
    }
}

/// The TOML form: fields other than `model` may be omitted when `model = "none"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ResonatorFile {
    model: ResonatorModel,
    pitch_m: Option<f64>,
    rod_height_m: Option<f64>,
    rod_diameter_m: Option<f64>,
    rod_youngs_modulus_pa: Option<f64>,
    rod_density_kg_m3: Option<f64>,
    loss_factor: Option<f64>,
    region_inset_m: Option<f64>,
    height_spread: Option<f64>,
    mass_ratio: Option<f64>,
    resonance_hz: Option<f64>,
    gyration_radius_m: Option<f64>,
}

impl TryFrom<ResonatorFile> for ResonatorSpec {
    type Error = String;

    fn try_from(f: ResonatorFile) -> Result<Self, String> {
        let needs_rods = f.model != ResonatorModel::None;
        let field = |name: &str, v: Option<f64>| match v {
            Some(v) => Ok(v),
            None if needs_rods => Err(format!("missing key `{name}` (needed unless model = \"none\")")),
            None => Ok(0.0),
        };
        Ok(Self {
            model: f.model,
            pitch_m: field("pitch_m", f.pitch_m)?,
            rod_height_m: field("rod_height_m", f.rod_height_m)?,
            rod_diameter_m: field("rod_diameter_m", f.rod_diameter_m)?,
            rod_youngs_modulus_pa: field("rod_youngs_modulus_pa", f.rod_youngs_modulus_pa)?,
            rod_density_kg_m3: field("rod_density_kg_m3", f.rod_density_kg_m3)?,
            loss_factor: field("loss_factor", f.loss_factor)?,
            region_inset_m: field("region_inset_m", f.region_inset_m)?,
            // A perfect lattice is a sensible default; the spread is a refinement.
            height_spread: f.height_spread.unwrap_or(0.0),
            mass_ratio: f.mass_ratio,
            resonance_hz: f.resonance_hz,
            gyration_radius_m: f.gyration_radius_m,
        })
    }
}

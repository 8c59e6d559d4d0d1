//! The resonator lattice: brass rods standing on the plate (the metamaterial), or none. A lattice either names a
//! unit-cell design (`design = "paper"` or a design file), which gives the lattice constant and the rods, or gives
//! them key by key.

use std::f64::consts::PI;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::SceneError;
use super::outline::Outline;
use crate::design::{CellResonator, Design};
use crate::toml_locate::TomlFileError;

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
/// when present, `> 0`, and `gyration_radius_m <= rod_height_m`; at most [`MAX_RESONATORS`] rods. With a `design`,
/// the model is `rocking_rod`, the design's resonator a rod, its plate the scene's, and no override is given.
#[derive(Debug, Clone, PartialEq)]
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
    pub mass_ratio: Option<f64>,
    /// Effective-model override: resonance frequency of one resonator on the plate, Hz. When absent, derived from
    /// the rod by the plate model.
    pub resonance_hz: Option<f64>,
    /// Effective-model override (`rocking_rod` only): the rod's radius of gyration about its base, m, so that its
    /// rotary inertia is `m r^2`. When absent, a rigid rod pivoting at its base: `rod_height_m / sqrt(3)`.
    pub gyration_radius_m: Option<f64>,
    /// The unit cell the lattice is built from: `pitch_m` and the rod's keys are its lattice constant and rod (whole
    /// height), and the plate model takes the rods' dynamics from the cell's band structure (`metaplate-design`'s
    /// homogenised fit) rather than from the rod alone.
    pub design: Option<Design>,
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
            design: None,
        }
    }

    /// Radius of gyration of a rod of the mean height about its base, m: the override, or a rigid rod's
    /// `rod_height_m / sqrt(3)`.
    pub fn gyration_radius_m(&self) -> f64 {
        self.gyration_radius_m.unwrap_or(self.rod_height_m / 3f64.sqrt())
    }

    /// This lattice's loss, inset and spread with the rods of `design`: `rocking_rod`, its lattice constant and rod,
    /// no override.
    ///
    /// # Errors
    /// [`SceneError::InvalidArgument`] when the design's resonator is not a rod.
    pub fn with_design(&self, design: Design) -> Result<Self, SceneError> {
        let CellResonator::Rod(rod) = design.resonator else {
            return Err(SceneError::invalid_argument(
                "design",
                format!("design `{}` has no rod: a scene's lattice holds rods", design.name),
            ));
        };
        Ok(Self {
            model: ResonatorModel::RockingRod,
            pitch_m: design.lattice_constant_m,
            rod_height_m: rod.height_m,
            rod_diameter_m: rod.diameter_m,
            rod_youngs_modulus_pa: rod.youngs_modulus_pa,
            rod_density_kg_m3: rod.density_kg_m3,
            mass_ratio: None,
            resonance_hz: None,
            gyration_radius_m: None,
            design: Some(design),
            ..self.clone()
        })
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

/// The TOML form: fields other than `model` may be omitted when `model = "none"`, and the lattice's and rod's when
/// a `design` gives them. Written back with the design inline, so that a scene's text stands alone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ResonatorFile {
    model: ResonatorModel,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pitch_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rod_height_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rod_diameter_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rod_youngs_modulus_pa: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rod_density_kg_m3: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    loss_factor: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    region_inset_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    height_spread: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    mass_ratio: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    resonance_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gyration_radius_m: Option<f64>,
    /// Last: a table, which TOML writes after the plain keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    design: Option<DesignEntry>,
}

/// A design named (a built-in, or a file's path relative to the scene file) or written inline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
enum DesignEntry {
    Named(String),
    Inline(Design),
}

impl ResonatorFile {
    /// No resonators.
    pub(crate) fn none() -> Self {
        Self::from(&ResonatorSpec::none())
    }

    /// The lattice this describes; a design's file path is taken relative to `base` (the scene file's folder).
    ///
    /// # Errors
    /// `(key path, why)`: a missing key, a key the design gives, a design that cannot be read or is not a rod's.
    pub(crate) fn resolve(self, base: Option<&Path>) -> Result<ResonatorSpec, (String, String)> {
        let at = |key: &str, message: String| (format!("resonators.{key}"), message);
        let design = match self.design {
            None => None,
            Some(DesignEntry::Inline(design)) => Some(design),
            Some(DesignEntry::Named(name)) => {
                let resolved = match (Design::builtin(&name), base) {
                    (Some(d), _) => Ok(d),
                    (None, Some(base)) if Path::new(&name).is_relative() => Design::load(&base.join(&name)),
                    (None, _) => Design::load(Path::new(&name)),
                };
                Some(resolved.map_err(|e| match e {
                    TomlFileError::Io { .. } => at(
                        "design",
                        format!("{e} (nor is it a built-in design: {})", crate::design::BUILTIN_DESIGNS.join(", ")),
                    ),
                    TomlFileError::Invalid(_) => at("design", e.to_string()),
                })?)
            }
        };
        if let Some(design) = design {
            if self.model != ResonatorModel::RockingRod {
                return Err(at("model", "a design's rods rock with the plate: use model = \"rocking_rod\"".into()));
            }
            for (name, v) in [
                ("pitch_m", self.pitch_m),
                ("rod_height_m", self.rod_height_m),
                ("rod_diameter_m", self.rod_diameter_m),
                ("rod_youngs_modulus_pa", self.rod_youngs_modulus_pa),
                ("rod_density_kg_m3", self.rod_density_kg_m3),
            ] {
                if v.is_some() {
                    return Err(at(name, "is given by the design (leave it out, or drop `design`)".into()));
                }
            }
            for (name, v) in [
                ("mass_ratio", self.mass_ratio),
                ("resonance_hz", self.resonance_hz),
                ("gyration_radius_m", self.gyration_radius_m),
            ] {
                if v.is_some() {
                    return Err(at(name, "is taken from the design's cell (leave it out, or drop `design`)".into()));
                }
            }
            let missing = |name: &str| at(name, format!("missing key `{name}`"));
            let lattice = ResonatorSpec {
                model: self.model,
                loss_factor: self.loss_factor.ok_or_else(|| missing("loss_factor"))?,
                region_inset_m: self.region_inset_m.ok_or_else(|| missing("region_inset_m"))?,
                height_spread: self.height_spread.unwrap_or(0.0),
                ..ResonatorSpec::none()
            };
            return lattice.with_design(design).map_err(|e| at("design", e.to_string()));
        }
        let needs_rods = self.model != ResonatorModel::None;
        let field = |name: &str, v: Option<f64>| match v {
            Some(v) => Ok(v),
            None if needs_rods => Err(at(name, format!("missing key `{name}` (needed unless model = \"none\")"))),
            None => Ok(0.0),
        };
        Ok(ResonatorSpec {
            model: self.model,
            pitch_m: field("pitch_m", self.pitch_m)?,
            rod_height_m: field("rod_height_m", self.rod_height_m)?,
            rod_diameter_m: field("rod_diameter_m", self.rod_diameter_m)?,
            rod_youngs_modulus_pa: field("rod_youngs_modulus_pa", self.rod_youngs_modulus_pa)?,
            rod_density_kg_m3: field("rod_density_kg_m3", self.rod_density_kg_m3)?,
            loss_factor: field("loss_factor", self.loss_factor)?,
            region_inset_m: field("region_inset_m", self.region_inset_m)?,
            // A perfect lattice is a sensible default; the spread is a refinement.
            height_spread: self.height_spread.unwrap_or(0.0),
            mass_ratio: self.mass_ratio,
            resonance_hz: self.resonance_hz,
            gyration_radius_m: self.gyration_radius_m,
            design: None,
        })
    }
}

impl From<&ResonatorSpec> for ResonatorFile {
    /// The file form: every key (zeros without rods, as the canonical form has always had them), or with a design,
    /// the design inline and the keys it does not give.
    fn from(r: &ResonatorSpec) -> Self {
        let own = |v: f64| r.design.is_none().then_some(v);
        Self {
            model: r.model,
            pitch_m: own(r.pitch_m),
            rod_height_m: own(r.rod_height_m),
            rod_diameter_m: own(r.rod_diameter_m),
            rod_youngs_modulus_pa: own(r.rod_youngs_modulus_pa),
            rod_density_kg_m3: own(r.rod_density_kg_m3),
            loss_factor: Some(r.loss_factor),
            region_inset_m: Some(r.region_inset_m),
            height_spread: Some(r.height_spread),
            mass_ratio: r.mass_ratio,
            resonance_hz: r.resonance_hz,
            gyration_radius_m: r.gyration_radius_m,
            design: r.design.clone().map(DesignEntry::Inline),
        }
    }
}

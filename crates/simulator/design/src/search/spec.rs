//! A search file: the base design, the parameters to vary and their values, the objectives, the band options.
//!
//! ```toml
//! base = "paper"                       # a built-in design or a design file (relative to this file)
//! [vary]
//! rod_height_m = { from = 0.020, to = 0.040, count = 5 }
//! rod_diameter_m = [0.002, 0.003175]
//! lattice_constant_m = [0.008]
//! plate_thickness_m = [0.0015]
//! rod_material = ["brass", "steel"]    # names from MATERIALS
//! plate_material = ["acrylic"]
//! [objectives]
//! max_phase_velocity_m_s = 10.0        # the first branch's phase velocity stays under this ...
//! over_hz = [75.0, 400.0]              # ... over this band, which the branch must reach
//! covers_hz = [75.0, 500.0]            # optional: a band the first branch must span
//! minimise = ["added_mass_kg_m2", "rod_height_m"]   # the trade-off front's axes
//! [band]                               # optional: the band diagram's resolution per design
//! wave_vectors = 31
//! ```

use std::path::Path;

use metaplate_core::toml_locate::{DocIndex, TomlFileError};
use serde::{Deserialize, Serialize};

use crate::band::BandOptions;
use crate::error::DesignError;
use crate::mesh::MeshOptions;
use metaplate_core::design::{CellPlate, CellResonator, Design};

/// The most designs one search may enumerate: a full grid of more is a mistake in the ranges (at a few seconds
/// each it would take weeks), refused before anything runs.
pub const MAX_DESIGNS: usize = 100_000;

/// A named material: Young's modulus, Pa; Poisson's ratio; density, kg/m^3 (handbook values; brass and acrylic
/// are the paper's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Material {
    /// Name used in search files.
    pub name: &'static str,
    /// Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
}

/// The materials a search file may name.
pub const MATERIALS: &[Material] = &[
    Material { name: "acrylic", youngs_modulus_pa: 3.2e9, poisson_ratio: 0.37, density_kg_m3: 1180.0 },
    Material { name: "polycarbonate", youngs_modulus_pa: 2.4e9, poisson_ratio: 0.37, density_kg_m3: 1200.0 },
    Material { name: "glass", youngs_modulus_pa: 70e9, poisson_ratio: 0.22, density_kg_m3: 2500.0 },
    Material { name: "brass", youngs_modulus_pa: 97e9, poisson_ratio: 0.31, density_kg_m3: 8489.0 },
    Material { name: "steel", youngs_modulus_pa: 200e9, poisson_ratio: 0.29, density_kg_m3: 7850.0 },
    Material { name: "aluminium", youngs_modulus_pa: 69e9, poisson_ratio: 0.33, density_kg_m3: 2700.0 },
    Material { name: "tungsten", youngs_modulus_pa: 411e9, poisson_ratio: 0.28, density_kg_m3: 19250.0 },
];

/// What the trade-off front minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Goal {
    /// The resonators' free mass per plate area, kg/m^2.
    AddedMassKgM2,
    /// The rod's whole height, m (the display's profile).
    RodHeightM,
    /// The first branch's highest phase velocity over the objective's band, m/s.
    MaxPhaseVelocityMS,
    /// Resonator over cell plate mass.
    MassRatio,
}

impl Goal {
    /// The column name of the goal in the results.
    pub fn column(self) -> &'static str {
        match self {
            Goal::AddedMassKgM2 => "added_mass_kg_m2",
            Goal::RodHeightM => "rod_height_m",
            Goal::MaxPhaseVelocityMS => "max_phase_velocity_m_s",
            Goal::MassRatio => "mass_ratio",
        }
    }
}

/// The objectives every design is judged by.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Objectives {
    /// The first branch's phase velocity must stay under this, m/s.
    pub max_phase_velocity_m_s: f64,
    /// ... over this band, Hz, which the first branch must reach (its top at least the upper edge).
    pub over_hz: [f64; 2],
    /// A band the first branch must span (its top at least the upper edge), Hz; none by default.
    #[serde(default)]
    pub covers_hz: Option<[f64; 2]>,
    /// The trade-off front's axes (at least one).
    pub minimise: Vec<Goal>,
}

/// One design of the grid: its index in the enumeration and the varied values.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Candidate {
    /// Position in the search's enumeration (0-based): shard `i/N` takes the indices equal to `i` modulo `N`.
    pub index: usize,
    /// Rod height, m.
    pub rod_height_m: f64,
    /// Rod diameter, m.
    pub rod_diameter_m: f64,
    /// Lattice constant, m.
    pub lattice_constant_m: f64,
    /// Plate thickness, m.
    pub plate_thickness_m: f64,
    /// Rod material's name.
    pub rod_material: String,
    /// Plate material's name.
    pub plate_material: String,
}

/// A parsed, validated search file.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchSpec {
    /// The design the varied parameters replace values of (a rod resonator).
    pub base: Design,
    /// Values per parameter, in the order of enumeration (the last varies fastest).
    pub rod_height_m: Vec<f64>,
    /// Rod diameters, m.
    pub rod_diameter_m: Vec<f64>,
    /// Lattice constants, m.
    pub lattice_constant_m: Vec<f64>,
    /// Plate thicknesses, m.
    pub plate_thickness_m: Vec<f64>,
    /// Rod materials.
    pub rod_material: Vec<Material>,
    /// Plate materials.
    pub plate_material: Vec<Material>,
    /// The objectives.
    pub objectives: Objectives,
    /// Resolution of each design's band diagram.
    pub band: BandOptions,
    /// The search's identity: a hash of everything that decides its results, recorded in every result so that
    /// parts of different searches are never merged.
    pub fingerprint: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SearchFile {
    base: String,
    #[serde(default)]
    vary: VaryFile,
    objectives: Objectives,
    #[serde(default)]
    band: BandFile,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct VaryFile {
    rod_height_m: Option<Values>,
    rod_diameter_m: Option<Values>,
    lattice_constant_m: Option<Values>,
    plate_thickness_m: Option<Values>,
    rod_material: Option<Vec<String>>,
    plate_material: Option<Vec<String>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Values {
    List(Vec<f64>),
    Range { from: f64, to: f64, count: usize },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BandFile {
    #[serde(default = "default_wave_vectors")]
    wave_vectors: usize,
    #[serde(default = "default_modes")]
    modes: usize,
    #[serde(default)]
    per_side: Option<usize>,
    #[serde(default)]
    radial: Option<usize>,
    #[serde(default)]
    rod_elements: Option<usize>,
}

impl Default for BandFile {
    fn default() -> Self {
        Self {
            wave_vectors: default_wave_vectors(),
            modes: default_modes(),
            per_side: None,
            radial: None,
            rod_elements: None,
        }
    }
}

/// A search judges the first branch only: 31 wave vectors (10 per leg of Gamma-X-M-Gamma) find its top and phase
/// velocity to within the branch's curvature between them; 2 modes keep its partner for a look.
fn default_wave_vectors() -> usize {
    31
}

fn default_modes() -> usize {
    2
}

impl SearchSpec {
    /// Reads and validates a search file; a relative `base` path is taken from the file's folder.
    ///
    /// # Errors
    /// [`DesignError::File`]: it cannot be read, or as [`SearchSpec::from_toml_str`].
    pub fn load(path: &Path) -> Result<Self, DesignError> {
        let text = TomlFileError::read(path)?;
        Self::from_toml_str(&text, &path.display().to_string(), path.parent())
    }

    /// Parses a search file's text; `origin` prefixes errors, `dir` resolves a relative `base` path.
    ///
    /// # Errors
    /// [`DesignError::File`] (not TOML, unknown or missing key, wrong type, value out of range, unknown material,
    /// too many designs), located by line and key; the base design's own errors.
    pub fn from_toml_str(text: &str, origin: &str, dir: Option<&Path>) -> Result<Self, DesignError> {
        let invalid_file = |l| DesignError::File(TomlFileError::Invalid(l));
        let doc = DocIndex::parse(text, origin).map_err(invalid_file)?;
        let file: SearchFile = toml::from_str(text).map_err(|e| invalid_file(doc.schema_error(&e)))?;
        let invalid = |key: &str, why: String| invalid_file(doc.invalid(key.to_owned(), why));
        let base = match Design::builtin(&file.base) {
            Some(d) => d,
            None => {
                let p = Path::new(&file.base);
                let p = if p.is_relative() { dir.map_or(p.to_path_buf(), |d| d.join(p)) } else { p.to_path_buf() };
                Design::load(&p)?
            }
        };
        let CellResonator::Rod(rod) = base.resonator else {
            return Err(invalid("base", "a search varies a rod resonator: the base design must have one".into()));
        };
        let values = |key: &str, v: Option<Values>, base: f64| -> Result<Vec<f64>, DesignError> {
            let out = match v {
                None => vec![base],
                Some(Values::List(list)) => list,
                Some(Values::Range { from, to, count }) => {
                    if count == 0 || count > MAX_DESIGNS || !(from.is_finite() && to.is_finite()) {
                        return Err(invalid(key, format!("a range needs finite ends and 1 to {MAX_DESIGNS} values")));
                    }
                    let step = if count == 1 { 0.0 } else { (to - from) / (count - 1) as f64 };
                    (0..count).map(|i| from + step * i as f64).collect()
                }
            };
            if out.is_empty() || out.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(invalid(key, "needs at least one value, each finite and positive (SI units)".into()));
            }
            Ok(out)
        };
        let materials = |key: &str, names: Option<Vec<String>>, base: Material| -> Result<Vec<Material>, DesignError> {
            let Some(names) = names else { return Ok(vec![base]) };
            if names.is_empty() {
                return Err(invalid(key, "needs at least one material".into()));
            }
            names
                .iter()
                .map(|n| {
                    MATERIALS.iter().find(|m| m.name == n).copied().ok_or_else(|| {
                        let known: Vec<&str> = MATERIALS.iter().map(|m| m.name).collect();
                        invalid(key, format!("unknown material `{n}`; known: {}", known.join(", ")))
                    })
                })
                .collect()
        };
        let o = &file.objectives;
        let band_ok = |b: [f64; 2]| b[0].is_finite() && b[1].is_finite() && 0.0 < b[0] && b[0] < b[1];
        if !(o.max_phase_velocity_m_s.is_finite() && o.max_phase_velocity_m_s > 0.0) {
            return Err(invalid("objectives.max_phase_velocity_m_s", "must be finite and positive".into()));
        }
        if !band_ok(o.over_hz) {
            return Err(invalid("objectives.over_hz", "needs [f_lo, f_hi] with 0 < f_lo < f_hi, Hz".into()));
        }
        if o.covers_hz.is_some_and(|b| !band_ok(b)) {
            return Err(invalid("objectives.covers_hz", "needs [f_lo, f_hi] with 0 < f_lo < f_hi, Hz".into()));
        }
        if o.minimise.is_empty() {
            return Err(invalid("objectives.minimise", "needs at least one goal".into()));
        }
        let defaults = MeshOptions::default();
        let b = &file.band;
        if b.wave_vectors < 4 || b.modes == 0 {
            return Err(invalid("band", "needs at least 4 wave vectors and 1 mode".into()));
        }
        let band = BandOptions {
            wave_vectors: b.wave_vectors,
            modes: b.modes,
            mesh: MeshOptions {
                per_side: b.per_side.unwrap_or(defaults.per_side),
                radial: b.radial.unwrap_or(defaults.radial),
                rod_elements: b.rod_elements.unwrap_or(defaults.rod_elements),
            },
            threads: 0,
        };
        let of = |p: &CellPlate| Material {
            name: "base",
            youngs_modulus_pa: p.youngs_modulus_pa,
            poisson_ratio: p.poisson_ratio,
            density_kg_m3: p.density_kg_m3,
        };
        let rod_base = Material {
            name: "base",
            youngs_modulus_pa: rod.youngs_modulus_pa,
            poisson_ratio: rod.poisson_ratio,
            density_kg_m3: rod.density_kg_m3,
        };
        let v = file.vary;
        let spec = Self {
            rod_height_m: values("vary.rod_height_m", v.rod_height_m, rod.height_m)?,
            rod_diameter_m: values("vary.rod_diameter_m", v.rod_diameter_m, rod.diameter_m)?,
            lattice_constant_m: values("vary.lattice_constant_m", v.lattice_constant_m, base.lattice_constant_m)?,
            plate_thickness_m: values("vary.plate_thickness_m", v.plate_thickness_m, base.plate.thickness_m)?,
            rod_material: materials("vary.rod_material", v.rod_material, rod_base)?,
            plate_material: materials("vary.plate_material", v.plate_material, of(&base.plate))?,
            objectives: file.objectives,
            band,
            fingerprint: String::new(),
            base,
        };
        let count = spec.count();
        if count > MAX_DESIGNS {
            return Err(invalid(
                "vary",
                format!("enumerates {count} designs, more than {MAX_DESIGNS}: narrow the ranges"),
            ));
        }
        Ok(Self { fingerprint: spec.compute_fingerprint(), ..spec })
    }

    /// Number of designs the grid enumerates.
    pub fn count(&self) -> usize {
        self.rod_height_m.len()
            * self.rod_diameter_m.len()
            * self.lattice_constant_m.len()
            * self.plate_thickness_m.len()
            * self.rod_material.len()
            * self.plate_material.len()
    }

    /// The `index`-th design of the grid (`None` past [`SearchSpec::count`]); the rod material varies slowest,
    /// then the plate material, the lattice constant, the plate thickness, the diameter, and the height fastest.
    pub fn candidate(&self, index: usize) -> Option<Candidate> {
        if index >= self.count() {
            return None;
        }
        let mut rest = index;
        let mut take = |n: usize| {
            let i = rest % n;
            rest /= n;
            i
        };
        let h = take(self.rod_height_m.len());
        let d = take(self.rod_diameter_m.len());
        let t = take(self.plate_thickness_m.len());
        let a = take(self.lattice_constant_m.len());
        let pm = take(self.plate_material.len());
        let rm = take(self.rod_material.len());
        Some(Candidate {
            index,
            rod_height_m: self.rod_height_m[h],
            rod_diameter_m: self.rod_diameter_m[d],
            lattice_constant_m: self.lattice_constant_m[a],
            plate_thickness_m: self.plate_thickness_m[t],
            rod_material: self.rod_material[rm].name.to_owned(),
            plate_material: self.plate_material[pm].name.to_owned(),
        })
    }

    /// The design of `candidate`: the base with the varied values put in (the embedded length kept, at most the
    /// plate's thickness).
    pub fn design(&self, candidate: &Candidate) -> Design {
        let mut design = self.base.clone();
        design.name = format!("{}#{}", self.base.name, candidate.index);
        design.lattice_constant_m = candidate.lattice_constant_m;
        design.plate.thickness_m = candidate.plate_thickness_m;
        if let Some(m) = self.plate_material.iter().find(|m| m.name == candidate.plate_material) {
            design.plate.youngs_modulus_pa = m.youngs_modulus_pa;
            design.plate.poisson_ratio = m.poisson_ratio;
            design.plate.density_kg_m3 = m.density_kg_m3;
        }
        if let CellResonator::Rod(rod) = &mut design.resonator {
            rod.height_m = candidate.rod_height_m;
            rod.diameter_m = candidate.rod_diameter_m;
            rod.embedded_m = rod.embedded_m.min(candidate.plate_thickness_m);
            if let Some(m) = self.rod_material.iter().find(|m| m.name == candidate.rod_material) {
                rod.youngs_modulus_pa = m.youngs_modulus_pa;
                rod.poisson_ratio = m.poisson_ratio;
                rod.density_kg_m3 = m.density_kg_m3;
            }
        }
        design
    }

    /// A hash of everything that decides the results (the base, the values, the objectives, the band options),
    /// as 16 hex digits (FNV-1a over the debug text: stable across runs and machines of one version).
    fn compute_fingerprint(&self) -> String {
        let text = format!(
            "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
            self.base,
            self.rod_height_m,
            self.rod_diameter_m,
            self.lattice_constant_m,
            self.plate_thickness_m,
            self.rod_material,
            self.plate_material,
            self.objectives,
            self.band
        );
        format!("{:016x}", metaplate_core::hash::fnv1a_64(text.bytes()))
    }
}

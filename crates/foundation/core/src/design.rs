//! A metamaterial unit cell's design: the plate, the resonator and the lattice; read from a TOML design file
//! (validated with file, line and key, as scene files are) or built in (`paper`). `metaplate-design` computes its
//! band structure; a scene's resonator lattice may name one.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::toml_locate::{DocIndex, TomlFileError};

/// An isotropic plate of uniform thickness (Mindlin theory: bending, transverse shear, rotary inertia).
///
/// Valid: `0 < thickness_m`, `1e5 <= youngs_modulus_pa <= 1e12`, `-1 < poisson_ratio < 0.5`,
/// `10 <= density_kg_m3 <= 1e5`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellPlate {
    /// Thickness h, m.
    pub thickness_m: f64,
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (dimensionless).
    pub poisson_ratio: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
}

impl CellPlate {
    /// Flexural rigidity D = E h^3 / (12 (1 - nu^2)), N m.
    pub fn flexural_rigidity_n_m(&self) -> f64 {
        self.youngs_modulus_pa * self.thickness_m.powi(3) / (12.0 * (1.0 - self.poisson_ratio.powi(2)))
    }

    /// Mass per area rho h, kg/m^2.
    pub fn areal_density_kg_m2(&self) -> f64 {
        self.density_kg_m3 * self.thickness_m
    }

    /// The analytic A0 (Kirchhoff) frequency at wavenumber `k_rad_m`: `f = sqrt(D / (rho h)) k^2 / (2 pi)`, Hz; the
    /// paper's formula `c^4 = omega^2 E h^2 / (12 (1 - nu^2) rho)` solved for omega.
    pub fn a0_freq_hz(&self, k_rad_m: f64) -> f64 {
        (self.flexural_rigidity_n_m() / self.areal_density_kg_m2()).sqrt() * k_rad_m * k_rad_m
            / (2.0 * std::f64::consts::PI)
    }

    /// The analytic A0 wavenumber at `freq_hz`, rad/m (the inverse of [`CellPlate::a0_freq_hz`]); its phase
    /// velocity is `2 pi f / k` and its wavelength `2 pi / k`.
    pub fn a0_wavenumber_rad_m(&self, freq_hz: f64) -> f64 {
        (2.0 * std::f64::consts::PI * freq_hz / (self.flexural_rigidity_n_m() / self.areal_density_kg_m2()).sqrt())
            .sqrt()
    }
}

/// Which face of the plate the rod stands on (the band structure does not depend on it: the two are mirror images;
/// it is kept so that a design file says where the rods are).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RodSide {
    /// Above the plate (+z).
    #[default]
    Top,
    /// Below the plate (-z).
    Bottom,
}

/// A cylindrical rod press-fit through the plate: the section inside the plate counts as plate (a rigid
/// footprint), the rest is a beam standing on the chosen face.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RodSpec {
    /// Whole rod length, embedded section included, m.
    pub height_m: f64,
    /// Diameter, m.
    pub diameter_m: f64,
    /// Length inside the plate (at most the plate's thickness), m.
    pub embedded_m: f64,
    /// Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (dimensionless).
    pub poisson_ratio: f64,
    /// Density, kg/m^3.
    pub density_kg_m3: f64,
    /// The face it stands on.
    pub side: RodSide,
}

impl RodSpec {
    /// The free length standing out of the plate, m.
    pub fn free_length_m(&self) -> f64 {
        self.height_m - self.embedded_m
    }

    /// Cross-section area, m^2.
    pub fn area_m2(&self) -> f64 {
        std::f64::consts::PI * self.diameter_m * self.diameter_m / 4.0
    }

    /// Mass of the free length (the resonator), kg.
    pub fn free_mass_kg(&self) -> f64 {
        self.density_kg_m3 * self.area_m2() * self.free_length_m()
    }

    /// First bending mode of the free length clamped at the plate's face, Hz (an upper bound on the rod in the
    /// cell: the plate is compliant).
    pub fn clamped_resonance_hz(&self) -> f64 {
        cantilever_first_mode_hz(self.diameter_m, self.youngs_modulus_pa, self.density_kg_m3, self.free_length_m())
    }
}

/// First bending mode of a solid round rod clamped at one end and free at the other (Euler-Bernoulli),
/// `(1.875^2 / 2 pi) (d / 4) sqrt(E / rho) / L^2`, Hz. Valid for slender rods (length well over the diameter);
/// finite and positive for finite, positive arguments.
pub fn cantilever_first_mode_hz(diameter_m: f64, youngs_modulus_pa: f64, density_kg_m3: f64, length_m: f64) -> f64 {
    // beta L of a clamped-free beam's first mode.
    let beta_l = 1.875_104_068_711_961_f64;
    beta_l * beta_l / (2.0 * std::f64::consts::PI) * (diameter_m / 4.0) * (youngs_modulus_pa / density_kg_m3).sqrt()
        / length_m.powi(2)
}

/// A point mass on a vertical spring attached to a small rigid footprint: the textbook local resonator (and the
/// validation case with a plane-wave-expansion answer).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpringMassSpec {
    /// The moving mass, kg.
    pub mass_kg: f64,
    /// Spring stiffness, N/m.
    pub stiffness_n_per_m: f64,
    /// Radius of the rigid footprint the spring acts on (plate material), m.
    pub footprint_radius_m: f64,
}

/// The resonator in each cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CellResonator {
    /// A homogeneous plate (the cell still has a tiny rigid footprint of plate material, 1/200 of the lattice
    /// constant in radius, so that every design shares one mesh topology).
    None,
    /// A rod standing on the plate.
    Rod(RodSpec),
    /// A spring-mass resonator.
    SpringMass(SpringMassSpec),
}

/// A square unit cell: lattice constant, plate, resonator.
///
/// Serialises as a design file's tables; deserialising (a design inline in a scene) validates as a file does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DesignFile")]
pub struct Design {
    /// Name (a built-in's, or the file's `name`, or empty).
    pub name: String,
    /// Lattice constant a (the cell's side), m.
    pub lattice_constant_m: f64,
    /// The host plate.
    pub plate: CellPlate,
    /// The resonator.
    pub resonator: CellResonator,
}

/// Names of the built-in designs.
pub const BUILTIN_DESIGNS: &[&str] = &["paper"];

/// The paper's acrylic plate (Supplementary Methods, "Metamaterial Design: Numerical Experiments").
pub const PAPER_PLATE: CellPlate =
    CellPlate { thickness_m: 1.5e-3, youngs_modulus_pa: 3.2e9, poisson_ratio: 0.37, density_kg_m3: 1180.0 };

impl Design {
    /// The paper's cell: 8 mm square of 1.5 mm acrylic with a brass rod of 33.4563 mm (1.5 mm of it press-fit in
    /// the plate), 3.175 mm in diameter.
    pub fn paper() -> Self {
        Self {
            name: "paper".into(),
            lattice_constant_m: 8e-3,
            plate: PAPER_PLATE,
            resonator: CellResonator::Rod(RodSpec {
                height_m: 33.4563e-3,
                diameter_m: 3.175e-3,
                embedded_m: 1.5e-3,
                youngs_modulus_pa: 97e9,
                poisson_ratio: 0.31,
                density_kg_m3: 8489.0,
                side: RodSide::Top,
            }),
        }
    }

    /// The same cell without its resonator.
    pub fn homogeneous(&self) -> Self {
        Self { name: format!("{} (homogeneous)", self.name), resonator: CellResonator::None, ..self.clone() }
    }

    /// Radius of the rigid footprint, m.
    pub fn footprint_radius_m(&self) -> f64 {
        match &self.resonator {
            CellResonator::None => self.lattice_constant_m / 200.0,
            CellResonator::Rod(rod) => rod.diameter_m / 2.0,
            CellResonator::SpringMass(s) => s.footprint_radius_m,
        }
    }

    /// The rigid footprint's mass, kg: the rod's embedded section and the plate material over the rest of the
    /// thickness (for a spring-mass resonator or none, plate material only).
    pub fn footprint_mass_kg(&self) -> f64 {
        let r = self.footprint_radius_m();
        let area = std::f64::consts::PI * r * r;
        let plate = &self.plate;
        match &self.resonator {
            CellResonator::Rod(rod) => {
                area * (rod.density_kg_m3 * rod.embedded_m + plate.density_kg_m3 * (plate.thickness_m - rod.embedded_m))
            }
            _ => area * plate.areal_density_kg_m2(),
        }
    }

    /// Resonator mass over the cell's plate mass (the footprint counted as plate, with its own density): the
    /// paper's `m_ratio` (10.7 for its cell).
    pub fn mass_ratio(&self) -> f64 {
        let a = self.lattice_constant_m;
        let r = self.footprint_radius_m();
        let footprint_m2 = std::f64::consts::PI * r * r;
        let plate_kg = |footprint_kg: f64| (a * a - footprint_m2) * self.plate.areal_density_kg_m2() + footprint_kg;
        match &self.resonator {
            CellResonator::None => 0.0,
            CellResonator::SpringMass(s) => s.mass_kg / plate_kg(footprint_m2 * self.plate.areal_density_kg_m2()),
            CellResonator::Rod(rod) => rod.free_mass_kg() / plate_kg(self.footprint_mass_kg()),
        }
    }

    /// The whole cell's mass, kg: the plate around the footprint, the footprint, and the resonator's moving mass.
    pub fn cell_mass_kg(&self) -> f64 {
        let a = self.lattice_constant_m;
        let r = self.footprint_radius_m();
        let around = (a * a - std::f64::consts::PI * r * r) * self.plate.areal_density_kg_m2();
        let resonator = match &self.resonator {
            CellResonator::None => 0.0,
            CellResonator::Rod(rod) => rod.free_mass_kg(),
            CellResonator::SpringMass(s) => s.mass_kg,
        };
        around + self.footprint_mass_kg() + resonator
    }

    /// A built-in design by name ([`BUILTIN_DESIGNS`]).
    pub fn builtin(name: &str) -> Option<Self> {
        (name == "paper").then(Self::paper)
    }

    /// A built-in name, or else a design file's path.
    ///
    /// # Errors
    /// As [`Design::load`].
    pub fn resolve(name_or_path: &str) -> Result<Self, TomlFileError> {
        match Self::builtin(name_or_path) {
            Some(design) => Ok(design),
            None => Self::load(Path::new(name_or_path)),
        }
    }

    /// Reads and validates a design file.
    ///
    /// # Errors
    /// [`TomlFileError::Io`] when it cannot be read; otherwise as [`Design::from_toml_str`].
    pub fn load(path: &Path) -> Result<Self, TomlFileError> {
        let text = TomlFileError::read(path)?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and validates a design from TOML text; `origin` (a path) prefixes every error.
    ///
    /// # Errors
    /// [`TomlFileError::Invalid`] (not TOML, unknown or missing key, wrong type, value out of range), located by line
    /// and key path.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self, TomlFileError> {
        let doc = DocIndex::parse(text, origin).map_err(TomlFileError::Invalid)?;
        let file: DesignFile = toml::from_str(text).map_err(|e| TomlFileError::Invalid(doc.schema_error(&e)))?;
        file.into_design().map_err(|(key, why)| TomlFileError::Invalid(doc.invalid(key, why)))
    }

    /// Checks the ranges; the error is `(key path, reason)`.
    ///
    /// # Errors
    /// The first value out of its range.
    pub fn check(&self) -> Result<(), (String, String)> {
        let p = &self.plate;
        within("lattice_constant_m", self.lattice_constant_m, 1e-4, 1.0)?;
        within("plate.thickness_m", p.thickness_m, 1e-5, 0.1)?;
        within("plate.youngs_modulus_pa", p.youngs_modulus_pa, 1e5, 1e12)?;
        within("plate.poisson_ratio", p.poisson_ratio, -0.99, 0.49)?;
        within("plate.density_kg_m3", p.density_kg_m3, 10.0, 1e5)?;
        if p.thickness_m > self.lattice_constant_m {
            return Err(("plate.thickness_m".into(), "is larger than the lattice constant".into()));
        }
        match &self.resonator {
            CellResonator::None => {}
            CellResonator::Rod(rod) => {
                within("resonator.height_m", rod.height_m, 1e-4, 1.0)?;
                within("resonator.diameter_m", rod.diameter_m, 1e-5, 0.8 * self.lattice_constant_m)?;
                within("resonator.embedded_m", rod.embedded_m, 0.0, p.thickness_m)?;
                within("resonator.youngs_modulus_pa", rod.youngs_modulus_pa, 1e5, 1e12)?;
                within("resonator.poisson_ratio", rod.poisson_ratio, -0.99, 0.49)?;
                within("resonator.density_kg_m3", rod.density_kg_m3, 10.0, 1e5)?;
                if rod.free_length_m() <= rod.diameter_m / 10.0 {
                    return Err(("resonator.height_m".into(), "leaves (almost) no rod above the plate".into()));
                }
            }
            CellResonator::SpringMass(s) => {
                within("resonator.mass_kg", s.mass_kg, 1e-9, 1e3)?;
                within("resonator.stiffness_n_per_m", s.stiffness_n_per_m, 1e-3, 1e12)?;
                within("resonator.footprint_radius_m", s.footprint_radius_m, 1e-6, 0.4 * self.lattice_constant_m)?;
            }
        }
        Ok(())
    }
}

fn within(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), (String, String)> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err((key.into(), format!("{v} is outside [{lo}, {hi}] (SI units: the key's suffix names its unit)")))
    }
}

/// The file's shape: the resonator's keys are all optional here, so that a missing or misplaced one is reported by
/// its key path.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    #[serde(default)]
    name: String,
    lattice_constant_m: f64,
    plate: CellPlate,
    resonator: ResonatorFile,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum ResonatorKind {
    None,
    Rod,
    SpringMass,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ResonatorFile {
    kind: ResonatorKind,
    height_m: Option<f64>,
    diameter_m: Option<f64>,
    embedded_m: Option<f64>,
    youngs_modulus_pa: Option<f64>,
    poisson_ratio: Option<f64>,
    density_kg_m3: Option<f64>,
    side: Option<RodSide>,
    mass_kg: Option<f64>,
    stiffness_n_per_m: Option<f64>,
    footprint_radius_m: Option<f64>,
}

impl TryFrom<DesignFile> for Design {
    type Error = String;

    fn try_from(file: DesignFile) -> Result<Self, String> {
        file.into_design().map_err(|(key, why)| format!("{key}: {why}"))
    }
}

impl DesignFile {
    fn into_design(self) -> Result<Design, (String, String)> {
        let r = &self.resonator;
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| ("resonator".to_owned(), format!("missing key `{key}` (needed by this kind)")))
        };
        let stray = |keys: &[(&str, bool)]| match keys.iter().find(|(_, present)| *present) {
            Some((key, _)) => Err((format!("resonator.{key}"), "is not a key of this resonator kind".to_owned())),
            None => Ok(()),
        };
        let rod_keys = [
            ("height_m", r.height_m.is_some()),
            ("diameter_m", r.diameter_m.is_some()),
            ("embedded_m", r.embedded_m.is_some()),
            ("youngs_modulus_pa", r.youngs_modulus_pa.is_some()),
            ("poisson_ratio", r.poisson_ratio.is_some()),
            ("density_kg_m3", r.density_kg_m3.is_some()),
            ("side", r.side.is_some()),
        ];
        let spring_keys = [
            ("mass_kg", r.mass_kg.is_some()),
            ("stiffness_n_per_m", r.stiffness_n_per_m.is_some()),
            ("footprint_radius_m", r.footprint_radius_m.is_some()),
        ];
        let resonator = match r.kind {
            ResonatorKind::None => {
                stray(&rod_keys)?;
                stray(&spring_keys)?;
                CellResonator::None
            }
            ResonatorKind::Rod => {
                stray(&spring_keys)?;
                CellResonator::Rod(RodSpec {
                    height_m: need("height_m", r.height_m)?,
                    diameter_m: need("diameter_m", r.diameter_m)?,
                    // A rod glued on the face rather than through the plate embeds nothing.
                    embedded_m: r.embedded_m.unwrap_or(self.plate.thickness_m),
                    youngs_modulus_pa: need("youngs_modulus_pa", r.youngs_modulus_pa)?,
                    poisson_ratio: need("poisson_ratio", r.poisson_ratio)?,
                    density_kg_m3: need("density_kg_m3", r.density_kg_m3)?,
                    side: r.side.unwrap_or_default(),
                })
            }
            ResonatorKind::SpringMass => {
                stray(&rod_keys)?;
                CellResonator::SpringMass(SpringMassSpec {
                    mass_kg: need("mass_kg", r.mass_kg)?,
                    stiffness_n_per_m: need("stiffness_n_per_m", r.stiffness_n_per_m)?,
                    footprint_radius_m: need("footprint_radius_m", r.footprint_radius_m)?,
                })
            }
        };
        let design =
            Design { name: self.name, lattice_constant_m: self.lattice_constant_m, plate: self.plate, resonator };
        design.check()?;
        Ok(design)
    }
}

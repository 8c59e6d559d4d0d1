//! Wavelengths at one frequency from a propagation response: each actuator's field assembled on the grid, measured
//! by the k-space estimator (the paper's method) and by the plate-equation estimator, and combined across actuators.
//!
//! This is what `metaplate simulate dispersion` and the plate's tests do at each frequency; the analysis crate takes
//! plain slices, so it does not depend on the plate model that produced them.

use metaplate_core::grid::GridSpec;
use metaplate_core::scene::Scene;
use num_complex::Complex64;

use crate::error::AnalysisError;
use crate::lattice::Lattice;
use crate::wavelength::stats::weighted_quantiles;
use crate::wavelength::{
    AcrossActuators, Exclusion, KSpaceOptions, LocalEstimate, LocalOptions, WavelengthEstimate, WavelengthSummary,
    estimate_local_wavelength, estimate_wavelength, summarise,
};

/// Where the response's values live on the grid, and which points each estimator may use. Fixed for a session:
/// build it once, use it at every frequency ([`SceneLayout`] builds one for a scene).
#[derive(Debug, Clone, Copy)]
pub struct FieldLayout<'a> {
    /// The measurement grid.
    pub grid: &'a GridSpec,
    /// Flat grid index of each response row (`response[k * actuators + a]` lies at `points[k]`).
    pub points: &'a [usize],
    /// Per grid point: measured; what the k-space estimator uses. Points not listed in `points` are zero in the
    /// assembled field, so they should be unmeasured here.
    pub mask: &'a [bool],
    /// Per grid point: usable by the plate-equation estimator (normally `mask` less the points on or next to the
    /// plate's edge, see [`SceneLayout`]).
    pub local_mask: &'a [bool],
    /// Discs where the plate equation does not hold (actuators, supports), m, in the grid's frame.
    pub exclusions: &'a [Exclusion],
}

/// Radius (m) kept clear around each actuator by the plate-equation estimator: 2 cm, four grid steps at 5 mm.
///
/// Why: a point force makes the field's fourth derivatives singular at the source (the plate's Green's function
/// goes as `r^2 log r` there), which the 13-point stencil cannot follow. On the simulated homogeneous plate
/// (75 to 600 Hz) the per-actuator residual falls from 0.9 with no exclusion to below 0.06 at 1 cm and 0.035 at
/// 2 cm, and the median wavelength moves by less than 0.1 % between 1, 2 and 3 cm: 2 cm is inside that plateau
/// while keeping about 440 of the 725 interior points.
pub const ACTUATOR_EXCLUSION_M: f64 = 0.02;

/// Points closer than this many grid steps to the plate's edge are not used by the plate-equation estimator.
///
/// Why: the plate model's edge is a staircase of lattice cells whose boundary rows obey the free-edge conditions,
/// not the plate equation, and a grid point on the outline takes the value of the nearest lattice node, which may
/// lie a lattice step away. On the built-in scenes two stencils reach such points, and they alone raise the residual
/// from 0.035 to 0.25; any margin from 0.1 to 1 step removes them (0.5: half a step).
pub const EDGE_MARGIN_STEPS: f64 = 0.5;

/// A scene's measurement layout, owned: points, masks and exclusions as [`wavelengths_at`] needs them.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneLayout {
    /// The scene's grid.
    pub grid: GridSpec,
    /// The measurable grid points ([`Scene::measured_points`]), the rows a response should have.
    pub points: Vec<usize>,
    /// [`Scene::grid_mask`].
    pub mask: Vec<bool>,
    /// `mask` less the points within [`EDGE_MARGIN_STEPS`] grid steps of the plate's edge.
    pub local_mask: Vec<bool>,
    /// Every actuator (radius [`ACTUATOR_EXCLUSION_M`]) and every support pad (radius: its half-diagonal, the
    /// circle around the square pad whose springs act on every node under it).
    pub exclusions: Vec<Exclusion>,
}

impl SceneLayout {
    /// The layout of `scene`'s grid, actuators, supports and outline. Works on any scene; a scene that fails
    /// validation gives a layout the estimators will refuse with a typed error.
    pub fn new(scene: &Scene) -> Self {
        let grid = scene.grid;
        let mask = scene.grid_mask();
        let margin_m = EDGE_MARGIN_STEPS * grid.spacing_m;
        let local_mask = mask
            .iter()
            .enumerate()
            .map(|(i, &m)| {
                let (x, y) = grid.position_m(i);
                m && scene.plate.outline.distance_inside_m(x, y) >= margin_m
            })
            .collect();
        let actuators =
            scene.actuators.iter().map(|a| Exclusion { x_m: a.x_m, y_m: a.y_m, radius_m: ACTUATOR_EXCLUSION_M });
        let supports = scene.supports.iter().map(|s| Exclusion {
            x_m: s.x_m,
            y_m: s.y_m,
            radius_m: s.size_m / std::f64::consts::SQRT_2,
        });
        Self {
            grid,
            points: scene.measured_points(),
            mask,
            local_mask,
            exclusions: actuators.chain(supports).collect(),
        }
    }

    /// Borrows the layout for [`wavelengths_at`].
    pub fn layout(&self) -> FieldLayout<'_> {
        FieldLayout {
            grid: &self.grid,
            points: &self.points,
            mask: &self.mask,
            local_mask: &self.local_mask,
            exclusions: &self.exclusions,
        }
    }
}

/// Options of [`wavelengths_at`]: one per estimator, and how actuators are combined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DispersionOptions {
    /// The k-space estimator's options (default: the paper's method).
    pub k_space: KSpaceOptions,
    /// The plate-equation estimator's options.
    pub local: LocalOptions,
    /// How per-actuator estimates are combined (both estimators).
    pub across: AcrossActuators,
}

impl Default for DispersionOptions {
    fn default() -> Self {
        Self { k_space: KSpaceOptions::default(), local: LocalOptions::default(), across: AcrossActuators::Median }
    }
}

/// Plate-equation wavelengths combined across the actuators whose estimate succeeded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalSummary {
    /// Combined wavelength (m): the median or the mean of the per-actuator wavelengths, as asked.
    pub wavelength_m: f64,
    /// Smallest and largest per-actuator wavelength (m).
    pub range_m: (f64, f64),
    /// Largest per-actuator residual (see [`LocalEstimate::residual`]).
    pub max_residual: f64,
    /// Estimates combined.
    pub actuators: usize,
    /// How many of them carried a range flag; they are included all the same.
    pub flagged: usize,
}

/// Wavelengths at one frequency, per actuator and combined.
#[derive(Debug, Clone, PartialEq)]
pub struct FrequencyWavelengths {
    /// The k-space (paper's method) estimate of each actuator's field.
    pub k_space: Vec<WavelengthEstimate>,
    /// Their combination across actuators.
    pub k_space_summary: WavelengthSummary,
    /// The plate-equation estimate of each actuator's field, or why that field gave none (for instance
    /// [`AnalysisError::NotAPlateWave`] in a band gap).
    pub local: Vec<Result<LocalEstimate, AnalysisError>>,
    /// Their combination across the actuators that gave one; `None` when none did.
    pub local_summary: Option<LocalSummary>,
}

/// The field of actuator `actuator` on the full grid: `response[k * actuators + actuator]` at `points[k]`, zero
/// elsewhere.
///
/// # Errors
/// [`AnalysisError::LengthMismatch`] when `response` is not `points.len() * actuators` long;
/// [`AnalysisError::InvalidParameter`] when `actuator >= actuators` or a point lies beyond `grid_len`.
pub fn actuator_field(
    response: &[Complex64],
    actuators: usize,
    actuator: usize,
    points: &[usize],
    grid_len: usize,
) -> Result<Vec<Complex64>, AnalysisError> {
    check_response(response, actuators, points, grid_len)?;
    if actuator >= actuators {
        return Err(AnalysisError::InvalidParameter {
            name: "actuator",
            reason: format!("{actuator} is not below the {actuators} actuator(s) of the response"),
        });
    }
    let mut field = vec![Complex64::ZERO; grid_len];
    for (k, &p) in points.iter().enumerate() {
        field[p] = response[k * actuators + actuator];
    }
    Ok(field)
}

/// Measures every actuator's field at one frequency with both estimators and combines them across actuators.
///
/// `response`: `layout.points.len() * actuators` values, point-major (`[k * actuators + a]`), as
/// `metaplate_plate::PlateModel::frequency_response` returns them; any unit. Valid range: as the two estimators'
/// (see [`crate::wavelength`] and [`crate::wavelength::local`]); a plate-equation failure for one actuator is
/// reported in [`FrequencyWavelengths::local`], not as an error.
///
/// # Errors
/// - [`AnalysisError::InvalidParameter`]: `actuators` is 0, a point lies off the grid, or an estimator refuses its
///   options or the grid;
/// - [`AnalysisError::LengthMismatch`]: `response`, `layout.mask` or `layout.local_mask` against the grid;
/// - any error of [`estimate_wavelength`] for an actuator's field (a NaN in the response, an all-zero field), and
///   of [`summarise`].
pub fn wavelengths_at(
    response: &[Complex64],
    actuators: usize,
    layout: &FieldLayout<'_>,
    opts: &DispersionOptions,
) -> Result<FrequencyWavelengths, AnalysisError> {
    let grid = layout.grid;
    check_response(response, actuators, layout.points, grid.len())?;
    if layout.local_mask.len() != grid.len() {
        return Err(AnalysisError::LengthMismatch {
            what: "local mask against grid points",
            a: layout.local_mask.len(),
            b: grid.len(),
        });
    }
    // The k-space estimate on the points' own lattice (a regular subset's holes would put spectral images of the
    // field at high wavenumbers; see `crate::lattice`); the grid itself for a full scan.
    let as_u32: Vec<u32> = layout.points.iter().map(|&p| p as u32).collect();
    // No points: the full-grid path, which reports too few points.
    let lattice = Lattice::of_points(grid, &as_u32).unwrap_or(Lattice { grid: *grid, indices: as_u32, stride: 1 });
    let on = &lattice.grid;
    let lattice_points: Vec<usize> = lattice.indices.iter().map(|&i| i as usize).collect();
    let mut lattice_mask = vec![false; if lattice.stride == 1 { 0 } else { on.len() }];
    if lattice.stride > 1 {
        for (&p, &i) in layout.points.iter().zip(&lattice_points) {
            lattice_mask[i] = layout.mask.get(p).copied().unwrap_or(false);
        }
    }
    let mut k_space = Vec::with_capacity(actuators);
    let mut local = Vec::with_capacity(actuators);
    for a in 0..actuators {
        let field = actuator_field(response, actuators, a, layout.points, grid.len())?;
        let k_field = if lattice.stride == 1 {
            None
        } else {
            Some(actuator_field(response, actuators, a, &lattice_points, on.len())?)
        };
        k_space.push(match &k_field {
            None => estimate_wavelength(&field, layout.mask, grid.nx, grid.ny, grid.spacing_m, &opts.k_space)?,
            Some(f) => estimate_wavelength(f, &lattice_mask, on.nx, on.ny, on.spacing_m, &opts.k_space)?,
        });
        local.push(estimate_local_wavelength(&field, layout.local_mask, grid, layout.exclusions, &opts.local));
    }
    let k_space_summary = summarise(&k_space, opts.across)?;
    let successes: Vec<&LocalEstimate> = local.iter().filter_map(|r| r.as_ref().ok()).collect();
    Ok(FrequencyWavelengths {
        k_space,
        k_space_summary,
        local_summary: summarise_local(&successes, opts.across),
        local,
    })
}

/// Combines successful plate-equation estimates; `None` for none.
fn summarise_local(estimates: &[&LocalEstimate], how: AcrossActuators) -> Option<LocalSummary> {
    let wavelengths: Vec<f64> = estimates.iter().map(|e| e.wavelength_m).collect();
    let wavelength_m = match how {
        AcrossActuators::Mean if !wavelengths.is_empty() => wavelengths.iter().sum::<f64>() / wavelengths.len() as f64,
        AcrossActuators::Mean => return None,
        AcrossActuators::Median => weighted_quantiles(&wavelengths, &vec![1.0; wavelengths.len()], &[0.5])?[0],
    };
    Some(LocalSummary {
        wavelength_m,
        range_m: (
            wavelengths.iter().copied().fold(f64::INFINITY, f64::min),
            wavelengths.iter().copied().fold(0.0, f64::max),
        ),
        max_residual: estimates.iter().map(|e| e.residual).fold(0.0, f64::max),
        actuators: estimates.len(),
        flagged: estimates.iter().filter(|e| !e.flags.in_range()).count(),
    })
}

fn check_response(
    response: &[Complex64],
    actuators: usize,
    points: &[usize],
    grid_len: usize,
) -> Result<(), AnalysisError> {
    if actuators == 0 {
        return Err(AnalysisError::InvalidParameter { name: "actuators", reason: "must be >= 1".to_owned() });
    }
    let expected = points.len().saturating_mul(actuators);
    if response.len() != expected {
        return Err(AnalysisError::LengthMismatch {
            what: "response against points x actuators",
            a: response.len(),
            b: expected,
        });
    }
    if let Some(&p) = points.iter().find(|&&p| p >= grid_len) {
        return Err(AnalysisError::InvalidParameter {
            name: "points",
            reason: format!("grid index {p} is beyond the grid's {grid_len} points"),
        });
    }
    Ok(())
}

//! Every analysis of the paper's Wave Field Analysis on one plate, from its propagation matrices: what
//! `metaplate analyze` prints (pixel area aside, which the `pixel` module computes).

use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSpec;
use num_complex::Complex64;

use crate::authority::{AuthorityOptions, DomainAuthority, PAPER_DOMAIN_EDGES_M, domain_authority};
use crate::bands::OPERATING_BAND_HZ;
use crate::dispersion::actuator_field;
use crate::error::AnalysisError;
use crate::lattice::{Lattice, ResolvableRange};
use crate::pod::{Pod, PodOptions, pod};
use crate::refresh::{Refresh, RefreshOptions, refresh};
use crate::response::{DrivenResponse, driven_response};
use crate::wavelength::{AcrossActuators, KSpaceOptions, WavelengthSummary, estimate_wavelength, summarise};

/// Options of [`analyse`]; the defaults are the paper's.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportOptions {
    /// Frequencies at which the wavelength is estimated, Hz (default 75 to 600 Hz every 25 Hz, the paper's
    /// Fig. 2A range); each uses the nearest bin of `g`, and one outside `g`'s bins is skipped.
    pub wavelength_freqs_hz: Vec<f64>,
    /// POD options.
    pub pod: PodOptions,
    /// Square-domain edges for the authority, m (default 9.5, 6.5, 3.5 cm).
    pub domain_edges_m: Vec<f64>,
    /// Authority options.
    pub authority: AuthorityOptions,
    /// Refresh options.
    pub refresh: RefreshOptions,
    /// Band of the driven response, Hz (default: the operating band).
    pub response_band_hz: (f64, f64),
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            wavelength_freqs_hz: (0..=21).map(|i| 75.0 + 25.0 * i as f64).collect(),
            pod: PodOptions::default(),
            domain_edges_m: PAPER_DOMAIN_EDGES_M.to_vec(),
            authority: AuthorityOptions::default(),
            refresh: RefreshOptions::default(),
            response_band_hz: OPERATING_BAND_HZ,
        }
    }
}

/// The k-space wavelength at one frequency.
#[derive(Debug, Clone, PartialEq)]
pub struct WavelengthAt {
    /// The bin's frequency, Hz (the nearest to the one asked).
    pub freq_hz: f64,
    /// The paper's summary: per-actuator median and quartiles, averaged over actuators; or why none.
    pub summary: Result<WavelengthSummary, AnalysisError>,
    /// Whether the summary can be trusted: its median lies in the lattice's [`ResolvableRange`] (which asks for
    /// a lattice filled well enough) and no actuator's estimate carried a range flag. `false` when there is none.
    pub in_range: bool,
}

/// Everything [`analyse`] measured. An analysis that could not run on this dataset (too few points in a domain, no
/// pixel resolving two pulses in the search) holds its error, so the others are still reported.
#[derive(Debug, Clone, PartialEq)]
pub struct PlateReport {
    /// The lattice the measured points lie on (every s-th point of the grid for a regular subset): the
    /// wavelength, the pixel area and the authority domains are all measured on it.
    pub lattice: Lattice,
    /// What a k-space estimate on that lattice can resolve.
    pub resolvable: ResolvableRange,
    /// Wavelength against frequency.
    pub wavelength: Vec<WavelengthAt>,
    /// POD of the actuator-summed response.
    pub pod: Result<Pod, AnalysisError>,
    /// Authority per domain edge, in the order of [`ReportOptions::domain_edges_m`].
    pub authority: Vec<(f64, Result<DomainAuthority, AnalysisError>)>,
    /// Temporal refresh.
    pub refresh: Result<Refresh, AnalysisError>,
    /// Driven response against frequency.
    pub driven_response: Result<DrivenResponse, AnalysisError>,
}

/// Runs every analysis on `g`, whose points lie on `grid`. Valid range: as each analysis's; `g` should cover the
/// refresh pulse's skirts (50 to 425 Hz by default) and the wavelength frequencies.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] when a point of `g` lies off `grid`; [`AnalysisError::Empty`] when `g` has
/// no points. Each analysis's own errors are kept in the report.
pub fn analyse(g: &PropagationMatrices, grid: &GridSpec, opts: &ReportOptions) -> Result<PlateReport, AnalysisError> {
    let lattice = lattice_of(g, grid)?;
    let resolvable = lattice.resolvable();
    let wavelength = opts.wavelength_freqs_hz.iter().filter_map(|&f| wavelength_at(g, grid, f, &resolvable)).collect();
    Ok(PlateReport {
        lattice,
        resolvable,
        wavelength,
        pod: pod(g, &opts.pod),
        authority: opts.domain_edges_m.iter().map(|&d| (d, domain_authority(g, grid, d, &opts.authority))).collect(),
        refresh: refresh(g, &opts.refresh),
        driven_response: driven_response(g, opts.response_band_hz),
    })
}

/// The k-space wavelength at `g`'s bin nearest `freq_hz`, judged against `resolvable` (the range of `g`'s lattice,
/// [`lattice_of`]); `None` when `freq_hz` lies more than half a bin outside `g`'s bins.
pub fn wavelength_at(
    g: &PropagationMatrices,
    grid: &GridSpec,
    freq_hz: f64,
    resolvable: &ResolvableRange,
) -> Option<WavelengthAt> {
    let k = nearest_bin(g, freq_hz)?;
    let summary = wavelength_at_bin(g, grid, k);
    let in_range = summary.as_ref().is_ok_and(|s| s.flagged == 0 && resolvable.contains(s.median_m));
    Some(WavelengthAt { freq_hz: g.freqs_hz()[k], summary, in_range })
}

/// Position of `g`'s bin nearest `freq_hz`, or `None` when `freq_hz` lies more than half a bin outside them.
fn nearest_bin(g: &PropagationMatrices, freq_hz: f64) -> Option<usize> {
    let spacing_hz = g.sample_rate_hz() / g.fft_len() as f64;
    let (k, f) =
        g.freqs_hz().iter().enumerate().min_by(|a, b| (a.1 - freq_hz).abs().total_cmp(&(b.1 - freq_hz).abs()))?;
    ((f - freq_hz).abs() <= spacing_hz / 2.0).then_some(k)
}

/// The lattice of `g`'s points on `grid` ([`Lattice::of_points`]).
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] when a point lies off `grid`; [`AnalysisError::Empty`] for no points.
pub fn lattice_of(g: &PropagationMatrices, grid: &GridSpec) -> Result<Lattice, AnalysisError> {
    if let Some(&p) = g.points().iter().find(|&&p| p as usize >= grid.len()) {
        return Err(AnalysisError::InvalidParameter {
            name: "points",
            reason: format!("grid index {p} is beyond the grid's {} points", grid.len()),
        });
    }
    Lattice::of_points(grid, g.points()).ok_or(AnalysisError::Empty { input: "measured points" })
}

/// The paper's k-space wavelength at bin `k`: each actuator's field over the measured points, averaged over
/// actuators ("the mean of these statistics across actuators"); an actuator whose field is zero (a dead coil) is
/// left out, and the summary's `actuators` says how many were averaged. The fields are laid on the points' own lattice
/// ([`Lattice::of_points`]): on the full grid, a subset's unmeasured points between would put spectral images of
/// the field at high wavenumbers, where the peak search finds them.
///
/// # Errors
/// As [`lattice_of`], [`estimate_wavelength`] and [`summarise`]; [`AnalysisError::NoEnergy`] when every actuator's
/// field is zero.
pub fn wavelength_at_bin(
    g: &PropagationMatrices,
    grid: &GridSpec,
    k: usize,
) -> Result<WavelengthSummary, AnalysisError> {
    let gk = g.at_bin(k).ok_or(AnalysisError::InvalidParameter {
        name: "k",
        reason: format!("bin {k} is not below the {} bins", g.n_bins()),
    })?;
    let (m, n) = (g.n_points(), g.n_actuators());
    let response: Vec<Complex64> = (0..m * n).map(|i| gk[(i / n, i % n)]).collect();
    let lattice = lattice_of(g, grid)?;
    let on = &lattice.grid;
    let points: Vec<usize> = lattice.indices.iter().map(|&p| p as usize).collect();
    let mask = lattice.mask();
    let mut estimates = Vec::with_capacity(n);
    for a in 0..n {
        let field = actuator_field(&response, n, a, &points, on.len())?;
        match estimate_wavelength(&field, &mask, on.nx, on.ny, on.spacing_m, &KSpaceOptions::default()) {
            Ok(estimate) => estimates.push(estimate),
            // A dead actuator (an all-zero column: a broken coil) has no wave to measure: left out of the mean,
            // which [`WavelengthSummary::actuators`] counts.
            Err(AnalysisError::NoEnergy { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    if estimates.is_empty() {
        return Err(AnalysisError::NoEnergy { what: "wavelength estimate: every actuator's field is zero" });
    }
    summarise(&estimates, AcrossActuators::Mean)
}

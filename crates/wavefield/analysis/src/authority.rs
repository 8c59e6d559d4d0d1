//! Input-output authority of the actuator array over small square domains (paper, Fig. 6B and C): the singular
//! values of the propagation matrix restricted to a domain, `G_D(omega)` (`M_D` points x 8 actuators), per frequency.
//!
//! Definitions (paper, Wave Field Analysis):
//! - relative singular-value energy `10 log10(sigma_i^2 / sigma_1^2)`, dB;
//! - effective rank: the number of singular values whose energy lies within 30 dB of the largest, i.e.
//!   `sigma_i^2 >= sigma_1^2 * 10^(-30/10)`, equivalently `sigma_i >= sigma_1 * 10^(-30/20)`. The paper puts the
//!   -30 dB on the singular-value *energy* (`sigma^2`), which is what is done here;
//! - condition number `kappa = sigma_1 / sigma_N` with all `N` singular values (`N` = 8 actuators);
//! - both averaged over the bins of the operating band (75 to 400 Hz).
//!
//! The paper's domains are squares of edge 9.5, 6.5 and 3.5 cm holding 361, 169 and 49 points of the 5 mm grid: a
//! square of edge `d` centred on a grid point holds the points within `d / 2` of its centre along x and y.

use faer::Mat;
use metaplate_control::PropagationMatrices;
use metaplate_core::grid::GridSpec;

use crate::bands::{OPERATING_BAND_HZ, bins_in_band};
use crate::error::AnalysisError;
use crate::linalg::singular_values_complex;

/// The paper's domain edges, m: 9.5, 6.5 and 3.5 cm.
pub const PAPER_DOMAIN_EDGES_M: [f64; 3] = [0.095, 0.065, 0.035];

/// Relative energies below this (dB) are reported at this floor, so that a zero singular value gives a finite
/// number: -300 dB lies far below any float-rounding floor of a measured matrix (about -310 dB for f64).
pub const ENERGY_FLOOR_DB: f64 = -300.0;

/// Options of [`domain_authority`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AuthorityOptions {
    /// Band whose bins are analysed and averaged, Hz (default: 75 to 400 Hz).
    pub band_hz: (f64, f64),
    /// Effective-rank threshold on the relative singular-value energy, dB (default -30, the paper's). Valid:
    /// finite, <= 0.
    pub threshold_db: f64,
    /// Centre of the domain, m, in the grid's frame (default (0, 0): the plate's centre).
    pub centre_m: (f64, f64),
}

impl Default for AuthorityOptions {
    fn default() -> Self {
        Self { band_hz: OPERATING_BAND_HZ, threshold_db: -30.0, centre_m: (0.0, 0.0) }
    }
}

/// Singular-value authority of `G_D` over one square domain, per frequency and band-averaged.
#[derive(Debug, Clone, PartialEq)]
pub struct DomainAuthority {
    /// Edge of the square, m.
    pub edge_m: f64,
    /// Grid points (flat indices) inside the domain, `M_D` of them.
    pub points: Vec<u32>,
    /// Frequencies of the bins analysed, Hz.
    pub freqs_hz: Vec<f64>,
    /// Per bin: the number of singular values within the threshold of the largest.
    pub effective_rank: Vec<usize>,
    /// Per bin: `sigma_1 / sigma_N`, finite and >= 1.
    pub condition_number: Vec<f64>,
    /// Per bin, per singular value (`N` of them): `10 log10(sigma_i^2 / sigma_1^2)`, dB, floored at
    /// [`ENERGY_FLOOR_DB`].
    pub relative_energy_db: Vec<Vec<f64>>,
}

impl DomainAuthority {
    /// Band-averaged effective rank (between 1 and `N`).
    pub fn mean_effective_rank(&self) -> f64 {
        mean(self.effective_rank.iter().map(|&r| r as f64))
    }

    /// Band-averaged condition number (>= 1).
    pub fn mean_condition_number(&self) -> f64 {
        mean(self.condition_number.iter().copied())
    }

    /// Per singular value: the mean and the standard deviation across bins of the relative energy, dB (the
    /// paper's Fig. 6B, its error bars the standard deviation across frequencies).
    pub fn relative_energy_db_stats(&self) -> Vec<(f64, f64)> {
        let n = self.relative_energy_db.first().map_or(0, Vec::len);
        (0..n)
            .map(|i| {
                let mu = mean(self.relative_energy_db.iter().map(|row| row[i]));
                let var = mean(self.relative_energy_db.iter().map(|row| (row[i] - mu).powi(2)));
                (mu, var.sqrt())
            })
            .collect()
    }
}

fn mean(values: impl ExactSizeIterator<Item = f64>) -> f64 {
    let n = values.len().max(1) as f64;
    values.sum::<f64>() / n
}

/// Rows of `g` (positions into `g.points()`) whose position (`position_m` of the point's index, m) lies in the
/// square of edge `edge_m` centred on `centre_m`: within `edge_m / 2` of the centre along x and along y (a
/// micrometre of slack, so that points exactly on the edge count whatever the rounding).
pub fn domain_rows(
    g: &PropagationMatrices,
    position_m: &dyn Fn(u32) -> (f64, f64),
    edge_m: f64,
    centre_m: (f64, f64),
) -> Vec<usize> {
    let half = edge_m / 2.0 + 1e-6;
    g.points()
        .iter()
        .enumerate()
        .filter(|(_, p)| {
            let (x, y) = position_m(**p);
            (x - centre_m.0).abs() <= half && (y - centre_m.1).abs() <= half
        })
        .map(|(row, _)| row)
        .collect()
}

/// Singular-value authority of `g` over the square domain of edge `edge_m` (see the module documentation).
///
/// Valid range: finite `edge_m > 0`; the domain must hold at least as many points as there are actuators (else
/// `G_D` has fewer rows than singular values to compare); `g` must have a bin in the band.
///
/// # Errors
/// [`AnalysisError::InvalidParameter`] for an edge or threshold outside its range or an empty band;
/// [`AnalysisError::TooFewPoints`] when the domain holds fewer points than actuators; [`AnalysisError::NoEnergy`]
/// when `G_D` is zero at some bin; [`AnalysisError::NonFiniteResult`] when `G_D` is singular at some bin (its
/// condition number is infinite) or the SVD fails.
pub fn domain_authority(
    g: &PropagationMatrices,
    grid: &GridSpec,
    edge_m: f64,
    opts: &AuthorityOptions,
) -> Result<DomainAuthority, AnalysisError> {
    domain_authority_at(g, &|p| grid.position_m(p as usize), edge_m, opts)
}

/// [`domain_authority`] with each point's position given by `position_m` (point index -> m): scattered points
/// (`crate::scattered`) select their domain by where they are.
///
/// # Errors
/// As [`domain_authority`].
pub fn domain_authority_at(
    g: &PropagationMatrices,
    position_m: &dyn Fn(u32) -> (f64, f64),
    edge_m: f64,
    opts: &AuthorityOptions,
) -> Result<DomainAuthority, AnalysisError> {
    if !(edge_m.is_finite() && edge_m > 0.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "edge_m",
            reason: format!("must be finite and positive, got {edge_m}"),
        });
    }
    if !(opts.threshold_db.is_finite() && opts.threshold_db <= 0.0) {
        return Err(AnalysisError::InvalidParameter {
            name: "threshold_db",
            reason: format!("must be finite and <= 0, got {}", opts.threshold_db),
        });
    }
    let bins = bins_in_band(g, opts.band_hz)?;
    let rows = domain_rows(g, position_m, edge_m, opts.centre_m);
    let n_act = g.n_actuators();
    if rows.len() < n_act {
        return Err(AnalysisError::TooFewPoints { measured: rows.len(), required: n_act });
    }
    let mut out = DomainAuthority {
        edge_m,
        points: rows.iter().map(|&r| g.points()[r]).collect(),
        freqs_hz: Vec::with_capacity(bins.len()),
        effective_rank: Vec::with_capacity(bins.len()),
        condition_number: Vec::with_capacity(bins.len()),
        relative_energy_db: Vec::with_capacity(bins.len()),
    };
    for &k in &bins {
        let Some(gk) = g.at_bin(k) else { continue };
        let gd = Mat::from_fn(rows.len(), n_act, |i, j| gk[(rows[i], j)]);
        let sigma = singular_values_complex(gd.as_ref(), "singular values of G_D")?;
        let (first, last) = match (sigma.first(), sigma.last()) {
            (Some(&a), Some(&b)) if a > 0.0 => (a, b),
            _ => return Err(AnalysisError::NoEnergy { what: "authority (G_D is zero at a bin)" }),
        };
        let kappa = first / last;
        if !kappa.is_finite() {
            return Err(AnalysisError::NonFiniteResult { what: "condition number (G_D is singular at a bin)" });
        }
        let energy_db: Vec<f64> = sigma.iter().map(|s| (20.0 * (s / first).log10()).max(ENERGY_FLOOR_DB)).collect();
        out.effective_rank.push(energy_db.iter().filter(|&&e| e >= opts.threshold_db).count());
        out.condition_number.push(kappa);
        out.relative_energy_db.push(energy_db);
        out.freqs_hz.push(g.freqs_hz()[k]);
    }
    Ok(out)
}

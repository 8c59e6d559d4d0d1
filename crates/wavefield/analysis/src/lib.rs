//! Wave-field analysis for metaplate, in `f64` throughout: the paper's Wave Field Analysis on a plate's propagation
//! matrices, and the whole analysis of a dataset on disk as `metaplate analyze` prints it.
//!
//! # Modules
//!
//! - [`wavelength`]: plate wavelengths from a k-space (2-D spatial Fourier) transform of the Green's functions at
//!   one frequency, as in the paper, with per-actuator estimates summarised across actuators; and
//!   [`wavelength::local`], the plate-equation (biharmonic Rayleigh quotient) wavelength, free of the k-space
//!   method's aperture limit (both below).
//! - [`dispersion`]: both estimators for every actuator's field at one frequency, from a propagation response, and
//!   their medians: what the plate's tests and `metaplate simulate dispersion` call.
//! - [`pod`]: spatial response dimensionality (POD of the actuator-summed response).
//! - [`authority`]: singular-value effective rank and condition number of `G_D(omega)` over square domains.
//! - [`refresh`]: the shortest resolvable spacing of two focused pulses, with the closed-form single-pixel
//!   focusing of [`focus`].
//! - [`response`]: the mean driven response.
//! - [`pixel`]: the virtual-pixel area (the half-maximum contour by marching squares) and its map over the plate,
//!   over the operating band whatever band the propagation matrices were loaded over.
//! - [`bands`]: the operating band, and the bins of a propagation matrix inside a band.
//! - [`lattice`]: the regular lattice a (subset of) measured points lies on, on which every lattice-dependent
//!   analysis works, and the range of wavelengths it can resolve (below).
//! - [`report`]: all of them on one plate, from its propagation matrices.
//! - [`scattered`]: points on no lattice (an imported scan mesh): which analyses run on the points, and the linear
//!   interpolation on their Delaunay triangulation onto a lattice within their hull for the k-space wavelength and
//!   the pixel area.
//! - [`dataset_report`]: the whole analysis of a dataset on disk as `metaplate analyze` prints it (a typed,
//!   serialisable report), with its figures ([`dataset_figures`], one plate's, or both built-in plates' on shared
//!   axes); [`paper_table`]: the paper-against-suite table from typed results.
//!
//! # Wavelength
//!
//! - [`wavelength`] (the paper's method): the 2-D FFT of one actuator's field over the measured grid (zero-padded
//!   x8, mean removed), its peak, the 8-connected region of bins at or above half of it, and the distribution of
//!   `2 pi / |k|` over that region (median, IQR). It is aperture-limited: on the 24 x 12 cm grid it resolves
//!   wavelengths up to about 12 cm (bias within about 3 % on synthetic plane and cylindrical waves); longer ones read
//!   10 to 20 % short and are flagged `under_resolved`.
//! - [`wavelength::local`] (the plate-equation estimate): the Rayleigh quotient of the discrete bilaplacian,
//!   `k^4 = sum conj(u) L2 u / sum |u|^2` over points away from sources and supports, with the stencil's dispersion
//!   corrected. It resolves wavelengths as long as the plate (within 0.1 % at 25 cm on synthetic fields on the
//!   stadium grid), but needs a high SNR (it is for simulated fields).
//!
//! # The lattice
//!
//! A scan of every `s`-th grid point (`--grid 25x13` on 49 x 25: `s = 2`) keeps the full grid's indices. Laid on
//! the full grid, its unmeasured points between read as zeros: the field is multiplied by a comb of period `s`, its
//! spectrum is repeated at multiples of `2 pi / (s h)` inside the full grid's Nyquist limit, and the k-space peak
//! lands on an image. [`lattice::Lattice::of_points`] finds the coarsest regular lattice through the points
//! (stride: the gcd of their offsets) and every lattice-dependent analysis works on it: the wavelength
//! ([`report::wavelength_at_bin`]), the pixel-area map, the maps of the figures. [`lattice::ResolvableRange`] says
//! what a k-space estimate on it resolves: `2 h` (Nyquist, `pi / h`) to half the aperture's longer side, on a
//! lattice at least half filled ([`lattice::MIN_LATTICE_FILL`]; an irregular subset, e.g. `--grid 13x7`, has
//! stride 1 and mostly holes). `analyze --json` gives `lattice` {nx, ny, spacing_m, stride, fill},
//! `wavelength_resolvable` {nyquist_k_rad_m, shortest_m, aperture_m, longest_m}, per frequency `in_range` (the
//! median inside the range and no actuator flagged), `actuators_flagged` and `a0_wavelength_m` (built-in scenes),
//! and `points_per_domain` of the authority domains (the condition number depends on it: on the 3.5 cm domain 9 to
//! 16 points at 1 cm against the paper's 49 at 5 mm). The test module `wavelength_lattice` checks the full grid and
//! every second and third point of both plates against each other (5 %) and the homogeneous plate against A0
//! (20 %, the estimator's bias near half the aperture), and that what a lattice cannot resolve is flagged.
//!
//! # Invariants
//!
//! Every public routine checks its input: an empty or mismatched input, a NaN or infinity, or a parameter outside the
//! routine's stated valid range is an [`AnalysisError`], never a panic and never a NaN in the result.

pub mod authority;
pub mod bands;
pub mod dataset_figures;
pub mod dataset_report;
pub mod dispersion;
pub mod error;
pub mod focus;
pub mod lattice;
mod linalg;
pub mod paper_table;
pub mod pixel;
pub mod pod;
pub mod refresh;
pub mod report;
pub mod response;
pub mod scattered;
pub mod wavelength;

pub use error::AnalysisError;

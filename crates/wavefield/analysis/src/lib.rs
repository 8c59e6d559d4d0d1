//! Wave-field analysis for metaplate, in `f64` throughout.
//!
//! [`wavelength`]: plate wavelengths from a k-space (2-D spatial Fourier) transform of the Green's functions at one
//! frequency, as in the paper's Wave Field Analysis, with per-actuator estimates summarised across actuators.
//! [`wavelength::local`]: the plate-equation (biharmonic Rayleigh quotient) wavelength, free of the k-space
//! method's aperture limit. [`dispersion`]: both, for every actuator's field at one frequency, from a propagation
//! response.
//! [`pod`]: spatial response dimensionality (POD of the actuator-summed response). [`authority`]: singular-value
//! effective rank and condition number of `G_D(omega)` over square domains. [`refresh`]: the shortest resolvable
//! spacing of two focused pulses, with the closed-form single-pixel focusing of [`focus`]. [`response`]: the mean
//! driven response. [`report`]: all of them on one plate. [`bands`]: the operating band. [`lattice`]: the regular
//! lattice a (subset of) measured points lies on, on which every lattice-dependent analysis works, and the range of
//! wavelengths it can resolve. [`dataset_report`]: the whole analysis of a dataset on disk as `metaplate analyze`
//! prints it (a typed, serialisable report), with its figures ([`dataset_figures`]); [`paper_table`]: the
//! paper-against-suite table from typed results.
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
pub mod wavelength;

pub use error::AnalysisError;

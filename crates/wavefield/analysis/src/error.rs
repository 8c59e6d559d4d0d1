//! The one error type of this crate.

use metaplate_dsp::DspError;

/// Why an analysis routine refused its input or could not produce a finite result.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// Two inputs that must match in length do not.
    #[error("{what}: lengths {a} and {b} differ")]
    LengthMismatch {
        /// What was compared.
        what: &'static str,
        /// First length.
        a: usize,
        /// Second length.
        b: usize,
    },
    /// A parameter lies outside the routine's valid range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// Parameter name, with its unit where it has one.
        name: &'static str,
        /// What was wrong and what is accepted.
        reason: String,
    },
    /// An input held NaN or an infinity (a device glitch, or a corrupt file).
    #[error("{input} contains a non-finite value at index {index}")]
    NonFinite {
        /// Which input.
        input: &'static str,
        /// First offending index.
        index: usize,
    },
    /// An input had no elements where at least one is needed.
    #[error("{input} is empty")]
    Empty {
        /// Which input.
        input: &'static str,
    },
    /// Too few grid points were measured for the analysis to mean anything.
    #[error("only {measured} grid point(s) measured, at least {required} needed")]
    TooFewPoints {
        /// Measured (unmasked) points.
        measured: usize,
        /// Minimum accepted.
        required: usize,
    },
    /// The input carries no energy the analysis can use (for the wavelength: an all-zero field, a field constant
    /// over the measured points, or one whose only energy lies at k = 0).
    #[error("{what}: the input has no usable energy")]
    NoEnergy {
        /// Which analysis.
        what: &'static str,
    },
    /// The field does not behave as one propagating plate wave over the points used, so no wavelength follows from
    /// the plate equation: its quotient `Re k^4` is zero or negative (a static or rigid-body field, one dominated by
    /// evanescent or band-gap waves), or beyond what the grid can sample (shorter than two grid steps).
    #[error("{what}: {reason}")]
    NotAPlateWave {
        /// Which analysis.
        what: &'static str,
        /// What was found.
        reason: String,
    },
    /// The analysis needs a lattice (a k-space transform, pixel contours) and the points give none: scattered
    /// points that span no area to interpolate over (see [`crate::scattered`]).
    #[error("needs a lattice, and these points give none: {reason}")]
    NeedsLattice {
        /// Why no lattice (the points, their number).
        reason: String,
    },
    /// A size would need more memory than the routine allows.
    #[error("{what} needs {len} elements, more than the limit of {max}")]
    TooLarge {
        /// What was too large.
        what: &'static str,
        /// Requested size.
        len: usize,
        /// Limit.
        max: usize,
    },
    /// The computation overflowed to NaN or infinity although the inputs were finite.
    #[error("{what} produced a non-finite result; the input is outside the routine's valid range")]
    NonFiniteResult {
        /// Which computation.
        what: &'static str,
    },
    /// A dataset could not be opened (the store's reason, its causes after colons).
    #[error("opening dataset {}: {reason}", path.display())]
    Dataset {
        /// The dataset's directory.
        path: std::path::PathBuf,
        /// Why.
        reason: String,
    },
    /// A step of a dataset's analysis failed in a lower crate (control: the point selection, G(omega)).
    #[error("{step}: {reason}")]
    Step {
        /// What was being done.
        step: &'static str,
        /// Why (the lower crate's error, its causes after colons).
        reason: String,
    },
    /// A figure could not be drawn or written.
    #[error("figure {name}: {reason}")]
    Figure {
        /// The figure's file stem.
        name: &'static str,
        /// Why (the figures crate's error, its causes after colons).
        reason: String,
    },
    /// A shared signal-processing helper refused its input.
    #[error(transparent)]
    Dsp(#[from] DspError),
}

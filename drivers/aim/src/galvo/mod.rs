//! Galvanometer mirrors: two analog outputs steer the beam; a map fitted from taught points turns plate coordinates
//! into their voltages.

mod aimer;
pub mod file;
mod fit;
pub mod teach;

pub use aimer::{GalvoAimer, GalvoSettings};
pub use fit::{FitModel, GalvoFit, Residual, TaughtPoint};

use metaplate_core::toml_locate::Located;

/// Why a galvo fit, its file or its teaching failed.
#[derive(Debug, thiserror::Error)]
pub enum GalvoError {
    /// Fewer taught points than the model needs.
    #[error("a {model} fit needs at least {needed} taught points, {got} given")]
    TooFewPoints {
        /// The model's name.
        model: &'static str,
        /// Its minimum.
        needed: usize,
        /// How many were given.
        got: usize,
    },
    /// A taught point with a non-finite coordinate.
    #[error("taught point {index}: {detail}")]
    InvalidPoint {
        /// Which point (0-based, in teaching order).
        index: usize,
        /// The point and what is wrong.
        detail: String,
    },
    /// Two taught points on one spot (of the plate, or at one pair of voltages).
    #[error("taught points {first} and {second} coincide on the {side} side: teach distinct marks")]
    Duplicate {
        /// `plate` or `volts`.
        side: &'static str,
        /// The first point (0-based).
        first: usize,
        /// The second point.
        second: usize,
    },
    /// Taught points on one line: they do not pin down a map of the plane.
    #[error("taught points {points:?} lie on one line on the {side} side: spread the marks over the plate")]
    Collinear {
        /// `plate` or `volts`.
        side: &'static str,
        /// The points on the line (0-based).
        points: Vec<usize>,
    },
    /// Any other set of points that does not determine the map.
    #[error("degenerate galvo fit: {detail}")]
    Degenerate {
        /// What is undetermined.
        detail: String,
    },
    /// A fit file that is not TOML, or a key missing, unknown or out of range (names the file, line and key).
    #[error("galvo fit file {0}")]
    File(Located),
    /// A fit file that cannot be read or written.
    #[error("galvo fit file {path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// Teaching asked for something it cannot do (no marks, a mark not finite, finishing before any point).
    #[error("aim teach: {detail}")]
    Teach {
        /// What and why.
        detail: String,
    },
    /// The mirrors' outputs failed while teaching.
    #[error(transparent)]
    Outputs(#[from] metaplate_core::aim::AimError),
}

//! The crate's error.

use metaplate_core::toml_locate::Located;

/// What can go wrong reading a design or computing its band structure.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// A design file could not be read.
    #[error("cannot read design file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A design file is not valid: where (file:line:column), which key, why.
    #[error("{0}")]
    Invalid(Located),
    /// An option out of its range (mesh sizes, number of wave vectors or modes).
    #[error("invalid option: {0}")]
    Option(String),
    /// The eigenproblem failed (a mass matrix not positive definite, or the eigensolver did not converge):
    /// a degenerate design.
    #[error("eigenproblem failed at {at}: {why}")]
    Eigen {
        /// Which problem (a wave vector, or the clamped cell).
        at: String,
        /// The solver's complaint.
        why: String,
    },
}

//! The crate's error.

use metaplate_core::toml_locate::TomlFileError;

/// What can go wrong reading a design or computing its band structure.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// A design or search file could not be read or is not valid (file, line, key).
    #[error(transparent)]
    File(#[from] TomlFileError),
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
    /// The homogenised model's fit to the cell's branch failed (parameters not finite and positive).
    #[error("homogenised fit failed: {0}")]
    Fit(String),
    /// A search's results could not be written or read, or do not fit together (another search's parts,
    /// designs missing from a merge).
    #[error("search results {path}: {why}")]
    Results {
        /// The file or folder.
        path: String,
        /// What is wrong.
        why: String,
    },
    /// A search was stopped (Ctrl-C) between designs: every design finished is written; the same command resumes.
    #[error("stopped after {done} of {total} designs; run the same command again to resume")]
    Stopped {
        /// Designs of the shard finished.
        done: usize,
        /// Designs of the shard in all.
        total: usize,
    },
}

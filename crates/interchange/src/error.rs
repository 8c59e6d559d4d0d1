//! The one error type of the universal-file bridge.

use metaplate_core::grid::GridError;
use metaplate_core::scene::SceneError;
use metaplate_dsp::DspError;
use metaplate_store::StoreError;
use metaplate_uff::{DecodeError, EncodeError};

/// Why an export or an import failed. Each variant's message says what was being done; its source (printed after
/// it by a caller that prints causes) says why.
#[derive(Debug, thiserror::Error)]
pub enum InterchangeError {
    /// A file could not be opened, created, read or written (`what`: which, and what was being done).
    #[error("{what}")]
    File {
        /// What was being done, naming the file.
        what: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// Writing the output failed.
    #[error(transparent)]
    Write(#[from] std::io::Error),
    /// A dataset could not be opened, created or written (`what` names it).
    #[error("{what}")]
    Dataset {
        /// What was being done, naming the dataset.
        what: String,
        /// The store's error.
        #[source]
        source: StoreError,
    },
    /// The store refused a read or a write.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// A universal file cannot be read: malformed, or a variant the codec does not read (the source names the
    /// record, line and field, and what is accepted there).
    #[error("{file} cannot be read")]
    Malformed {
        /// The file, as given.
        file: String,
        /// Where and what.
        #[source]
        source: DecodeError,
    },
    /// A value cannot be written in the universal-file format.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    /// The scene giving the actuators' positions could not be read.
    #[error("{what}")]
    Scene {
        /// What was being read.
        what: String,
        /// The scene's error.
        #[source]
        source: SceneError,
    },
    /// Points do not fit, or form no grid (`what`: which points).
    #[error("{what}")]
    Grid {
        /// Which points.
        what: String,
        /// The grid's error.
        #[source]
        source: GridError,
    },
    /// A transform failed.
    #[error(transparent)]
    Dsp(#[from] DspError),
    /// The files or the dataset hold something the bridge does not take; the message says what, and why.
    #[error("{0}")]
    Refused(String),
    /// An error at a place (`at`: a file's record, or the export of a dataset to a file).
    #[error("{at}")]
    At {
        /// Where.
        at: String,
        /// What went wrong there.
        #[source]
        source: Box<InterchangeError>,
    },
}

impl InterchangeError {
    /// A closure wrapping an error with the place `at`, for `map_err`.
    pub(crate) fn at<E: Into<InterchangeError>>(at: impl FnOnce() -> String) -> impl FnOnce(E) -> InterchangeError {
        move |e| InterchangeError::At { at: at(), source: Box::new(e.into()) }
    }
}

/// `Err(InterchangeError::Refused(..))` with a formatted reason.
macro_rules! refuse {
    ($($arg:tt)*) => {
        return Err($crate::error::InterchangeError::Refused(format!($($arg)*)))
    };
}
pub(crate) use refuse;

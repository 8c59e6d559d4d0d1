//! Reading a cassette for replay, with the typed errors of a damaged file.

use std::path::Path;

use metaplate_cassette::{Cassette, CassetteError, DeviceKind};

use crate::mismatch::Mismatch;

/// Why a replay could not start, or stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The cassette file could not be read.
    #[error("cannot read cassette {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The cassette is damaged: no readable header, or (in strict loading) any bad or missing part (the defect is
    /// the error's source, which the binary prints after it).
    #[error("bad cassette")]
    Cassette(#[from] CassetteError),
    /// The cassette was recorded with another kind of device than the replay transport plays.
    #[error("the cassette holds a {found:?} session, not {expected:?}")]
    WrongDevice {
        /// The device kind the transport plays.
        expected: DeviceKind,
        /// The cassette's.
        found: DeviceKind,
    },
    /// The driver did not do what the recording did.
    #[error(transparent)]
    Mismatch(#[from] Mismatch),
}

/// A cassette as read for replay: every good record, and what was wrong with the file.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCassette {
    /// The header and the good records.
    pub cassette: Cassette,
    /// Defects met after the header (a cut-short file ends with `CassetteError::Truncated`).
    pub errors: Vec<CassetteError>,
    /// Whether the end marker was read.
    pub complete: bool,
}

/// Reads a cassette from bytes. `strict`: any defect (a truncation included) is an error; otherwise every good
/// record is kept and the defects are listed, so a recording cut short by a crash can still be replayed up to
/// the cut.
///
/// # Errors
/// [`ReplayError::Cassette`]: no readable header, or in strict mode the first defect.
pub fn load_bytes(bytes: &[u8], strict: bool) -> Result<LoadedCassette, ReplayError> {
    let recovered = Cassette::recover(bytes)?;
    if strict && let Some(error) = recovered.errors.first() {
        return Err(ReplayError::Cassette(error.clone()));
    }
    Ok(LoadedCassette { cassette: recovered.cassette, errors: recovered.errors, complete: recovered.complete })
}

/// Reads a cassette file (see [`load_bytes`]).
///
/// # Errors
/// [`ReplayError::Io`] when the file cannot be read; as [`load_bytes`].
pub fn load_file(path: &Path, strict: bool) -> Result<LoadedCassette, ReplayError> {
    let bytes = std::fs::read(path).map_err(|source| ReplayError::Io { path: path.display().to_string(), source })?;
    load_bytes(&bytes, strict)
}

/// Checks that `cassette` was recorded with a device of kind `expected`.
///
/// # Errors
/// [`ReplayError::WrongDevice`].
pub(crate) fn check_kind(cassette: &Cassette, expected: DeviceKind) -> Result<(), ReplayError> {
    let found = cassette.header.device_kind;
    if found == expected { Ok(()) } else { Err(ReplayError::WrongDevice { expected, found }) }
}

//! Where there are no pseudo-terminals (not Unix): the same API, refusing to start, so that the mock lab and the
//! binary build everywhere and say why the pseudo-terminal link is missing.

use std::path::Path;
use std::sync::{Arc, Mutex};

use crate::served::ServedDevice;

/// Why the pseudo-terminal server could not start.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    /// This system has no pseudo-terminals.
    #[error("pseudo-terminals exist on Unix only; serve the mock controller in process instead")]
    Unsupported,
}

/// Never constructed here: [`PtyServer::spawn`] always fails off Unix.
#[derive(Debug)]
pub struct PtyServer {
    _never: std::convert::Infallible,
}

impl PtyServer {
    /// Fails: there are no pseudo-terminals on this system.
    ///
    /// # Errors
    /// Always [`PtyError::Unsupported`].
    pub fn spawn<D: ServedDevice>(_device: Arc<Mutex<D>>) -> Result<Self, PtyError> {
        Err(PtyError::Unsupported)
    }

    /// The terminal's device path (unreachable: no server exists off Unix).
    pub fn path(&self) -> &Path {
        match self._never {}
    }
}

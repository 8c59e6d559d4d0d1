//! Scratch directories for the scans an evaluation makes and throws away (budget, tradeoff).

use std::path::PathBuf;

use metaplate_core::scene::Scene;
use metaplate_recipes::Output;

use crate::error::{EvaluationError, io_error};

/// A fresh run directory for a scan of `scene` on the mock lab, and the scan's output there (a new run).
///
/// # Errors
/// The directory cannot be created.
pub(crate) fn scratch_output(scene: &Scene) -> Result<(PathBuf, Output), EvaluationError> {
    let dir = scratch_dir()?;
    let out = Output {
        dir: dir.clone(),
        scene: scene.id(),
        software_version: env!("CARGO_PKG_VERSION").into(),
        resume: false,
        force: false,
        preflight: None,
    };
    Ok((dir, out))
}

/// A fresh directory under the system's temporary directory.
///
/// # Errors
/// The directory cannot be created.
pub(crate) fn scratch_dir() -> Result<PathBuf, EvaluationError> {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let dir = std::env::temp_dir().join(format!("metaplate-tradeoff-{}-{nanos}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(io_error("creating", &dir))?;
    Ok(dir)
}

//! Where the plate's Green's functions are cached: the one `--cache-dir` / `--no-cache` option every command that
//! builds a simulated plate flattens in, and its default under the user's cache directory.

use std::path::PathBuf;

use clap::Args;
use metaplate_plate::{CACHE_DIR_ENV, default_cache_dir};

/// The Green's-function cache option of a command (`#[command(flatten)] cache: CacheArgs`).
#[derive(Args, Debug, Clone, Default)]
pub struct CacheArgs {
    /// Directory caching the plate's Green's functions (keyed by the scene's plate and the request; created when
    /// missing), so that a rerun skips the plate model. Default: `$METAPLATE_CACHE_DIR`, else
    /// `$XDG_CACHE_HOME/metaplate`, else `~/.cache/metaplate`.
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
    /// Compute the Green's functions afresh and cache nothing.
    #[arg(long, conflicts_with = "cache_dir")]
    pub no_cache: bool,
}

impl CacheArgs {
    /// The cache directory to use, or `None` for no cache (`--no-cache`, or no default can be found: then a
    /// warning says so and the run computes everything).
    pub fn dir(&self) -> Option<PathBuf> {
        if self.no_cache {
            return None;
        }
        if let Some(dir) = &self.cache_dir {
            return Some(dir.clone());
        }
        let dir = default_cache_dir(|name| std::env::var_os(name));
        if dir.is_none() {
            tracing::warn!(
                "no cache directory: none of {CACHE_DIR_ENV}, XDG_CACHE_HOME, HOME is set; Green's functions are not \
                 cached (pass --cache-dir DIR)"
            );
        }
        dir
    }
}

//! Where the plate's Green's functions are cached: the one `--cache-dir` / `--no-cache` option every command that
//! builds a simulated plate flattens in, and its default under the user's cache directory.

use std::path::PathBuf;

use clap::Args;

/// Environment variable naming the cache directory outright (first choice of the default).
pub const CACHE_DIR_ENV: &str = "METAPLATE_CACHE_DIR";

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

/// The default cache directory from the environment (`var` reads a variable): `$METAPLATE_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/metaplate`, else `$HOME/.cache/metaplate`; `None` when none is set. Empty values count as
/// unset, and a relative `XDG_CACHE_HOME` is ignored (the XDG specification says so).
pub fn default_cache_dir(var: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let set = |name: &str| var(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    set(CACHE_DIR_ENV)
        .or_else(|| set("XDG_CACHE_HOME").filter(|p| p.is_absolute()).map(|p| p.join("metaplate")))
        .or_else(|| set("HOME").map(|p| p.join(".cache").join("metaplate")))
}

#[cfg(test)]
mod tests {
    use std::ffi::OsString;

    use super::*;

    fn env(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<OsString> {
        let pairs: Vec<(String, OsString)> = pairs.iter().map(|(k, v)| ((*k).to_owned(), OsString::from(v))).collect();
        move |name| pairs.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone())
    }

    #[test]
    fn the_default_follows_the_environment_in_order() {
        let all = [("METAPLATE_CACHE_DIR", "/m"), ("XDG_CACHE_HOME", "/x"), ("HOME", "/h")];
        assert_eq!(default_cache_dir(env(&all)), Some(PathBuf::from("/m")));
        assert_eq!(default_cache_dir(env(&all[1..])), Some(PathBuf::from("/x/metaplate")));
        assert_eq!(default_cache_dir(env(&all[2..])), Some(PathBuf::from("/h/.cache/metaplate")));
        assert_eq!(default_cache_dir(env(&[])), None);
        // Empty is unset; a relative XDG_CACHE_HOME is ignored.
        let odd = [("METAPLATE_CACHE_DIR", ""), ("XDG_CACHE_HOME", "rel"), ("HOME", "/h")];
        assert_eq!(default_cache_dir(env(&odd)), Some(PathBuf::from("/h/.cache/metaplate")));
    }

    #[test]
    fn flags_override_the_default() {
        let given = CacheArgs { cache_dir: Some(PathBuf::from("/given")), no_cache: false };
        assert_eq!(given.dir(), Some(PathBuf::from("/given")));
        assert_eq!(CacheArgs { cache_dir: None, no_cache: true }.dir(), None);
    }
}

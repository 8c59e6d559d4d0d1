//! Free space on the file system a dataset is written to: what the pre-flight check and the monitor compare a
//! run's size with.

use std::path::Path;

/// Free bytes for an unprivileged writer on the file system holding `path`, or, when `path` does not exist yet (a
/// run's directory before its first run), on the file system of its nearest existing ancestor. `None` when it
/// cannot be read (no such ancestor, or a platform without `statvfs`).
pub fn free_bytes(path: &Path) -> Option<u64> {
    // A relative path's last ancestor is the empty path: the current directory.
    let here = |p: &'_ Path| if p.as_os_str().is_empty() { Path::new(".").to_path_buf() } else { p.to_path_buf() };
    let existing = path.ancestors().map(here).find(|p| p.exists())?;
    statvfs_free(&existing)
}

#[cfg(unix)]
fn statvfs_free(dir: &Path) -> Option<u64> {
    let stat = rustix::fs::statvfs(dir).ok()?;
    Some(stat.f_bavail.saturating_mul(stat.f_frsize))
}

#[cfg(not(unix))]
fn statvfs_free(_dir: &Path) -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(unix)]
    #[test]
    fn a_directory_not_yet_made_reads_its_ancestors_disk() {
        let here = free_bytes(Path::new(".")).expect("the current directory's disk");
        assert!(here > 0);
        let later = free_bytes(Path::new("not-made-yet/nor-this")).expect("its ancestor's disk");
        // The same file system, read twice: other writers may change it a little in between.
        assert!(later.abs_diff(here) < here / 10 + (1 << 30), "{later} vs {here}");
        assert!(free_bytes(Path::new("")).is_some(), "the empty path is the current directory");
    }
}

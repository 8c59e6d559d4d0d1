//! On-disk cache of Green's functions, keyed by the scene's physics hash ([`Scene::physics_hash`]: what the plate
//! depends on, so scenes that differ only in their instruments, faults or setup share entries), the model options
//! and the request.
//!
//! Where: only in a directory the caller passes (nothing is written otherwise), one file per key,
//! `greens-<scene hash>-<request key>.bin` (both 16 hex digits). Format (little-endian): magic `MPGREEN1`, key u64,
//! sample rate f64, ir_len u64, point count u64, actuator count u64, the point and actuator indices (u64 each), then
//! the samples (f64). A file is written to a temporary name of its writer's own, fsynced and renamed, so a reader
//! never sees half a file and concurrent writers of one entry (processes or threads) do not mix; a file
//! whose header does not match the request, is truncated, or holds a non-finite sample is ignored and recomputed.

use metaplate_core::hash::fnv1a_64;
use std::fs;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use metaplate_core::scene::Scene;

use crate::error::PlateError;
use crate::greens::{GreensFunctions, GreensRequest};
use crate::model::{ModelOptions, PlateModel};

const MAGIC: &[u8; 8] = b"MPGREEN1";

/// Bumped whenever the model's numerics change, so stale caches are not reused.
const MODEL_VERSION: u64 = 1;

/// Cache key of a request on a scene (by hash) with given options. The thread count is left out: results do not
/// depend on it.
pub fn cache_key(scene_hash: u64, options: &ModelOptions, request: &GreensRequest) -> u64 {
    let words = [MODEL_VERSION, scene_hash, options.refinement as u64]
        .into_iter()
        .chain([request.band_hz.0, request.band_hz.1, request.duration_s, request.sample_rate_hz].map(f64::to_bits))
        .chain([request.points.len() as u64])
        .chain(request.points.iter().map(|&p| p as u64))
        .chain([request.actuators.len() as u64])
        .chain(request.actuators.iter().map(|&a| a as u64));
    fnv1a_64(words.flat_map(u64::to_le_bytes))
}

/// Path of the cache file for a key.
pub fn cache_path(dir: &Path, scene_hash: u64, key: u64) -> PathBuf {
    dir.join(format!("greens-{scene_hash:016x}-{key:016x}.bin"))
}

/// Green's functions of `scene` for `request`, from `cache_dir` when a matching file is there, otherwise computed
/// (see [`PlateModel::greens_functions`]) and, with a cache directory, stored there.
///
/// # Errors
/// As [`PlateModel::from_scene`] and [`PlateModel::greens_functions`]; [`PlateError::Cache`] when the cache
/// directory cannot be created (it is created with its parents when missing), read or written.
pub fn greens_functions(
    scene: &Scene,
    options: &ModelOptions,
    request: &GreensRequest,
    cache_dir: Option<&Path>,
) -> Result<GreensFunctions, PlateError> {
    if let Some(dir) = cache_dir {
        // Before the computation, so that an unusable directory fails at once rather than after it.
        ensure_dir(dir)?;
    }
    let scene_hash = scene.physics_hash();
    let path = cache_dir.map(|dir| cache_path(dir, scene_hash, cache_key(scene_hash, options, request)));
    if let Some(path) = &path
        && let Some(hit) = load(path, cache_key(scene_hash, options, request), request)?
    {
        return Ok(hit);
    }
    // Computed once across processes and threads: claim the entry, or wait for whoever holds the claim to store it.
    let mut claim = None;
    if let Some(path) = &path {
        let key = cache_key(scene_hash, options, request);
        loop {
            if let Some(taken) = Claim::take(path)? {
                claim = Some(taken);
                break;
            }
            std::thread::sleep(CLAIM_POLL);
            if let Some(hit) = load(path, key, request)? {
                return Ok(hit);
            }
        }
        // The holder may have stored the entry between the first look and the claim.
        if let Some(hit) = load(path, key, request)? {
            return Ok(hit);
        }
    }
    let greens = PlateModel::from_scene(scene, options)?.greens_functions(request)?;
    if let Some(path) = &path {
        store(path, cache_key(scene_hash, options, request), &greens)?;
    }
    drop(claim);
    Ok(greens)
}

/// How often a request waiting for another computation of its entry looks for it.
const CLAIM_POLL: std::time::Duration = std::time::Duration::from_millis(100);

/// A claim on computing one entry: the file `<entry>.computing` holding the computing process's id, created
/// exclusively and removed when the claim is dropped. Two tests, or two runs of the demo, that need the same Green's
/// functions at once then compute them once: the others wait and load the entry. A claim whose process is gone (it
/// was killed while computing) is stale and taken over. Liveness is read from `/proc`, so claims are made on Linux
/// only; elsewhere every request computes for itself, as before (never waiting on a claim it cannot judge).
struct Claim {
    path: PathBuf,
}

impl Claim {
    /// Claims `entry`: `Some` when this computation holds the claim (or claims are not made here), `None` while
    /// another live computation holds it.
    fn take(entry: &Path) -> Result<Option<Self>, PlateError> {
        let path = entry.with_extension("computing");
        if !cfg!(target_os = "linux") {
            return Ok(Some(Self { path: PathBuf::new() }));
        }
        match fs::OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(mut file) => {
                // Best effort: a claim without an id is judged live until its holder removes it.
                let _ = write!(file, "{}", std::process::id());
                Ok(Some(Self { path }))
            }
            Err(e) if e.kind() == ErrorKind::AlreadyExists => {
                if claim_is_stale(&path) {
                    // Taken over at the next look (another waiter may take it first: then this one waits again).
                    let _ = fs::remove_file(&path);
                }
                Ok(None)
            }
            Err(e) => Err(cache_error(&path, e)),
        }
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        if !self.path.as_os_str().is_empty() {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Whether the claim file at `path` belongs to a process that no longer runs (its id has no `/proc` entry).
fn claim_is_stale(path: &Path) -> bool {
    let Ok(text) = fs::read_to_string(path) else {
        return false;
    };
    match text.trim().parse::<u32>() {
        Ok(pid) => !Path::new("/proc").join(pid.to_string()).exists(),
        Err(_) => false,
    }
}

/// Creates the cache directory (and its parents) when it does not exist.
fn ensure_dir(dir: &Path) -> Result<(), PlateError> {
    fs::create_dir_all(dir).map_err(|e| PlateError::Cache {
        path: dir.display().to_string(),
        reason: format!("cannot create the cache directory: {e}"),
    })
}

fn cache_error(path: &Path, e: impl ToString) -> PlateError {
    PlateError::Cache { path: path.display().to_string(), reason: e.to_string() }
}

/// Reads a cache file; `Ok(None)` when it is absent or does not match.
fn load(path: &Path, key: u64, request: &GreensRequest) -> Result<Option<GreensFunctions>, PlateError> {
    let bytes = match fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(cache_error(path, e)),
    };
    Ok(parse(&bytes, key, request))
}

fn parse(bytes: &[u8], key: u64, request: &GreensRequest) -> Option<GreensFunctions> {
    let mut words =
        bytes.get(MAGIC.len()..)?.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8])));
    if bytes.get(..MAGIC.len())? != MAGIC || words.next()? != key {
        return None;
    }
    let sample_rate_hz = f64::from_bits(words.next()?);
    let ir_len = usize::try_from(words.next()?).ok()?;
    let n_points = usize::try_from(words.next()?).ok()?;
    let n_act = usize::try_from(words.next()?).ok()?;
    if sample_rate_hz != request.sample_rate_hz || n_points != request.points.len() || n_act != request.actuators.len()
    {
        return None;
    }
    let points: Vec<usize> = (0..n_points).map(|_| words.next().map(|w| w as usize)).collect::<Option<_>>()?;
    let actuators: Vec<usize> = (0..n_act).map(|_| words.next().map(|w| w as usize)).collect::<Option<_>>()?;
    if points != request.points || actuators != request.actuators {
        return None;
    }
    let data: Vec<f64> = words.map(f64::from_bits).collect();
    if data.len() != n_points.checked_mul(n_act)?.checked_mul(ir_len)? || !data.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some(GreensFunctions { sample_rate_hz, ir_len, points, actuators, data })
}

/// Distinguishes the temporary files of one process's concurrent writers (threads filling the same entry).
static TEMP_SERIAL: AtomicU64 = AtomicU64::new(0);

/// Writes a cache file atomically: a temporary name of its own (process id and a per-process serial, so that two
/// processes or threads filling the same entry at once never write one file), fsync, then rename over the entry
/// (atomic: a reader sees the old file, none, or the whole new one; the last writer wins with identical content).
fn store(path: &Path, key: u64, g: &GreensFunctions) -> Result<(), PlateError> {
    let serial = TEMP_SERIAL.fetch_add(1, Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp{}-{serial}", std::process::id()));
    let write = || -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(fs::File::create(&tmp)?);
        out.write_all(MAGIC)?;
        let header =
            [key, g.sample_rate_hz.to_bits(), g.ir_len as u64, g.points.len() as u64, g.actuators.len() as u64];
        for w in
            header.into_iter().chain(g.points.iter().map(|&p| p as u64)).chain(g.actuators.iter().map(|&a| a as u64))
        {
            out.write_all(&w.to_le_bytes())?;
        }
        for v in &g.data {
            out.write_all(&v.to_le_bytes())?;
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = fs::remove_file(&tmp);
        cache_error(path, e)
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;

    /// A fresh scratch directory (no tempfile dependency in this crate).
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("metaplate-plate-cache-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_missing_cache_directory_is_created_with_its_parents() {
        let root = scratch("create");
        let dir = root.join("a").join("b");
        ensure_dir(&dir).unwrap();
        assert!(dir.is_dir());
        // Existing already: still fine.
        ensure_dir(&dir).unwrap();
        fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn a_cache_directory_that_cannot_be_created_is_a_clear_error() {
        let root = scratch("refuse");
        let file = root.join("file");
        fs::write(&file, b"x").unwrap();
        let err = ensure_dir(&file.join("cache")).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("cannot create the cache directory") && text.contains("file/cache"), "{text}");
        fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn writers_filling_one_entry_at_once_leave_a_whole_file() {
        let root = scratch("race");
        let request = GreensRequest {
            points: vec![0, 3],
            actuators: vec![1],
            band_hz: (50.0, 600.0),
            duration_s: 0.1,
            sample_rate_hz: 24_000.0,
        };
        let ir_len = 2400;
        let greens = GreensFunctions {
            sample_rate_hz: request.sample_rate_hz,
            ir_len,
            points: request.points.clone(),
            actuators: request.actuators.clone(),
            data: (0..2 * ir_len).map(|i| i as f64 * 1e-3).collect(),
        };
        let path = cache_path(&root, 1, 2);
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| {
                    for _ in 0..5 {
                        store(&path, 2, &greens).unwrap();
                    }
                });
            }
        });
        assert_eq!(load(&path, 2, &request).unwrap(), Some(greens));
        // Only the entry is left: every temporary name was renamed away.
        assert_eq!(fs::read_dir(&root).unwrap().count(), 1);
        fs::remove_dir_all(&root).unwrap();
    }

    /// A small request on the built-in homogeneous plate, its entry's path in `dir`, and a stand-in result that no
    /// computation would give (every sample 0.25), to tell a loaded entry from a computed one.
    fn entry(dir: &Path) -> (Scene, ModelOptions, GreensRequest, PathBuf, GreensFunctions) {
        let scene = Scene::builtin("homogeneous").unwrap();
        // The coarsest lattice: these tests are about the cache's files and claims, not the physics, and a
        // computation at the default lattice takes half a minute.
        let options = ModelOptions { refinement: 1, ..ModelOptions::default() };
        let request = GreensRequest {
            points: vec![612],
            actuators: vec![0],
            band_hz: (50.0, 600.0),
            duration_s: 0.05,
            sample_rate_hz: 24_000.0,
        };
        let hash = scene.physics_hash();
        let path = cache_path(dir, hash, cache_key(hash, &options, &request));
        let ir_len = 1200;
        let stand_in = GreensFunctions {
            sample_rate_hz: 24_000.0,
            ir_len,
            points: vec![612],
            actuators: vec![0],
            data: vec![0.25; ir_len],
        };
        (scene, options, request, path, stand_in)
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_request_waits_for_a_live_claim_and_loads_what_its_holder_stores() {
        let root = scratch("claim-live");
        let (scene, options, request, path, stand_in) = entry(&root);
        let claim = path.with_extension("computing");
        // Held by a live process (this one), as another test's computation would hold it.
        fs::write(&claim, std::process::id().to_string()).unwrap();
        let key = cache_key(scene.physics_hash(), &options, &request);
        let got = std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(std::time::Duration::from_millis(300));
                store(&path, key, &stand_in).unwrap();
                fs::remove_file(&claim).unwrap();
            });
            greens_functions(&scene, &options, &request, Some(&root)).unwrap()
        });
        assert_eq!(got, stand_in, "loaded the holder's entry rather than computing its own");
        fs::remove_dir_all(&root).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_claim_left_by_a_dead_process_is_taken_over_and_removed() {
        let root = scratch("claim-stale");
        let (scene, options, request, path, stand_in) = entry(&root);
        let claim = path.with_extension("computing");
        // A process id above the kernel's maximum (2^22) never runs.
        fs::write(&claim, "4194305").unwrap();
        let got = greens_functions(&scene, &options, &request, Some(&root)).unwrap();
        assert_ne!(got, stand_in);
        assert_eq!((got.points.clone(), got.actuators.clone()), (vec![612], vec![0]));
        assert!(got.data.iter().any(|v| *v != 0.0), "computed");
        // The entry is stored and the claim gone.
        assert!(path.is_file() && !claim.exists());
        fs::remove_dir_all(&root).unwrap();
    }
}

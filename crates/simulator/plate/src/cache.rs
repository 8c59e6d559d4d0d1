//! On-disk cache of Green's functions: one entry per scene physics ([`Scene::physics_hash`]: what the plate depends
//! on, so scenes that differ only in their instruments, faults or setup share entries), model options, band,
//! duration and sample rate, holding every grid point on the plate and every driving point from every actuator
//! ([`crate::entry`]); every request with those settings, whatever its points and actuators, is cut from it, equal
//! bit for bit to computing it alone. [`greens_functions_within`] cuts a request at another rate or band from a
//! named entry whose frequency bins include the request's own (the ground truth from the mock lab's entry).
//!
//! Where: only in a directory the caller passes (nothing is written otherwise), one file per entry,
//! `greens-<scene hash>-<entry key>.bin` (both 16 hex digits), laid out so that a request reads only its points'
//! blocks ([`crate::entry_file`]: the format, the checks, the atomic write). A file that is not the expected entry,
//! is truncated or damaged, or was written by an older format or model version is ignored and recomputed. An entry
//! is computed once across processes and threads ([`Claim`]).
//!
//! Sizes: an entry holds `(slots on the plate) x actuators` pairs, each its impulse response or its band's spectrum,
//! whichever is shorter. On the built-in scenes' 49 x 25 grid (1,153 grid points on the plate plus 8 driving
//! points) with 8 actuators: the mock lab's default (24 kHz, 0.5 s, 40 to 800 Hz, default lattice: 1,396 bins
//! against 12,000 samples) 208 MB, where the impulse responses would take 950 MB; the lab tests' (24 kHz, 0.25 s,
//! 100 to 600 Hz, coarse lattice: 367 bins) 55 MB; the ground truth's (2 kHz, 0.5 s, 40 to 700 Hz: 1,000 samples
//! against 1,213 bins) 74 MB. A request for 43 points reads 8 MB of it.

use metaplate_core::hash::fnv1a_64;
use std::fs;
use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

use metaplate_core::scene::Scene;

use crate::entry::{Representation, Target};
use crate::entry_file::{self, Expected, Lookup};
use crate::error::PlateError;
use crate::greens::{GreensFunctions, GreensRequest, SpectralPlan};
use crate::model::{ModelOptions, PlateModel};

/// Environment variable naming the cache directory outright (first choice of [`default_cache_dir`]).
pub const CACHE_DIR_ENV: &str = "METAPLATE_CACHE_DIR";

/// The default cache directory from the environment (`var` reads a variable): `$METAPLATE_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/metaplate`, else `$HOME/.cache/metaplate`; `None` when none is set. Empty values count as
/// unset, and a relative `XDG_CACHE_HOME` is ignored (the XDG specification says so).
pub fn default_cache_dir(var: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let set = |name: &str| var(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    set(CACHE_DIR_ENV)
        .or_else(|| set("XDG_CACHE_HOME").filter(|p| p.is_absolute()).map(|p| p.join("metaplate")))
        .or_else(|| set("HOME").map(|p| p.join(".cache").join("metaplate")))
}

/// Bumped whenever the model's numerics or the entry's format change, so stale entries are not reused (a stale
/// file has another key, hence another name, and is never read).
const MODEL_VERSION: u64 = 2;

/// Key of the entry serving a request on a scene (by hash) with given options: the model options, band, duration
/// and sample rate. The request's points and actuators are left out (the entry holds them all), and so is the
/// thread count (results do not depend on it).
pub fn cache_key(scene_hash: u64, options: &ModelOptions, request: &GreensRequest) -> u64 {
    let words = [MODEL_VERSION, scene_hash, options.refinement as u64]
        .into_iter()
        .chain([request.band_hz.0, request.band_hz.1, request.duration_s, request.sample_rate_hz].map(f64::to_bits));
    fnv1a_64(words.flat_map(u64::to_le_bytes))
}

/// Path of the cache file for a key.
pub fn cache_path(dir: &Path, scene_hash: u64, key: u64) -> PathBuf {
    dir.join(format!("greens-{scene_hash:016x}-{key:016x}.bin"))
}

/// Green's functions of `scene` for `request`. Without a cache directory they are computed for the request alone
/// ([`PlateModel::greens_functions`]). With one, the request is cut from its entry there; when there is none, the
/// entry (every point, every actuator: about the cost of the request alone, see [`crate::entry`]) is computed,
/// stored, and the request cut from it. A scene whose entry would exceed [`crate::MAX_GREENS_BYTES`] gets the
/// request computed alone, uncached.
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
    let Some(dir) = cache_dir else {
        return PlateModel::from_scene(scene, options)?.greens_functions(request);
    };
    cut_from_entry(scene, options, request, request, None, dir)
}

/// The band, duration and sample rate of a cache entry (its points and actuators are always all of them).
///
/// Valid range: as [`GreensRequest`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EntrySettings {
    /// Band, Hz.
    pub band_hz: (f64, f64),
    /// Length of each impulse response, s.
    pub duration_s: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// As [`greens_functions`], but cut from the entry of `entry`'s settings when that entry's frequency bins include
/// every bin of the request's own, at the same frequencies bit for bit, and it stores band spectra: the request's
/// responses are then synthesised from them on its own plan, equal bit for bit to computing it alone. So a request
/// at another rate or band shares the entry another request computes anyway (the ground truth at 2 kHz, 40 to
/// 700 Hz, with the mock lab's at 24 kHz, 40 to 800 Hz, whose bins are the same frequencies). When the bins do not
/// fall on the entry's, the request gets its own entry, as [`greens_functions`].
///
/// # Errors
/// As [`greens_functions`]; [`PlateError::InvalidParameter`] for `entry` settings out of range.
pub fn greens_functions_within(
    scene: &Scene,
    options: &ModelOptions,
    request: &GreensRequest,
    entry: &EntrySettings,
    cache_dir: Option<&Path>,
) -> Result<GreensFunctions, PlateError> {
    let Some(dir) = cache_dir else {
        return PlateModel::from_scene(scene, options)?.greens_functions(request);
    };
    let entry_request = GreensRequest {
        points: request.points.clone(),
        actuators: request.actuators.clone(),
        band_hz: entry.band_hz,
        duration_s: entry.duration_s,
        sample_rate_hz: entry.sample_rate_hz,
    };
    let model = PlateModel::from_scene(scene, options)?;
    let bound = |f| model.loss_factor_bound(f);
    let plan = SpectralPlan::new(request, &bound)?;
    let entry_plan = SpectralPlan::new(&entry_request, &bound)?;
    if Representation::shorter(&entry_plan) != Representation::BandSpectrum || entry_plan.bins_at(&plan).is_none() {
        return cut_from_entry(scene, options, request, request, None, dir);
    }
    let target = Target { plan, sample_rate_hz: request.sample_rate_hz };
    cut_from_entry(scene, options, &entry_request, request, Some(&target), dir)
}

/// `request` cut from the entry of `entry_request`'s band, duration and rate in `dir` (on `target`'s plan when
/// given), the entry computed and stored first when it is missing.
fn cut_from_entry(
    scene: &Scene,
    options: &ModelOptions,
    entry_request: &GreensRequest,
    request: &GreensRequest,
    target: Option<&Target>,
    dir: &Path,
) -> Result<GreensFunctions, PlateError> {
    // Before the computation, so that an unusable directory fails at once rather than after it.
    ensure_dir(dir)?;
    let scene_hash = scene.physics_hash();
    let key = cache_key(scene_hash, options, entry_request);
    let path = cache_path(dir, scene_hash, key);
    let expected = Expected {
        key,
        sample_rate_hz: entry_request.sample_rate_hz,
        slot_count: scene.grid.len() + scene.actuators.len(),
        actuator_count: scene.actuators.len(),
    };
    let lookup = || entry_file::lookup(&path, &expected, request, target, options.threads);
    let model = match lookup()? {
        Lookup::Hit(hit) => return Ok(hit),
        // A sound entry holds every point the model can answer: computing the request says what is wrong with it.
        Lookup::NotServed => return PlateModel::from_scene(scene, options)?.greens_functions(request),
        Lookup::Miss => PlateModel::from_scene(scene, options)?,
    };
    // A request the model refuses (a point off the plate, an unknown actuator) fails now, before any computation.
    model.resolve(&request.actuators, &request.points)?;
    // Computed once across processes and threads: claim the entry, or wait for whoever holds the claim to store it.
    let claim = loop {
        if let Some(taken) = Claim::take(&path)? {
            break taken;
        }
        std::thread::sleep(CLAIM_POLL);
        if let Lookup::Hit(hit) = lookup()? {
            return Ok(hit);
        }
    };
    // The holder may have stored the entry between the first look and the claim.
    if let Lookup::Hit(hit) = lookup()? {
        return Ok(hit);
    }
    let entry = match model.greens_entry(entry_request) {
        Ok(entry) => entry,
        Err(PlateError::TooLarge { .. }) => return model.greens_functions(request),
        Err(e) => return Err(e),
    };
    entry_file::write(&path, key, &entry)?;
    drop(claim);
    match entry.cut(request, target, options.threads)? {
        Some(greens) => Ok(greens),
        None => model.greens_functions(request),
    }
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
            Err(e) => Err(PlateError::cache(&path, e)),
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
    fs::create_dir_all(dir).map_err(|e| PlateError::cache(dir, format!("cannot create the cache directory: {e}")))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use super::*;
    use crate::entry::{EntryLayout, GreensEntry, Representation};
    use crate::greens::SpectralPlan;

    /// A fresh scratch directory (under the system's temporary directory, named by tempfile; each test removes
    /// it when it passes).
    fn scratch(name: &str) -> PathBuf {
        tempfile::Builder::new().prefix(&format!("metaplate-plate-cache-{name}-")).tempdir().unwrap().keep()
    }

    #[test]
    fn a_missing_cache_directory_is_created_with_its_parents() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("a").join("b");
        ensure_dir(&dir).unwrap();
        assert!(dir.is_dir());
        // Existing already: still fine.
        ensure_dir(&dir).unwrap();
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

    /// A small request on the built-in homogeneous plate, its entry's path and key in `dir`, and a stand-in entry
    /// that no computation would give (point 612 only, 4 samples of 0.25 per actuator), to tell a loaded entry
    /// from a computed one.
    fn entry(dir: &Path) -> (Scene, ModelOptions, GreensRequest, PathBuf, u64, GreensEntry) {
        let scene = Scene::builtin("homogeneous").unwrap();
        // The coarsest lattice: these tests are about the cache's files and claims, not the physics.
        let options = ModelOptions { refinement: 1, ..ModelOptions::default() };
        let request = GreensRequest {
            points: vec![612],
            actuators: vec![0],
            band_hz: (300.0, 400.0),
            duration_s: 0.05,
            sample_rate_hz: 24_000.0,
        };
        let hash = scene.physics_hash();
        let key = cache_key(hash, &options, &request);
        let mut present = vec![false; scene.grid.len() + scene.actuators.len()];
        present[612] = true;
        let layout = EntryLayout {
            sample_rate_hz: 24_000.0,
            plan: SpectralPlan { fft_len: 8, ir_len: 4, bins: vec![(1, 3000.0, 1.0)] },
            representation: Representation::ImpulseResponse,
            actuator_count: scene.actuators.len(),
            present,
        };
        let stand_in = GreensEntry { data: vec![0.25; layout.block_words()], layout };
        (scene, options, request, cache_path(dir, hash, key), key, stand_in)
    }

    #[test]
    fn writers_filling_one_entry_at_once_leave_a_whole_file() {
        let root = scratch("race");
        let (scene, options, request, path, key, stand_in) = entry(&root);
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| {
                    for _ in 0..5 {
                        entry_file::write(&path, key, &stand_in).unwrap();
                    }
                });
            }
        });
        let want = stand_in.cut(&request, None, 1).unwrap().unwrap();
        assert_eq!(greens_functions(&scene, &options, &request, Some(&root)).unwrap(), want);
        // Only the entry is left: every temporary name was renamed away.
        assert_eq!(fs::read_dir(&root).unwrap().count(), 1);
        fs::remove_dir_all(&root).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_request_waits_for_a_live_claim_and_loads_what_its_holder_stores() {
        let root = scratch("claim-live");
        let (scene, options, request, path, key, stand_in) = entry(&root);
        let claim = path.with_extension("computing");
        // Held by a live process (this one), as another test's computation would hold it.
        fs::write(&claim, std::process::id().to_string()).unwrap();
        let got = std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(std::time::Duration::from_millis(300));
                entry_file::write(&path, key, &stand_in).unwrap();
                fs::remove_file(&claim).unwrap();
            });
            greens_functions(&scene, &options, &request, Some(&root)).unwrap()
        });
        assert_eq!(
            got,
            stand_in.cut(&request, None, 1).unwrap().unwrap(),
            "loaded the holder's entry, not computed its own"
        );
        fs::remove_dir_all(&root).unwrap();
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_claim_left_by_a_dead_process_is_taken_over_and_removed() {
        let root = scratch("claim-stale");
        let (scene, options, request, path, _, _) = entry(&root);
        let claim = path.with_extension("computing");
        // A process id above the kernel's maximum (2^22) never runs.
        fs::write(&claim, "4194305").unwrap();
        let got = greens_functions(&scene, &options, &request, Some(&root)).unwrap();
        assert_eq!((got.points.clone(), got.actuators.clone(), got.ir_len), (vec![612], vec![0], 1200));
        assert!(got.data.iter().any(|v| *v != 0.0), "computed");
        // The entry is stored and the claim gone.
        assert!(path.is_file() && !claim.exists());
        fs::remove_dir_all(&root).unwrap();
    }
}

//! Shared fixtures of the recipe tests: a mock lab of a scene with a scan plan, outputs, the error of a measured
//! response against the lab's ground truth, and datasets reduced to what "equal" means for a resume.
#![allow(dead_code, clippy::unwrap_used)] // Each test file uses a subset; tests may unwrap.

use std::collections::BTreeMap;
use std::path::Path;

use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_dsp::kirkeby::KirkebyFilter;
use metaplate_lab::{LabOptions, MockLab};
use metaplate_recipes::scan::{ScanConfig, ScanPoints, ScanSummary, scan};
use metaplate_recipes::{Event, Observer, Output, RecipeError, RunControl};
use metaplate_store::Dataset;

/// Compared band, Hz: the suite's one Green's-function error band.
pub use metaplate_dsp::accuracy::ERROR_BAND_HZ as BAND_HZ;

/// The built-in metamaterial scene (its random dropouts are keyed by the measurement, so runs reproduce) with its own
/// seed, as the end-to-end tests' scans (`tests/`) and the ground truth: the seed draws the rods' heights, so one
/// seed is one Green's-function cache entry for every test of this plate.
pub fn metamaterial() -> Scene {
    Scene::builtin("metamaterial").unwrap()
}

/// The `nx` x `ny` plan of `scene` and a lab preparing its points and the actuators' driving points (for
/// calibration on the magnets), Green's functions cached under the target directory (shared by test runs and
/// files: the plate model's cost is per scene, so the tests share the 7 x 5 plan's lab and scan prefixes of it).
pub fn lab_and_plan(scene: &Scene, nx: usize, ny: usize) -> (MockLab, ScanPoints) {
    let plan = ScanPoints::new(scene.grid, &scene.grid_mask(), Some((nx, ny))).unwrap();
    (MockLab::new(scene, &lab_options(scene, &plan)).unwrap(), plan)
}

/// The options of [`lab_and_plan`]'s lab: `plan`'s points and the driving points, the shared cache.
pub fn lab_options(scene: &Scene, plan: &ScanPoints) -> LabOptions {
    let grid_len = scene.grid.len();
    let mut points = plan.points.clone();
    points.extend((0..scene.actuators.len()).map(|k| grid_len + k));
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("greens-cache");
    std::fs::create_dir_all(&cache).unwrap();
    LabOptions { points: Some(points), cache_dir: Some(cache), ..LabOptions::default() }
}

/// The output of a run of `scene` into `dir`.
pub fn output(dir: &Path, scene: &Scene, resume: bool) -> Output {
    Output {
        dir: dir.to_path_buf(),
        scene: scene.id(),
        software_version: "test".into(),
        resume,
        force: false,
        preflight: None,
    }
}

/// The first `n` points of `plan` (in its order).
pub fn prefix(plan: &ScanPoints, n: usize) -> ScanPoints {
    ScanPoints { grid: plan.grid, points: plan.points[..n].to_vec() }
}

/// The first `n` points of the built-in scene's 7 x 5 plan.
pub fn small_plan(n: usize) -> ScanPoints {
    let scene = metamaterial();
    prefix(&ScanPoints::new(scene.grid, &scene.grid_mask(), Some((7, 5))).unwrap(), n)
}

/// One scan run of `plan` on a fresh lab of the built-in scene (a restarted program: new devices, a clock from
/// 0), uncalibrated, with [`quick_config`].
pub fn run_scan(
    plan: &ScanPoints,
    out: &Output,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<ScanSummary, RecipeError> {
    run_scan_with(plan, &quick_config(), out, control, observer)
}

/// As [`run_scan`] with `cfg`.
pub fn run_scan_with(
    plan: &ScanPoints,
    cfg: &ScanConfig,
    out: &Output,
    control: &RunControl,
    observer: &mut dyn Observer,
) -> Result<ScanSummary, RecipeError> {
    let (lab, _) = lab_and_plan(&metamaterial(), 7, 5);
    let mut rig = lab.rig().unwrap();
    scan(&mut rig, plan, None, cfg, out, control, observer)
}

/// The quick protocol with seed 7.
pub fn quick_config() -> ScanConfig {
    ScanConfig { protocol: ExcitationProtocol::quick(), seed: 7, ..ScanConfig::default() }
}

/// Relative error energy of a measured response against the truth over [`BAND_HZ`], dB.
pub fn error_db(lab: &MockLab, point: usize, actuator: usize, ir: &[f32], fs: f64) -> f64 {
    error_db_compensated(lab, point, actuator, ir, fs, None)
}

/// As [`error_db`] for a scan through `filter` (see [`MockLab::response_error_db`]).
pub fn error_db_compensated(
    lab: &MockLab,
    point: usize,
    actuator: usize,
    ir: &[f32],
    fs: f64,
    filter: Option<&KirkebyFilter>,
) -> f64 {
    // A scan's responses start `PRE_SAMPLES` before time 0.
    let ir: Vec<f64> = ir.iter().map(|v| f64::from(*v)).collect();
    let ir = metaplate_lab::time_zero_first(&ir, metaplate_dsp::excitation::PRE_SAMPLES);
    lab.response_error_db(point, actuator, &ir, fs, BAND_HZ, filter).unwrap()
}

/// Median and worst of `errors_db` (sorted in place).
pub fn median_and_worst(errors_db: &mut [f64]) -> (f64, f64) {
    errors_db.sort_by(f64::total_cmp);
    (errors_db[errors_db.len() / 2], errors_db[errors_db.len() - 1])
}

/// One row as a resume must reproduce it: the response, the status, the SNR, the retries and where the beam was.
/// (`measured_at` is wall time and differs by nature.)
#[derive(Debug, Clone, PartialEq)]
pub struct RowImage {
    pub ir: Vec<f32>,
    pub status: Option<&'static str>,
    pub snr_db: Option<f64>,
    pub retries: Option<u32>,
    pub position_bits: (u64, u64),
}

/// Every row of the dataset in `dir`, by (point, actuator); the reader refuses duplicates itself.
pub fn image(dir: &Path) -> BTreeMap<(u32, u16), RowImage> {
    let dataset = Dataset::open(dir).unwrap();
    dataset
        .rows()
        .iter()
        .enumerate()
        .map(|(row, m)| {
            let image = RowImage {
                ir: dataset.row_ir(row).unwrap().to_vec(),
                status: m.status.map(|s| s.as_str()),
                snr_db: m.snr_db,
                retries: m.retries,
                position_bits: (m.x_m.to_bits(), m.y_m.to_bits()),
            };
            (m.key(), image)
        })
        .collect()
}

/// Asserts that `a` and `b` hold the same keys and, row for row, bit-identical responses and SNRs and the same
/// status, retries and beam position, naming the first difference (with the responses' relative difference in dB,
/// to tell a rounding slip, some -110 dB, from a point measured again with other noise, -90 dB or more). The mock
/// lab keys its noise by measurement and renders a playback independently of the session's history, so a resumed
/// run must equal an uninterrupted one exactly.
pub fn assert_same_rows(a: &BTreeMap<(u32, u16), RowImage>, b: &BTreeMap<(u32, u16), RowImage>, what: &str) {
    let keys_a: Vec<_> = a.keys().collect();
    let keys_b: Vec<_> = b.keys().collect();
    assert_eq!(keys_a, keys_b, "{what}: the same (point, actuator) keys");
    for (key, row) in a {
        let other = &b[key];
        assert_eq!(
            (row.status, row.retries, row.position_bits),
            (other.status, other.retries, other.position_bits),
            "{what}: row {key:?}: status, retries, position"
        );
        assert_eq!(row.snr_db.map(f64::to_bits), other.snr_db.map(f64::to_bits), "{what}: row {key:?}: SNR");
        assert_eq!(row.ir.len(), other.ir.len(), "{what}: row {key:?}: IR length");
        if row.ir.iter().zip(&other.ir).any(|(x, y)| x.to_bits() != y.to_bits()) {
            let (err, energy) = row.ir.iter().zip(&other.ir).fold((0.0, 0.0), |(e, n), (x, y)| {
                (e + (f64::from(*x) - f64::from(*y)).powi(2), n + f64::from(*x).powi(2))
            });
            panic!("{what}: row {key:?}: responses differ by {:.1} dB", 10.0 * (err / energy).log10());
        }
    }
    eprintln!("{what}: {} rows, bit-identical", a.len());
}

/// An observer that keeps every event.
#[derive(Debug, Default)]
pub struct Recorder(pub Vec<Event>);

impl metaplate_recipes::Observer for Recorder {
    fn event(&mut self, event: &Event) {
        self.0.push(event.clone());
    }
}

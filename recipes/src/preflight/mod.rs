//! The pre-flight check (`metaplate check`): in a few minutes of the rig's time, before a night's scan, whether the
//! rig can run it, and if not, what is wrong and how to fix it. It writes nothing; the caller keeps its report.
//!
//! The checks, in order (a check whose instruments failed is reported as not run, and fails):
//! 1. `wiring`: the wiring is consistent (channels distinct, rates positive).
//! 2. `vibrometer`: the LDV answers its identity and takes the scan's velocity range.
//! 3. `daq`: the DAQ takes the velocity and loopback inputs at the wiring's rate and range (its handshake was made
//!    when it was opened).
//! 4. `audio`: the audio interface opens at exactly the wiring's rate and channel count.
//! 5. `loopback`: four repetitions of a quiet sweep (-20 dBFS, 100 Hz to 4 kHz, 0.25 s) on the loopback channel
//!    reach the DAQ's loopback input, at the level the wiring's `loopback_volts_per_full_scale` predicts (within
//!    [`LOOPBACK_LEVEL_TOLERANCE_DB`]); the latency from the DAQ's start to the sound is measured. A loopback that
//!    arrives on the velocity input instead is named as swapped inputs, a silent one as missing.
//! 6. `clocks`: the audio-to-DAQ drift fitted to the four repetitions, against the scan's limit.
//! 7. `actuator_wiring`: with the beam on each actuator's magnet in turn, a quiet chirp (-26 dBFS, 62 to 625 Hz,
//!    0.3 s) on every actuator channel, one after another, gives the response from each channel to each magnet.
//!    Loudness cannot tell which channel drives the magnet under the beam: on a small, lightly damped plate the
//!    reverberant field at a magnet is as strong as the direct one (within 1 to 3 dB on the built-in plates).
//!    Reciprocity can: a passive plate's response from actuator `a` to magnet `b` equals the one from `b` to `a`,
//!    up to the two coils' gains. As wired, the pair (`a` to `b`, `b` to `a`) must agree within
//!    `RECIPROCITY_LIMIT_DB` (-15 dB) after the best gain; when it does not and (`a` to `a`, `b` to `b`) does, the
//!    cables of `a` and `b` are swapped, and the check names both channels. A magnet that does not move is named.
//! 8. `ldv_signal`: at a few grid points, the returned signal level (against the scan's aiming minimum) and each
//!    actuator's chirp at the scan's drive level: the velocity against the range (a response lost in the range's
//!    resolution fails; clipping is noted, since the scan widens its range where a response clips) and the
//!    chirp's signal-to-noise ratio.
//! 9. `disk` and `duration` (when the caller plans a run): the free space against the run's estimated size, and
//!    the estimated time of the run.
//!
//! Valid range: a rig whose wiring names one channel per actuator ([`PreflightConfig::actuator_sites_m`] has one
//! site per wired actuator) and DAQ and audio rates within a factor 2 of each other (as every recipe needs).

mod bench;
mod chirps;
mod keypad;
mod reciprocity;
mod signals;

use std::fmt::Write as _;

use metaplate_core::rig::Rig;
use metaplate_dsp::excitation::ExcitationProtocol;
use serde_json::{Value, json};

use crate::engine::aim::AimPolicy;
use crate::error::RecipeError;
pub use keypad::keypad_check;

/// The loopback's level may differ from the wiring's prediction by this much, dB, before the check fails: more
/// means a wrong `loopback_volts_per_full_scale` (every response's scale would be off by as much) or a wrong cable.
pub const LOOPBACK_LEVEL_TOLERANCE_DB: f64 = 3.0;

/// Lowest signal-to-noise ratio of a short chirp at the scan's drive level, dB (energy in the chirp's window over
/// the noise before it). The scan's own responses gain 10 to 30 dB more from their longer sweeps and repetitions.
pub const MIN_CHIRP_SNR_DB: f64 = 20.0;

/// A peak velocity above this fraction of the range's full scale is noted: the scan's longer sweeps build
/// resonances higher than a 0.3 s chirp does (and the scan widens its range where a response clips).
pub const MAX_PEAK_FRACTION: f64 = 0.5;

/// A peak velocity below this fraction of the full scale fails: the response would use a handful of the DAQ's codes.
pub const MIN_PEAK_FRACTION: f64 = 1e-3;

/// The checks that use the instruments, in order: not run when the wiring is invalid or an instrument did not open.
const INSTRUMENT_CHECKS: [&str; 7] =
    ["vibrometer", "daq", "audio", "loopback", "clocks", "actuator_wiring", "ldv_signal"];

/// Disk space a run needs beyond its estimated size, as a factor (the journal, the log, a compaction's copy).
pub const DISK_MARGIN: f64 = 1.25;

/// What the check needs to know of the plate and of the planned run.
#[derive(Debug, Clone, PartialEq)]
pub struct PreflightConfig {
    /// Each actuator's magnet, m, in actuator order: where the beam goes for the wiring check.
    pub actuator_sites_m: Vec<(f64, f64)>,
    /// A few grid points, m, for the LDV check (3 to 5 spread over the plate are plenty).
    pub ldv_points_m: Vec<(f64, f64)>,
    /// The velocity range the run asks of the vibrometer, m/s.
    pub max_velocity_m_s: f64,
    /// The largest audio-to-DAQ drift the run accepts, ppm.
    pub max_drift_ppm: f64,
    /// The signal level below which the run nudges the beam, 0 to 1.
    pub min_signal_level: f64,
    /// The planned run, for the disk and duration checks; `None` skips them.
    pub planned: Option<PlannedRun>,
}

impl PreflightConfig {
    /// A configuration with the scan's defaults (0.1 m/s range, 200 ppm, the aiming minimum level).
    pub fn new(actuator_sites_m: Vec<(f64, f64)>, ldv_points_m: Vec<(f64, f64)>) -> Self {
        let scan = crate::ScanConfig::default();
        Self {
            actuator_sites_m,
            ldv_points_m,
            max_velocity_m_s: scan.max_velocity_m_s,
            max_drift_ppm: scan.max_drift_ppm,
            min_signal_level: AimPolicy::default().min_signal_level,
            planned: None,
        }
    }
}

/// The run a check prepares for.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedRun {
    /// Grid points to measure.
    pub points: usize,
    /// The excitation protocol.
    pub protocol: ExcitationProtocol,
    /// Where the dataset goes (for the message).
    pub out_dir: String,
    /// Free space there, bytes (`None` when it cannot be read: the disk check then fails and says so).
    pub free_bytes: Option<u64>,
}

impl PlannedRun {
    /// Estimated size of the dataset, bytes: one row per point and actuator, each the impulse response as 32-bit
    /// floats plus 256 bytes of other columns and Parquet overhead (noisy responses do not compress).
    pub fn estimated_bytes(&self, actuators: usize) -> u64 {
        let row = 4 * self.protocol.deconv.ir_len as u64 + 256;
        (self.points * actuators) as u64 * row
    }

    /// Estimated time of the run, s: the protocol's nominal playing time per point and 0.2 s per point for the beam
    /// to move and settle (retries, re-measures and deferred points add to it).
    pub fn estimated_duration_s(&self, actuators: usize) -> f64 {
        self.points as f64 * (self.protocol.nominal_time_per_point_s(actuators) + 0.2)
    }
}

/// One check's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckOutcome {
    /// Which check (`loopback`, `actuator_wiring`, ...).
    pub name: &'static str,
    /// Whether it passed.
    pub passed: bool,
    /// One or two sentences: what was measured, and when it failed, what is wrong and what to do.
    pub message: String,
    /// The measured values (JSON object).
    pub details: Value,
}

impl CheckOutcome {
    fn pass(name: &'static str, message: String, details: Value) -> Self {
        Self { name, passed: true, message, details }
    }

    fn fail(name: &'static str, message: String, details: Value) -> Self {
        Self { name, passed: false, message, details }
    }

    fn not_run(name: &'static str, needs: &str) -> Self {
        Self::fail(name, format!("not run: it needs {needs} to pass first"), json!({}))
    }

    /// The outcome as `metaplate check` prints it: `  ok   name: message` or `  FAIL name: message`.
    pub fn line(&self) -> String {
        format!("  {} {}: {}", if self.passed { "ok  " } else { "FAIL" }, self.name, self.message)
    }

    /// The outcome as JSON: `{"name", "passed", "message", "details"}`.
    pub fn to_json(&self) -> Value {
        json!({"name": self.name, "passed": self.passed, "message": self.message, "details": self.details})
    }
}

/// Every check's outcome, in order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PreflightReport {
    /// The outcomes.
    pub checks: Vec<CheckOutcome>,
}

impl PreflightReport {
    /// Whether the run can start: every check passed.
    pub fn passed(&self) -> bool {
        !self.checks.is_empty() && self.checks.iter().all(|c| c.passed)
    }

    /// `"pass"` or `"fail"`.
    pub fn verdict(&self) -> &'static str {
        if self.passed() { "pass" } else { "fail" }
    }

    /// The one-line verdict: `pass: 9 of 9 checks passed` or `fail: loopback, clocks (7 of 9 passed)`.
    pub fn verdict_line(&self) -> String {
        let passed = self.checks.iter().filter(|c| c.passed).count();
        if self.passed() {
            format!("pass: {passed} of {} checks passed; the run can start", self.checks.len())
        } else {
            let failed: Vec<&str> = self.checks.iter().filter(|c| !c.passed).map(|c| c.name).collect();
            format!("fail: {} ({passed} of {} passed)", failed.join(", "), self.checks.len())
        }
    }

    /// The report as JSON: `{"verdict", "checks": [...]}`.
    pub fn to_json(&self) -> Value {
        json!({"verdict": self.verdict(), "checks": self.checks.iter().map(CheckOutcome::to_json).collect::<Vec<_>>()})
    }

    /// The report of a rig whose instruments did not all open: each one that failed, as `(section, message)` with
    /// its hardware file's section (`ldv`, `daq`, `audio`, `aim`, `keypad`), fails the check of its name (`ldv`'s is
    /// `vibrometer`; the others' are the section's), and every instrument check of [`preflight`] not already named
    /// is not run. The verdict is `fail`.
    pub fn unopened(failed: &[(&'static str, String)]) -> Self {
        let name_of = |section: &'static str| if section == "ldv" { "vibrometer" } else { section };
        let mut checks: Vec<CheckOutcome> = failed
            .iter()
            .map(|(section, message)| {
                CheckOutcome::fail(name_of(section), message.clone(), json!({"section": section}))
            })
            .collect();
        let needs = "the instruments of the hardware file (every one opened)";
        for name in INSTRUMENT_CHECKS {
            if !checks.iter().any(|c| c.name == name) {
                checks.push(CheckOutcome::not_run(name, needs));
            }
        }
        Self { checks }
    }

    /// The report as `metaplate check` prints and writes it: [`PreflightReport::to_json`] with when it was checked
    /// (`checked_at`, RFC 3339), the plate (`{"name", "hash"}`), the software's version and the rig's identities and
    /// wiring (`rig`, as [`crate::rig_config`] gives it, or `{"error"}` saying why it could not be read; `{"error"}`
    /// too without a rig, when its instruments did not open).
    pub fn document(&self, plate: &metaplate_store::SceneId, software_version: &str, rig: Option<&mut Rig>) -> Value {
        let mut document = self.to_json();
        if let Some(object) = document.as_object_mut() {
            object.insert("checked_at".into(), json!(chrono::Utc::now().to_rfc3339()));
            object.insert("plate".into(), json!({"name": plate.name, "hash": plate.hash}));
            object.insert("software_version".into(), json!(software_version));
            let rig = match rig {
                Some(rig) => crate::rig_config(rig).unwrap_or_else(|e| json!({"error": e.to_string()})),
                None => json!({"error": "the rig's instruments did not all open"}),
            };
            object.insert("rig".into(), rig);
        }
        document
    }
}

/// Writes a pre-flight report's `document` to `path` durably (the store's write: a temporary file, fsync'd,
/// renamed), so that a report that exists is whole.
///
/// # Errors
/// [`RecipeError::Config`] for a path that does not end in a file name of UTF-8 text; [`RecipeError::Store`] when
/// it cannot be written.
pub fn write_report(path: &std::path::Path, document: &Value) -> Result<(), RecipeError> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let name = path.file_name().and_then(|n| n.to_str()).ok_or_else(|| {
        RecipeError::Config(format!("--report {} must end in a file name of UTF-8 text", path.display()))
    })?;
    Ok(metaplate_store::write_bytes(dir, name, format!("{document:#}\n").as_bytes())?)
}

/// Runs every check on `rig`, calling `on_check` with each outcome as it is known (for progress), and returns them
/// all. Device failures are outcomes, not errors: the point is to report them. The devices are left stopped.
///
/// # Errors
/// [`RecipeError::Config`] when `config` does not fit the rig (a site per wired actuator, at least one LDV point,
/// finite positive range and drift limit).
pub fn preflight(
    rig: &mut Rig,
    config: &PreflightConfig,
    on_check: &mut dyn FnMut(&CheckOutcome),
) -> Result<PreflightReport, RecipeError> {
    validate(rig, config)?;
    let mut report = PreflightReport::default();
    let mut record = |outcome: CheckOutcome, report: &mut PreflightReport| {
        on_check(&outcome);
        report.checks.push(outcome);
    };
    let wiring = wiring_check(rig);
    let wiring_ok = wiring.passed;
    record(wiring, &mut report);
    if !wiring_ok {
        for name in INSTRUMENT_CHECKS {
            record(CheckOutcome::not_run(name, "a valid wiring"), &mut report);
        }
    } else {
        let mut bench = bench::Bench::new(rig);
        let vibrometer = bench.vibrometer(config.max_velocity_m_s);
        let daq = bench.daq();
        let audio = bench.audio();
        let (ldv_ok, daq_ok, audio_ok) = (vibrometer.passed, daq.passed, audio.passed);
        record(vibrometer, &mut report);
        record(daq, &mut report);
        record(audio, &mut report);
        let play_ok = daq_ok && audio_ok;
        let mut loopback_ok = false;
        if play_ok {
            let (loopback, clocks) = bench.loopback(config.max_drift_ppm);
            loopback_ok = loopback.passed;
            record(loopback, &mut report);
            record(clocks, &mut report);
        } else {
            record(CheckOutcome::not_run("loopback", "the DAQ and the audio interface"), &mut report);
            record(CheckOutcome::not_run("clocks", "the DAQ and the audio interface"), &mut report);
        }
        if play_ok && ldv_ok && loopback_ok {
            record(bench.actuator_wiring(&config.actuator_sites_m), &mut report);
        } else {
            let needs = "the vibrometer, the DAQ, the audio interface and the loopback";
            record(CheckOutcome::not_run("actuator_wiring", needs), &mut report);
        }
        if play_ok && ldv_ok {
            record(bench.ldv_signal(config), &mut report);
        } else {
            record(CheckOutcome::not_run("ldv_signal", "the vibrometer, the DAQ and the audio interface"), &mut report);
        }
    }
    if let Some(planned) = &config.planned {
        let actuators = rig.wiring.actuator_channels.len();
        record(disk_check(planned, actuators), &mut report);
        record(duration_check(planned, actuators), &mut report);
    }
    Ok(report)
}

fn validate(rig: &Rig, config: &PreflightConfig) -> Result<(), RecipeError> {
    let actuators = rig.wiring.actuator_channels.len();
    if config.actuator_sites_m.len() != actuators {
        return Err(RecipeError::Config(format!(
            "{} actuator sites for the {actuators} actuators the wiring names",
            config.actuator_sites_m.len()
        )));
    }
    if config.ldv_points_m.is_empty() {
        return Err(RecipeError::Config("the LDV check needs at least one grid point".into()));
    }
    let all_finite =
        config.actuator_sites_m.iter().chain(&config.ldv_points_m).all(|(x, y)| x.is_finite() && y.is_finite());
    if !all_finite {
        return Err(RecipeError::Config("a site or point with a non-finite coordinate".into()));
    }
    for (name, value) in [("max_velocity_m_s", config.max_velocity_m_s), ("max_drift_ppm", config.max_drift_ppm)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(RecipeError::Config(format!("{name} = {value} must be finite and > 0")));
        }
    }
    Ok(())
}

fn wiring_check(rig: &Rig) -> CheckOutcome {
    let w = &rig.wiring;
    let details = json!({
        "actuator_channels": w.actuator_channels, "loopback_channel": w.loopback_channel,
        "velocity_input": w.velocity_input, "loopback_input": w.loopback_input,
        "audio_sample_rate_hz": w.audio_sample_rate_hz, "daq_sample_rate_hz": w.daq_sample_rate_hz,
    });
    match w.validate() {
        Ok(()) => CheckOutcome::pass(
            "wiring",
            format!(
                "actuators on audio channels {:?}, loopback channel {} into DAQ input {}, LDV into DAQ input {}",
                w.actuator_channels, w.loopback_channel, w.loopback_input, w.velocity_input
            ),
            details,
        ),
        Err(reason) => CheckOutcome::fail("wiring", format!("{reason}: correct the hardware file's [wiring]"), details),
    }
}

fn disk_check(planned: &PlannedRun, actuators: usize) -> CheckOutcome {
    let need = planned.estimated_bytes(actuators);
    let with_margin = (need as f64 * DISK_MARGIN).ceil() as u64;
    let details = json!({"free_bytes": planned.free_bytes, "need_bytes": need, "need_with_margin_bytes": with_margin});
    match planned.free_bytes {
        None => CheckOutcome::fail(
            "disk",
            format!("cannot read the free space at {}: is the directory's disk mounted?", planned.out_dir),
            details,
        ),
        Some(free) if free >= with_margin => CheckOutcome::pass(
            "disk",
            format!(
                "{} free at {}; the run needs about {} ({} x {DISK_MARGIN} margin)",
                bytes_text(free),
                planned.out_dir,
                bytes_text(with_margin),
                bytes_text(need)
            ),
            details,
        ),
        Some(free) => CheckOutcome::fail(
            "disk",
            format!(
                "only {} free at {}, the run needs about {} ({} x {DISK_MARGIN} margin): free {} or write elsewhere \
                 (--out)",
                bytes_text(free),
                planned.out_dir,
                bytes_text(with_margin),
                bytes_text(need),
                bytes_text(with_margin - free)
            ),
            details,
        ),
    }
}

fn duration_check(planned: &PlannedRun, actuators: usize) -> CheckOutcome {
    let duration_s = planned.estimated_duration_s(actuators);
    let mut message = String::new();
    let _ = write!(
        message,
        "about {:.1} h for {} points with the `{}` protocol ({:.1} s per point; retries and deferred points add to it)",
        duration_s / 3600.0,
        planned.points,
        planned.protocol.name,
        duration_s / planned.points.max(1) as f64
    );
    CheckOutcome::pass("duration", message, json!({"estimated_s": duration_s, "points": planned.points}))
}

/// Bytes as a person reads them: `512 B`, `3.2 MB`, `41.0 GB` (decimal units, as disks are sold).
fn bytes_text(bytes: u64) -> String {
    let b = bytes as f64;
    match b {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.1} MB", b / 1e6),
        b if b >= 1e3 => format!("{:.1} kB", b / 1e3),
        _ => format!("{bytes} B"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(free_bytes: Option<u64>) -> PlannedRun {
        PlannedRun { points: 1225, protocol: ExcitationProtocol::paper(), out_dir: "/data/scan".into(), free_bytes }
    }

    #[test]
    fn the_disk_check_compares_free_space_with_the_estimate_and_its_margin() {
        let need = planned(None).estimated_bytes(8);
        assert!(need > 1225 * 8 * 4 * 1000, "{need}");
        assert!(!disk_check(&planned(None), 8).passed);
        let short = disk_check(&planned(Some(need)), 8);
        assert!(
            !short.passed && short.message.contains("only") && short.message.contains("--out"),
            "{}",
            short.message
        );
        assert!(disk_check(&planned(Some(need * 2)), 8).passed);
    }

    #[test]
    fn the_duration_is_the_protocols_playing_time_and_the_beams_moves() {
        let run = planned(None);
        let per_point_s = ExcitationProtocol::paper().nominal_time_per_point_s(8) + 0.2;
        assert!((run.estimated_duration_s(8) - 1225.0 * per_point_s).abs() < 1e-6);
        // The paper's overnight scan took about 30 h; its protocol's playing time alone is more than that here
        // (five 3 s sweeps per actuator), so the estimate is not optimistic.
        assert!(run.estimated_duration_s(8) / 3600.0 > 30.0);
        assert!(duration_check(&run, 8).message.contains("1225 points"));
    }

    #[test]
    fn the_verdict_fails_on_any_failed_check_and_names_it() {
        let mut report = PreflightReport::default();
        assert!(!report.passed(), "no check run is no pass");
        report.checks.push(CheckOutcome::pass("wiring", "ok".into(), json!({})));
        assert_eq!(report.verdict(), "pass");
        report.checks.push(CheckOutcome::not_run("loopback", "the DAQ"));
        assert_eq!(report.verdict(), "fail");
        assert_eq!(report.verdict_line(), "fail: loopback (1 of 2 passed)");
        assert_eq!(report.to_json()["checks"][1]["passed"], false);
    }

    #[test]
    fn bytes_read_as_a_person_reads_them() {
        assert_eq!(bytes_text(512), "512 B");
        assert_eq!(bytes_text(3_200_000), "3.2 MB");
        assert_eq!(bytes_text(41_000_000_000), "41.0 GB");
    }
}

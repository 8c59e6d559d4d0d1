//! `metaplate check`: the pre-flight of a rig before a calibration or a scan ([`metaplate_recipes::preflight`] runs
//! the checks). It prints each check as it completes and a one-line verdict, writes nothing but its report
//! (`--report FILE`), and exits 0 only when the run can start.
//!
//! On the mock lab (`--scene`), the scene's `[setup]` table injects the mistakes the checks must catch, and its
//! `disk_free_bytes` stands for the lab computer's free space; `--ldv-pty` serves the mock LDV on a pseudo-terminal
//! and drives it through the real serial transport, as a hardware file's `serial` backend does.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::rig::Rig;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_keypad::{HidInput, Keypad};
use metaplate_lab::{LabOptions, LdvLink};
use metaplate_recipes::preflight::{CheckOutcome, PlannedRun, PreflightConfig, preflight};
use metaplate_recipes::{ScanPlan, rig_config};
use serde_json::{Value, json};

use crate::rig::{self, Plate};
use crate::run::{EXIT_FLAGGED, Source};
use crate::scan::plan;

/// Arguments of `metaplate check`.
#[derive(Args, Debug)]
#[command(after_help = "Exit codes: 0 every check passed (the run can start); 3 a check failed (the verdict and \
each failed check say what to fix); 1 the check itself could not run (the message says why); 2 bad arguments.")]
pub struct CheckArgs {
    #[command(flatten)]
    pub source: Source,
    /// Where the run will write: the free space of its disk is checked against the run's estimated size (the
    /// directory need not exist yet).
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// The run's grid subset NXxNY (as `scan --grid`); default: every measurable point.
    #[arg(long)]
    pub grid: Option<GridSubset>,
    /// The run's excitation protocol (as `scan --protocol`), for the disk and duration estimates.
    #[arg(long, default_value = "paper")]
    pub protocol: String,
    /// Write the report (the verdict, every check with its figures, the rig's identities and wiring, when) as JSON
    /// to this file; give it to `calibrate` and `scan` as `--preflight FILE` to record the verdict in the dataset.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON on stdout (`{"verdict", "checks": [{"name", "passed", "message", "details"}]}`)
    /// instead of the lines.
    #[arg(long)]
    pub json: bool,
    /// Seed of the mock lab (default: the scene's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// With --hardware and a keypad in the file: wait this long for a key press on it (0: only check it opened).
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub keypad_wait_s: f64,
    /// With --scene: serve the mock LDV on a pseudo-terminal and drive it through the real serial transport.
    #[arg(long, requires = "scene")]
    pub ldv_pty: bool,
    #[command(flatten)]
    pub cache: crate::cache::CacheArgs,
}

/// Grid points the LDV check visits: this many, spread along the plan.
const LDV_POINTS: usize = 3;

/// Runs `metaplate check`.
pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    let protocol = ExcitationProtocol::by_name(&args.protocol)?;
    if !(args.keypad_wait_s.is_finite() && args.keypad_wait_s >= 0.0) {
        anyhow::bail!("--keypad-wait-s {} must be finite and >= 0", args.keypad_wait_s);
    }
    let mut keypad = None;
    let (plate, mut rig, _lab, plan, disk_budget) = match (&args.source.scene, &args.source.hardware) {
        (_, Some(file)) => {
            let (plate, opened) = rig::hardware_rig_and_keypad(file)?;
            keypad = opened.keypad;
            let plan = plan(&plate, args.grid)?;
            (plate, opened.rig, None, plan, None)
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            let plan = plan(&plate, args.grid)?;
            // A small plan is prepared whole (shared with a scan of it); a large one: the LDV points only.
            let points = plate.small_plan_points(&plan).unwrap_or_else(|| {
                let mut points = ldv_points(&plan);
                points.extend(plate.driving_points());
                points
            });
            let ldv_link = if args.ldv_pty { LdvLink::Pty } else { LdvLink::InProcess };
            let options = LabOptions {
                seed: args.seed,
                cache_dir: args.cache.dir(),
                points: Some(points),
                ldv_link,
                ..LabOptions::default()
            };
            let (lab, rig) = rig::mock_rig_with(&plate, &options)?;
            let budget = plate.scene.setup.disk_free_bytes;
            (plate, rig, Some(lab), plan, budget)
        }
        (None, None) => anyhow::bail!("give --scene or --hardware"),
    };
    let free_bytes = match (metaplate_store::free_bytes(&args.out), disk_budget) {
        (Some(free), Some(budget)) => Some(free.min(budget)),
        (free, budget) => free.or(budget),
    };
    let mut config = PreflightConfig::new(
        plate.actuator_sites_m(),
        ldv_points(&plan).into_iter().map(|p| plate.scene.grid.position_m(p)).collect(),
    );
    config.planned =
        Some(PlannedRun { points: plan.points.len(), protocol, out_dir: args.out.display().to_string(), free_bytes });
    let json_out = args.json;
    if !json_out {
        eprintln!("pre-flight of {} ({} points planned):", plate.id.name, plan.points.len());
    }
    let mut print = |c: &CheckOutcome| {
        if !json_out {
            eprintln!("  {} {}: {}", if c.passed { "ok  " } else { "FAIL" }, c.name, c.message);
        }
    };
    let mut report = preflight(&mut rig, &config, &mut print)?;
    if let Some(keypad) = keypad.as_mut() {
        if !json_out && args.keypad_wait_s > 0.0 {
            eprintln!("  press a key on the response keypad (waiting {} s)", args.keypad_wait_s);
        }
        let outcome = keypad_check(keypad, args.keypad_wait_s);
        print(&outcome);
        report.checks.push(outcome);
    }
    let mut document = report.to_json();
    if let Some(object) = document.as_object_mut() {
        object.insert("checked_at".into(), json!(chrono::Utc::now().to_rfc3339()));
        object.insert("plate".into(), json!({"name": plate.id.name, "hash": plate.id.hash}));
        object.insert("software_version".into(), json!(env!("CARGO_PKG_VERSION")));
        object.insert("rig".into(), rig_identity(&mut rig));
    }
    if let Some(path) = &args.report {
        write_report(path, &document)?;
    }
    if json_out {
        println!("{document}");
    } else {
        println!("{}", report.verdict_line());
    }
    if !report.passed() {
        std::process::exit(EXIT_FLAGGED);
    }
    Ok(())
}

/// The keypad answers: with `wait_s > 0` a key pressed within that time, otherwise only that it opened.
fn keypad_check(keypad: &mut Keypad<impl HidInput>, wait_s: f64) -> CheckOutcome {
    let (vendor, product, serial) = keypad.transport().describe();
    let who = format!("{vendor} {product} (serial {serial})");
    let details = json!({"vendor": vendor, "product": product, "serial": serial, "waited_s": wait_s});
    if wait_s == 0.0 {
        let message = format!("{who} opened; its keys were not tested (--keypad-wait-s 10 to test them)");
        return CheckOutcome { name: "keypad", passed: true, message, details };
    }
    let (passed, message) = match keypad.next_event(wait_s) {
        Ok(Some(event)) => (true, format!("{who} answers: key 0x{:02x} {:?}", event.key.usage(), event.action)),
        Ok(None) => (false, format!("{who} opened, but no key was pressed within {wait_s} s: is it the right device?")),
        Err(e) => (false, format!("{who}: {e}")),
    };
    CheckOutcome { name: "keypad", passed, message, details }
}

/// The rig as the datasets record it (identities and wiring), or why it could not be read.
fn rig_identity(rig: &mut Rig) -> Value {
    rig_config(rig).unwrap_or_else(|e| json!({"error": e.to_string()}))
}

/// Writes the report durably (a temporary file, fsync'd, renamed): a report that exists is whole.
fn write_report(path: &std::path::Path, document: &Value) -> anyhow::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    let mut file = tempfile::NamedTempFile::new_in(dir)
        .with_context(|| format!("cannot write the report beside {}", path.display()))?;
    writeln!(file, "{document:#}")?;
    file.as_file().sync_all()?;
    file.persist(path).with_context(|| format!("cannot write the report {}", path.display()))?;
    Ok(())
}

/// [`LDV_POINTS`] points spread along the plan (at a quarter, half and three quarters of its path).
fn ldv_points(plan: &ScanPlan) -> Vec<usize> {
    let n = plan.points.len();
    let mut points: Vec<usize> = (1..=LDV_POINTS).map(|k| plan.points[(k * n / (LDV_POINTS + 1)).min(n - 1)]).collect();
    points.dedup();
    points
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // Tests may unwrap: a panic is the failure report.

    use std::sync::Arc;

    use metaplate_core::clock::VirtualClock;
    use metaplate_keypad::{ReportPrefix, ScriptStep, ScriptedHid};

    use super::*;

    /// A keypad that sends `reports` (each after `after_s` of virtual time), then nothing.
    fn pad(reports: Vec<(f64, [u8; 8])>) -> Keypad<ScriptedHid> {
        let clock = Arc::new(VirtualClock::new());
        let script = reports.into_iter().map(|(after_s, bytes)| ScriptStep::boot_report(after_s, bytes)).collect();
        Keypad::new(ScriptedHid::new(&clock, script), clock, ReportPrefix::None)
    }

    #[test]
    fn a_key_pressed_in_time_passes_and_silence_fails_by_name() {
        // Boot keyboard report: modifiers, reserved, six key slots; 0x1e is the key `1`.
        let press = [0, 0, 0x1e, 0, 0, 0, 0, 0];
        let outcome = keypad_check(&mut pad(vec![(2.0, press)]), 10.0);
        assert!(outcome.passed && outcome.message.contains("key 0x1e Down"), "{}", outcome.message);
        let late = keypad_check(&mut pad(vec![(12.0, press)]), 10.0);
        assert!(!late.passed && late.message.contains("no key was pressed within 10 s"), "{}", late.message);
        let unasked = keypad_check(&mut pad(Vec::new()), 0.0);
        assert!(unasked.passed && unasked.message.contains("not tested"), "{}", unasked.message);
    }
}

//! `metaplate check`: the pre-flight of a rig before a calibration or a scan ([`metaplate_recipes::preflight`] runs
//! the checks). It prints each check as it completes and a one-line verdict, writes nothing but its report
//! (`--report FILE`), and exits 0 only when the run can start.
//!
//! On the mock lab (`--scene`), the scene's `[setup]` table injects the mistakes the checks must catch, and its
//! `disk_free_bytes` stands for the lab computer's free space; `--ldv-pty` serves the mock LDV on a pseudo-terminal
//! and drives it through the real serial transport, as a hardware file's `serial` backend does.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::rig::Rig;
use metaplate_drivers::{HardwareError, HardwareFile};
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_lab::{LabOptions, LdvLink};
use metaplate_recipes::ScanPoints;
use metaplate_recipes::preflight::{
    CheckOutcome, PlannedRun, PreflightConfig, PreflightReport, keypad_check, preflight,
};
use metaplate_store::SceneId;

use crate::rig::{self, Opened};
use crate::run::{EXIT_FLAGGED, Source};

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
    let opened = rig::open(&args.source, metaplate_drivers::OpenPurpose::Check, |plate| {
        let plan = ScanPoints::of_scene(&plate.scene, args.grid)?;
        // A small plan is prepared whole (shared with a scan of it); a large one: the LDV points only.
        let points = plan
            .prepared_whole(&plate.scene)
            .unwrap_or_else(|| [plan.spread(LDV_POINTS), plate.scene.driving_points()].concat());
        let ldv_link = if args.ldv_pty { LdvLink::Pty } else { LdvLink::InProcess };
        Ok(LabOptions {
            seed: args.seed,
            cache_dir: args.cache.dir(),
            points: Some(points),
            ldv_link,
            ..Default::default()
        })
    });
    let Opened { plate, mut rig, mut keypad, lab } = match opened {
        Ok(opened) => opened,
        Err(error) => return unopened(args, error),
    };
    let plan = ScanPoints::of_scene(&plate.scene, args.grid)?;
    // The lab's disk stands for the lab computer's free space.
    let disk_budget = lab.as_ref().and(plate.scene.setup.disk_free_bytes);
    let free_bytes = match (metaplate_store::free_bytes(&args.out), disk_budget) {
        (Some(free), Some(budget)) => Some(free.min(budget)),
        (free, budget) => free.or(budget),
    };
    let mut config = PreflightConfig::new(
        plate.scene.actuator_sites_m(),
        plan.spread(LDV_POINTS).into_iter().map(|p| plate.scene.grid.position_m(p)).collect(),
    );
    config.planned =
        Some(PlannedRun { points: plan.points.len(), protocol, out_dir: args.out.display().to_string(), free_bytes });
    let json_out = args.json;
    if !json_out {
        eprintln!("pre-flight of {} ({} points planned):", plate.id.name, plan.points.len());
    }
    let mut print = |c: &CheckOutcome| {
        if !json_out {
            eprintln!("{}", c.line());
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
    finish(args, &plate.id, &report, Some(&mut rig))
}

/// A hardware file whose instruments did not all open: each that failed (a device, or a value of the file that only
/// opening checks) is a failed check of its name, every one at once, and the verdict `fail`. Any other error (the
/// file as read, its plate, a backend this build lacks) is returned.
fn unopened(args: &CheckArgs, error: anyhow::Error) -> anyhow::Result<()> {
    let failed = error.downcast_ref::<HardwareError>().map(HardwareError::failed_instruments).unwrap_or_default();
    let (Some(file), false) = (&args.source.hardware, failed.is_empty()) else { return Err(error) };
    let plate = rig::Plate::resolve(&HardwareFile::load(file)?.plate)?;
    let report = PreflightReport::unopened(&failed);
    for c in report.checks.iter().filter(|_| !args.json) {
        eprintln!("{}", c.line());
    }
    finish(args, &plate.id, &report, None)
}

/// Writes the report (`--report`), prints it (the verdict line, or the JSON document), and exits 3 unless it passed.
fn finish(args: &CheckArgs, plate: &SceneId, report: &PreflightReport, rig: Option<&mut Rig>) -> anyhow::Result<()> {
    let document = report.document(plate, env!("CARGO_PKG_VERSION"), rig);
    if let Some(path) = &args.report {
        metaplate_recipes::preflight::write_report(path, &document)
            .with_context(|| format!("cannot write the report {}", path.display()))?;
    }
    if args.json {
        println!("{document}")
    } else {
        println!("{}", report.verdict_line())
    }
    if !report.passed() {
        std::process::exit(EXIT_FLAGGED);
    }
    Ok(())
}

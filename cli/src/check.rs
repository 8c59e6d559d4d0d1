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
    /// With --scene: serve the mock LDV on a pseudo-terminal and drive it through the real serial transport.
    #[arg(long, requires = "scene")]
    pub ldv_pty: bool,
    #[command(flatten)]
    pub cache: crate::cache::CacheArgs,
}

/// Grid points the LDV check visits: this many, spread along the plan.
const LDV_POINTS: usize = 3;

/// On the mock lab, a plan of at most this many points is prepared whole (64 points of 8 responses of 0.5 s take
/// 100 MB).
const PREPARE_WHOLE_PLAN_POINTS: usize = 64;

/// Runs `metaplate check`.
pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    let protocol = ExcitationProtocol::by_name(&args.protocol)?;
    let (plate, mut rig, _lab, plan, disk_budget) = match (&args.source.scene, &args.source.hardware) {
        (_, Some(file)) => {
            let (plate, rig) = rig::hardware_rig(file)?;
            let plan = plan(&plate, args.grid)?;
            (plate, rig, None, plan, None)
        }
        (Some(scene), None) => {
            let plate = Plate::resolve(scene)?;
            let plan = plan(&plate, args.grid)?;
            // A small plan is prepared whole: the plate model's cost does not depend on the points, and a check,
            // a calibration and a scan of the plan then share one cache entry. A large one: the LDV points only.
            let mut points =
                if plan.points.len() <= PREPARE_WHOLE_PLAN_POINTS { plan.points.clone() } else { ldv_points(&plan) };
            points.extend(plate.driving_points());
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
    let report = preflight(&mut rig, &config, &mut |c: &CheckOutcome| {
        if !json_out {
            eprintln!("  {} {}: {}", if c.passed { "ok  " } else { "FAIL" }, c.name, c.message);
        }
    })?;
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

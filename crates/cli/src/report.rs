//! `metaplate report`: one self-contained HTML file on analysed scan datasets (one plate, or the pair of built-in
//! plates): the paper-against-suite table, the figures, each measurement's summary with status and SNR maps, its
//! error against the simulated truth, and its provenance (`metaplate_evaluation::report`).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;
use metaplate_core::scene::Scene;
use metaplate_evaluation::Progress;
use metaplate_evaluation::report::{ReportRequest, report_on_datasets};
use metaplate_recipes::{Event, Observer};

use crate::cache::CacheArgs;
use crate::progress;

/// Arguments of `metaplate report`.
#[derive(Args)]
pub struct ReportArgs {
    /// Scan dataset directories: one per plate (for both built-in plates, the pair side by side).
    #[arg(required = true)]
    datasets: Vec<PathBuf>,
    /// The HTML file to write (its directory must exist; an earlier file is replaced).
    #[arg(long, default_value = "report.html")]
    out: PathBuf,
    /// Calibration directories the scans were compensated with, any order (each is matched to its scans by content
    /// hash); needed to compare a calibrated scan with the ground truth.
    #[arg(long)]
    calibration: Vec<PathBuf>,
    /// Scene files of scans on scenes that are not built in (matched by hash), for the ground truth.
    #[arg(long)]
    scene: Vec<PathBuf>,
    /// Skip the comparison with the simulated plate's ground truth (its Green's functions take minutes to compute
    /// when they are not cached).
    #[arg(long)]
    no_truth: bool,
    #[command(flatten)]
    cache: CacheArgs,
}

/// Runs `metaplate report`.
pub fn run(args: &ReportArgs) -> anyhow::Result<()> {
    let scenes: Vec<Scene> = args
        .scene
        .iter()
        .map(|p| Scene::load(p).with_context(|| format!("reading scene {}", p.display())))
        .collect::<anyhow::Result<_>>()?;
    let cache_dir = args.cache.dir();
    let request = ReportRequest {
        datasets: &args.datasets,
        calibrations: &args.calibration,
        scenes: &scenes,
        no_truth: args.no_truth,
        cache_dir: cache_dir.as_deref(),
        out: &args.out,
    };
    report_on_datasets(&request, &mut Spinner(None))?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// A spinner on stderr per step.
struct Spinner(Option<ProgressBar>);

impl Observer for Spinner {
    fn event(&mut self, _event: &Event) {}
}

impl Progress for Spinner {
    fn begin(&mut self, label: &str) {
        self.0 = Some(progress::spinner(label.to_owned()));
    }

    fn end(&mut self) {
        if let Some(spinner) = self.0.take() {
            spinner.finish_and_clear();
        }
    }
}

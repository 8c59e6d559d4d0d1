//! `metaplate budget`: the Green's-function error budget of a scene on the mock lab, per imperfection
//! (`metaplate_evaluation::budget`).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_dsp::excitation::ExcitationProtocol;
use metaplate_evaluation::budget::{BudgetRequest, measure_budget};

use crate::cache::CacheArgs;

#[derive(Args)]
pub struct BudgetArgs {
    /// Built-in scene name or scene file.
    #[arg(long)]
    scene: String,
    /// The scan's excitation protocol.
    #[arg(long, default_value = "paper", long_help = metaplate_dsp::excitation::help_text())]
    protocol: String,
    /// Grid subset NXxNY (evenly spread points of the scene's grid; masked points are skipped).
    #[arg(long, default_value = "5x3")]
    grid: String,
    /// Scan through this calibration's inverse filters (a `calibrate --scene` directory of the same scene), and
    /// compare with the truth through them.
    #[arg(long, conflicts_with = "uncalibrated")]
    calibration: Option<PathBuf>,
    /// Scan with raw drives (the default).
    #[arg(long)]
    uncalibrated: bool,
    /// Measure only these parts (comma-separated: `floor`, an imperfection's name such as `ldv-noise`, `all-on`);
    /// the additivity check needs the floor and all-on.
    #[arg(long)]
    only: Option<String>,
    /// Seed of the lab and the scan.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Replace the protocol's samples before time 0 of each response (the band limit's precursor; the response's
    /// length stays the same): 0 gives the one-sided responses of earlier versions (a -38 dB floor). For
    /// measuring the processing's own biases.
    #[arg(long)]
    pre_samples: Option<usize>,
    /// Replace the protocol's response length, samples (pre-samples included). For measuring the processing's own
    /// biases.
    #[arg(long)]
    ir_len: Option<usize>,
    /// Replace the protocol's deconvolution regularisation (relative to the excitation's peak power): 1e-3 was
    /// the linear sweeps' before (a -57 dB floor). For measuring the processing's own biases.
    #[arg(long)]
    regularisation: Option<f64>,
    #[command(flatten)]
    cache: CacheArgs,
    /// Print one JSON object on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
}

pub fn run(args: &BudgetArgs) -> anyhow::Result<()> {
    let scene = Scene::resolve(&args.scene).with_context(|| format!("loading scene {}", args.scene))?;
    let mut protocol = ExcitationProtocol::by_name(&args.protocol)?;
    let deconv = &mut protocol.deconv;
    deconv.pre_samples = args.pre_samples.unwrap_or(deconv.pre_samples);
    deconv.ir_len = args.ir_len.unwrap_or(deconv.ir_len);
    deconv.regularisation = args.regularisation.unwrap_or(deconv.regularisation);
    let only: Option<Vec<String>> = args.only.as_ref().map(|o| o.split(',').map(|w| w.trim().to_owned()).collect());
    let cache_dir = args.cache.dir();
    let request = BudgetRequest {
        scene: &scene,
        protocol,
        grid: args.grid.parse::<GridSubset>()?,
        calibration: args.calibration.as_deref(),
        only: only.as_deref(),
        seed: args.seed,
        cache_dir: cache_dir.as_deref(),
    };
    let report = measure_budget(&request, &mut |part| eprintln!("{part}"))?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table_text());
    }
    Ok(())
}

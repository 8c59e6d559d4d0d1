//! `metaplate tradeoff`: the speed/accuracy trade of the scan's excitation protocols, measured on the mock lab
//! (`metaplate_evaluation::tradeoff`, whose documentation says what is measured and why the SNR gate is off).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_core::grid::GridSubset;
use metaplate_core::scene::Scene;
use metaplate_evaluation::tradeoff::{
    DEFAULT_PROTOCOLS, TradeoffRequest, measure_tradeoff, parse_seeds, write_tradeoff_figure,
};

use crate::cache::CacheArgs;

#[derive(Args)]
pub struct TradeoffArgs {
    /// Built-in scene name or scene file.
    #[arg(long)]
    scene: String,
    /// Grid subset NXxNY (evenly spread points of the scene's grid; masked points are skipped).
    #[arg(long, default_value = "5x3")]
    grid: String,
    /// Comma-separated excitation protocols (D sweep seconds >= 0.6, R periods per shot (>= 2 for adaptive), SNR
    /// dB).
    #[arg(long, default_value = DEFAULT_PROTOCOLS, long_help = metaplate_dsp::excitation::help_text())]
    protocols: String,
    /// Seed of the lab and the scan (one seed; see --seeds).
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Several seeds, comma-separated (e.g. `7,8,9,10,11`): every protocol is scanned once per seed, and each
    /// figure is the mean over the seeds with a Student-t 95 % interval (`*_ci95` keys; per seed under
    /// `per_seed`). Replaces --seed.
    #[arg(long, conflicts_with = "seed")]
    seeds: Option<String>,
    /// A family of protocols of one scheme in order of increasing excitation time, typically doubling, e.g.
    /// `hadamard:0.6x2,0.6x4,0.6x8,0.6x16` (a member without a scheme takes the previous one's); may be repeated.
    /// Measured as --protocols are; reported: the error's slope per doubling of excitation time step by step, its
    /// noise-limited run (the leading steps within 1 dB of -3 dB per doubling), the slope fitted over that run, and
    /// the step where the error departs from it (JSON `series`, one object per --series).
    #[arg(long)]
    series: Vec<String>,
    /// Turn on the scan's SNR gate at this many dB (the scan's default is 20): rows whose SNR estimate is below it
    /// are re-measured, at most twice. Off by default: the estimates differ by scheme, so on a noisy plate the gate
    /// re-measures some protocols and not others (see `metaplate_evaluation::tradeoff`'s docs and the README).
    #[arg(long)]
    min_snr_db: Option<f64>,
    #[command(flatten)]
    cache: CacheArgs,
    /// Print one JSON object on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
    /// Write the time-against-error Pareto plot (PNG and SVG, the seeds' means) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
}

pub fn run(args: &TradeoffArgs) -> anyhow::Result<()> {
    let scene = Scene::resolve(&args.scene).with_context(|| format!("loading scene {}", args.scene))?;
    let seeds = match &args.seeds {
        Some(list) => parse_seeds(list)?,
        None => vec![args.seed],
    };
    let cache_dir = args.cache.dir();
    let request = TradeoffRequest {
        scene: &scene,
        grid: args.grid.parse::<GridSubset>()?,
        protocols: &args.protocols,
        seeds: &seeds,
        series: &args.series,
        min_snr_db: args.min_snr_db,
        cache_dir: cache_dir.as_deref(),
    };
    let report = measure_tradeoff(&request, &mut |scan| eprintln!("{scan}"))?;
    if let Some(dir) = &args.figures {
        write_tradeoff_figure(dir, &report)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.text());
    }
    Ok(())
}

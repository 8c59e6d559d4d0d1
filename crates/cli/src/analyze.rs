//! `metaplate analyze`: the paper's Wave Field Analysis on a dataset (wavelength, pixel area, POD, authority,
//! refresh, driven response), as one JSON object or a short table, and optionally its figures
//! (`metaplate_analysis::dataset_report`).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use metaplate_analysis::dataset_figures::write_dataset_figures;
use metaplate_analysis::dataset_report::analyse_dataset;

/// Arguments of `metaplate analyze`.
#[derive(Args)]
pub struct AnalyzeArgs {
    /// Dataset directory (a scan or `metaplate simulate greens`).
    #[arg(long)]
    data: PathBuf,
    /// Print one JSON object on stdout instead of a table.
    #[arg(long)]
    json: bool,
    /// Write the figures (PNG and SVG) into this directory.
    #[arg(long)]
    figures: Option<PathBuf>,
    /// Analyse only the points whose every row's estimated error (the dataset's `estimated_error_db`, from the
    /// spread of repetitions) is at most this, dB; the others are left out as if unmeasured (rows without an
    /// estimate are kept). Default: every point.
    #[arg(long, allow_hyphen_values = true)]
    max_error_db: Option<f64>,
}

/// Runs `metaplate analyze`.
pub fn run(args: &AnalyzeArgs) -> anyhow::Result<()> {
    let (mut analysis, parts) = analyse_dataset(&args.data, args.max_error_db)?;
    if let Some(dir) = &args.figures {
        let written = write_dataset_figures(dir, &analysis.scene.clone(), &analysis, &parts)
            .with_context(|| format!("writing the figures in {}", dir.display()))?;
        analysis.figures = Some(written.iter().map(|p| p.display().to_string()).collect());
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&analysis)?);
    } else {
        print!("{}", analysis.table_text());
    }
    Ok(())
}

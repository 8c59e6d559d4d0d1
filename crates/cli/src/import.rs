//! `metaplate import`: a metaplate dataset from universal files (datasets 164, 2411, 58 and 58b), streamed
//! ([`metaplate_interchange::import`] says how the grid, keys, sample rate and units are found).

use std::path::PathBuf;

use clap::Args;
use metaplate_interchange::{ImportOptions, import, skipped_summary};

use crate::progress;

/// Arguments of `metaplate import`.
#[derive(Args)]
pub struct ImportArgs {
    /// Universal files to read (58/58b responses, 2411 nodes, 164 units), in order.
    #[arg(long, num_args = 1.., required = true)]
    uff: Vec<PathBuf>,
    /// Dataset directory to create (must not exist or be empty).
    #[arg(long)]
    out: PathBuf,
    /// Take the grid from the nodes' positions even when the files carry metaplate's grid.
    #[arg(long)]
    grid_from_nodes: bool,
    /// Node positions as CSV (header `node,x_m,y_m` and optionally `z_m`; metres), for files without dataset 2411
    /// (used in its place when given).
    #[arg(long, value_name = "FILE")]
    nodes: Option<PathBuf>,
    /// Import responses whose ordinate is no motion (pressure, force, voltage, unknown) as they are, their unit
    /// declared unknown (by default they are refused by name).
    #[arg(long)]
    accept_unknown_quantity: bool,
    /// Of frequency responses by several estimators for one pair (ID line 2 naming them, as Polytec PSV exports
    /// H1 and H2), the one to import: H1, H2, H3, Hv or FRF. Default: the first of these the files hold.
    #[arg(long, value_name = "NAME")]
    estimator: Option<String>,
}

/// Runs `metaplate import`.
pub fn run(args: &ImportArgs) -> anyhow::Result<()> {
    let bar = progress::bar(0, "importing");
    let options = ImportOptions {
        grid_from_nodes: args.grid_from_nodes,
        accept_unknown_quantity: args.accept_unknown_quantity,
        nodes: args.nodes.clone(),
        estimator: args.estimator.clone(),
    };
    let summary = import(&args.uff, &args.out, options, |p| {
        bar.set_length(p.total);
        bar.set_position(p.done);
    })?;
    bar.finish_and_clear();
    eprintln!(
        "imported {} responses ({} from frequency responses) into {}: {} (from {}), {} Hz, {} samples, in {}",
        summary.rows,
        summary.from_frf,
        args.out.display(),
        summary.placement(),
        summary.grid_from,
        summary.sample_rate_hz,
        summary.ir_len,
        summary.ir_unit,
    );
    eprintln!("ordinate: {}", summary.conversion);
    if let Some(estimator) = summary.estimator {
        eprintln!("estimator: {estimator} (of several per pair; the others skipped)");
    }
    if let Some(hash) = &summary.calibration {
        eprintln!("measured through the calibration {hash} (from the export's header; `play` checks it)");
    }
    if let Some(direction) = summary.response_direction {
        eprintln!("response direction: ±{direction} (along the points' plane normal; the others skipped)");
    }
    for a in &summary.actuators {
        eprintln!("actuator {}: reference node {} direction {}", a.actuator, a.reference_node, a.direction);
    }
    if !summary.skipped.is_empty() {
        eprintln!("skipped {} records: {}", summary.skipped.len(), skipped_summary(&summary.skipped));
    }
    Ok(())
}
